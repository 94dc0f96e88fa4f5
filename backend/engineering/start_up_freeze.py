"""What a long-running PADT process (the API, the UI, the demo) made while it started is
taken out of the cycle collector's sight once it serves.

A client of a large watch set makes 10,000 small objects for every message (one per
value); they live long enough to be promoted, which sends a full collection through
every object of the process about once a second. With all the modules, the compiled
project and Zenoh's objects in it, each took 11-24 ms (measured in the watch benchmark's
client), and a message arriving meanwhile waited for it. After the freeze a full
collection walks only what came since."""

from __future__ import annotations

import gc


def freeze_start_up() -> None:
    """Collect what start-up left over, then freeze the rest (`gc.freeze`)."""
    gc.collect()
    gc.freeze()
