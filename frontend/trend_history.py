"""The live history of the Trends screen, one per browser: the charted variables' values as
the resource feed delivers them (10 a second), for the last 11 minutes, in ring buffers of
numpy arrays. Its memory is fixed (8 bytes a sample: 53 KB per variable, 16 variables under
1 MB), and taking a sample costs one array write per variable, so it collects whether
the Trends tab is in view or not."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

RATE_HZ = 10  # the resource feed's watch period is 100 ms
HISTORY_S = 660  # at least 10 minutes at 10 Hz, with a margin for a faster feed
CAPACITY = HISTORY_S * RATE_HZ

Floats = npt.NDArray[np.float64]


@dataclass
class TrendHistory:
    """Samples in time order, the oldest overwritten once `capacity` are held. A variable
    added later has no values before it was added: NaN there, which the chart leaves
    empty."""

    capacity: int = CAPACITY
    times: Floats = field(init=False)  # Unix seconds
    columns: dict[str, Floats] = field(default_factory=dict)
    next: int = 0  # where the next sample goes
    count: int = 0  # samples held

    def __post_init__(self) -> None:
        self.times = np.full(self.capacity, np.nan)

    def follow(self, paths: Iterable[str]) -> None:
        """Collect these variables from now on; forget the others."""
        wanted = list(dict.fromkeys(paths))
        for gone in set(self.columns) - set(wanted):
            del self.columns[gone]
        for path in wanted:
            if path not in self.columns:
                self.columns[path] = np.full(self.capacity, np.nan)

    def add(self, time_s: float, values: Mapping[str, float]) -> None:
        index = self.next
        self.times[index] = time_s
        for path, column in self.columns.items():
            column[index] = values.get(path, np.nan)
        self.next = (index + 1) % self.capacity
        self.count = min(self.count + 1, self.capacity)

    def clear(self) -> None:
        self.times.fill(np.nan)
        for column in self.columns.values():
            column.fill(np.nan)
        self.next = self.count = 0

    def span_s(self) -> float:
        """How far back the history reaches now."""
        if self.count == 0:
            return 0.0
        newest = self.times[(self.next - 1) % self.capacity]
        oldest = self.times[(self.next - self.count) % self.capacity]
        return float(newest - oldest)

    def since(self, start_s: float) -> tuple[Floats, dict[str, Floats]]:
        """The samples taken at or after `start_s`, oldest first: their times and each
        variable's values (copies)."""
        if self.count < self.capacity:
            order = np.arange(self.count)
        else:
            order = np.r_[self.next : self.capacity, 0 : self.next]
        times = self.times[order]
        first = int(np.searchsorted(times, start_s))
        kept = order[first:]
        return self.times[kept], {path: column[kept] for path, column in self.columns.items()}
