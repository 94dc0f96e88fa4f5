"""Event log benchmark: how long a recorder, the cycle thread among them, waits in a
long-term `record()`: the log's file written at once (what the runtime did before,
baseline of the same run), written behind on the log's own thread (what `padt runtime`
does now), and a log without a file. Each event is recorded cold, a few milliseconds
after the one before, as the cycle thread records them between cycles.

Run with `python -m tests.bench.bench_event_log`. It prints figures and asserts nothing
about time (machines are shared and noisy).
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

from runtime.event_log import EventLog

EVENTS = 200
APART_S = 0.002


def record_us(folder: Path | None, write_behind: bool) -> tuple[float, float]:
    """Median and longest time in `record()` of a reload's event, in microseconds."""
    path = folder / "events.jsonl" if folder is not None else None
    log = EventLog(time.time_ns, long_path=path, write_behind=write_behind)
    times = []
    for n in range(EVENTS):
        started = time.perf_counter_ns()
        log.record(
            "reload",
            f"reload done: BA073FAD -> C4ACB61E, {n} values carried over",
            user="anna",
            long_term=True,
            old_crc="BA073FAD",
            new_crc="C4ACB61E",
            pause_us=180.5,
            carried=n,
        )
        times.append((time.perf_counter_ns() - started) / 1000)
        time.sleep(APART_S)
    log.close()
    return statistics.median(times), max(times)


def main() -> None:
    with tempfile.TemporaryDirectory() as at_once, tempfile.TemporaryDirectory() as behind:
        baseline = record_us(Path(at_once), write_behind=False)
        now = record_us(Path(behind), write_behind=True)
    memory = record_us(None, write_behind=False)
    print(f"event log, a long-term record() ({EVENTS} events, {APART_S * 1e3:.0f} ms apart):")
    print(
        f"  written behind (padt runtime): median {now[0]:,.0f} us, max {now[1]:,.0f} us; "
        f"written at once (before): median {baseline[0]:,.0f} us, max {baseline[1]:,.0f} us: "
        f"{baseline[0] / now[0]:.1f}x less"
    )
    print(f"  no file: median {memory[0]:,.0f} us, max {memory[1]:,.0f} us")


if __name__ == "__main__":
    main()
