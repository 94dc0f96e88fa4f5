"""CPU cycle statistics: always available, reset on command."""

from __future__ import annotations

from dataclasses import dataclass

from runtime.contract.protocol import CycleStatistics


@dataclass
class CycleStats:
    count: int = 0
    last_ns: int = 0  # duration of the last CPU cycle (inputs to outputs)
    min_ns: int = 0
    max_ns: int = 0
    total_ns: int = 0
    overruns: int = 0  # cycles whose work (inputs to outputs) took longer than the target
    jitter_max_ns: int = 0  # largest deviation of a period from the target cycle time
    last_period_ns: int = 0  # start to start

    def record(self, duration_ns: int, target_ns: int = 0) -> None:
        self.count += 1
        if target_ns and duration_ns > target_ns:
            self.overruns += 1
        self.last_ns = duration_ns
        self.min_ns = duration_ns if self.count == 1 else min(self.min_ns, duration_ns)
        self.max_ns = max(self.max_ns, duration_ns)
        self.total_ns += duration_ns

    def record_period(self, period_ns: int, target_ns: int) -> None:
        """The time from one cycle's start to the next's; its deviation from the target
        is the jitter (a late wake-up of the operating system shows here, not as an
        overrun)."""
        self.last_period_ns = period_ns
        if target_ns:
            self.jitter_max_ns = max(self.jitter_max_ns, abs(period_ns - target_ns))

    @property
    def mean_ns(self) -> int:
        return self.total_ns // self.count if self.count else 0

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
        )
