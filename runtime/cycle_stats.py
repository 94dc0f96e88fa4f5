"""CPU cycle statistics: always available, reset on command."""

from __future__ import annotations

from dataclasses import dataclass

from runtime.contract.protocol import CycleStatistics

# a period is an overrun when it is longer than the target by a quarter of it, at least 1 ms
MIN_TOLERANCE_NS = 1_000_000


@dataclass(slots=True)  # slots: the CPU cycle in C writes them (padt_cycle.c)
class CycleStats:
    count: int = 0
    last_ns: int = 0  # duration of the last CPU cycle (inputs to outputs)
    min_ns: int = 0
    max_ns: int = 0
    total_ns: int = 0
    mean_ns: int = 0  # kept with the total: read by every cycle (CYCLE_TIME_MEAN)
    overruns: int = 0  # periods longer than the target cycle time and its tolerance
    jitter_max_ns: int = 0  # largest deviation of a period from the target cycle time
    last_period_ns: int = 0  # start to start
    watch_deferred: int = 0  # watch sets that waited a cycle for the communication slice

    def record(self, duration_ns: int) -> None:
        # every CPU cycle: comparisons, not min() and max() calls (a fifth of its cost)
        self.count += 1
        self.last_ns = duration_ns
        if duration_ns < self.min_ns or self.count == 1:
            self.min_ns = duration_ns
        if duration_ns > self.max_ns:
            self.max_ns = duration_ns
        self.total_ns += duration_ns
        self.mean_ns = self.total_ns // self.count

    def record_period(self, period_ns: int, target_ns: int) -> None:
        """The time from one cycle's start to the next's. Its deviation from the target is
        the jitter; a period longer than the target and its tolerance is an overrun,
        whatever made it long (the programs, communication, the operating system)."""
        self.last_period_ns = period_ns
        if target_ns:
            self.jitter_max_ns = max(self.jitter_max_ns, abs(period_ns - target_ns))
            if period_ns > target_ns + max(MIN_TOLERANCE_NS, target_ns // 4):
                self.overruns += 1

    def info(self) -> CycleStatistics:
        return CycleStatistics(
            count=self.count,
            last_ms=self.last_ns / 1e6,
            min_ms=self.min_ns / 1e6,
            max_ms=self.max_ns / 1e6,
            mean_ms=self.mean_ns / 1e6,
            period_ms=self.last_period_ns / 1e6,
            jitter_max_ms=self.jitter_max_ns / 1e6,
            overruns=self.overruns,
            watch_deferred=self.watch_deferred,
        )
