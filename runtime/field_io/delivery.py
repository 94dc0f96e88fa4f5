"""What a client driver hands the cycle from a remote device: its input values, as one
immutable snapshot.

The driver builds a new `Delivery` on the I/O thread and publishes it with one reference
assignment; the cycle thread reads the reference and takes the values when `seq` moved on.
Neither side waits for the other or holds a lock.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Delivery:
    """What the device last delivered for its input points; `good` False: safe values."""

    seq: int
    values: dict[str, Any]
    good: bool
