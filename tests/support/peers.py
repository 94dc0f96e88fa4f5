"""The peers of ../shared/peers (its README): the bench programs compiled by matiec to C and
by ironplc to its VM's bytecode, run for padt's figures and values to be set beside theirs.
No pytest here: `make bench` uses it too."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

PEERS = Path(__file__).resolve().parents[2].parent / "shared" / "peers"
POU = "Bench"  # the one PROGRAM of both programs
# the FOR counter after the loop: 4 in padt and ironplc, 3 in matiec (the peers' README)
MATIEC_DIFFERS = frozenset({"k"})


@dataclass(frozen=True)
class PeerProgram:
    source: str  # the ST file
    matiec: str  # matiec's binary, in bin/
    ironplc: str  # ironplc's bytecode, in bin/

    @property
    def text(self) -> str:
        return (PEERS / self.source).read_text(encoding="utf-8")

    @property
    def _bytecode(self) -> str:
        return str(PEERS / "bin" / self.ironplc)

    def _json(self, binary: str, *arguments: str) -> dict[str, Any]:
        done = subprocess.run(
            [str(PEERS / "bin" / binary), *arguments],
            capture_output=True,
            text=True,
            check=True,
        )
        reply: dict[str, Any] = json.loads(done.stdout)
        return reply

    def matiec_dump(self, cycles: int) -> dict[str, Any]:
        """Every variable of `Bench` after `cycles` cycles of 100 ms on matiec's C."""
        return self._json(self.matiec, "dump", str(cycles))

    def ironplc_dump(self, cycles: int) -> dict[str, Any]:
        """Every variable of `Bench` after `cycles` cycles of 100 ms on ironplc's VM."""
        return self._json("vbench", "dump", self._bytecode, str(cycles))

    def matiec_us(self, cycles: int, warmup: int, batch: int) -> float:
        """The median time of one cycle on matiec's C, in microseconds."""
        reply = self._json(self.matiec, "bench", str(cycles), str(warmup), str(batch))
        return float(reply["median_us"])

    def ironplc_us(self, cycles: int, warmup: int, batch: int) -> float:
        """The median time of one cycle on ironplc's VM, in microseconds."""
        reply = self._json("vbench", "bench", self._bytecode, str(cycles), str(warmup), str(batch))
        return float(reply["batch_median_us"])


BENCH = PeerProgram("bench.st", "bench_full", "bench.iplc")
BENCH_NOTON = PeerProgram("bench_noton.st", "bench_noton", "bench_noton.iplc")
PROGRAMS = (BENCH, BENCH_NOTON)


def differences(
    padt: Mapping[str, object], peer: Mapping[str, object], skip: frozenset[str] = frozenset()
) -> dict[str, tuple[object, object]]:
    """The variables of a peer's dump whose value padt's `values()` does not give (padt's,
    the peer's), but those in `skip`; a function block instance is left out (ironplc dumps
    a number of its own for it, matiec nothing; padt gives its members)."""
    instances = {path.split(".")[1] for path in padt if path.count(".") > 1}
    found = {}
    for name, value in peer.items():
        if name in skip or name in instances:
            continue
        mine = padt.get(f"{POU}.{name}")
        if type(mine) is not type(value) or mine != value:
            found[name] = (mine, value)
    return found
