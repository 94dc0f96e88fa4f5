"""The peers' bench programs (../shared/peers: matiec's C, ironplc's VM) on both of padt's
tiers: after 1, 10, 100 and 1000 cycles of 100 ms every variable padt gives equals the
value matiec and ironplc give (but the FOR counter after matiec's loop, a known difference
of matiec), on the Python tier and on the native tier alike. No timing here: `make bench`
prints the speeds."""

from __future__ import annotations

import pytest

from runtime.code.native.tier import NativeTier
from tests.support.corpus_paths import shared_dir
from tests.support.native_runs import advance, side_by_side
from tests.support.peers import MATIEC_DIFFERS, PEERS, PROGRAMS, PeerProgram, differences

CHECKPOINTS = (1, 10, 100, 1000)


@pytest.mark.parametrize("program", PROGRAMS, ids=lambda program: program.source)
def test_values_equal_matiec_and_ironplc(native_tier: NativeTier, program: PeerProgram) -> None:
    shared_dir(PEERS)
    pair = side_by_side(program.text, native_tier)
    assert "Bench" in pair.report.bodies, pair.report.left  # the native tier runs it as C
    done = 0
    for checkpoint in CHECKPOINTS:
        for _ in range(checkpoint - done):
            advance(pair.python)
            advance(pair.native)
        done = checkpoint
        matiec, ironplc = program.matiec_dump(checkpoint), program.ironplc_dump(checkpoint)
        for tier, resource in (("python", pair.python), ("native", pair.native)):
            values = resource.variables.values()
            assert not differences(values, matiec, MATIEC_DIFFERS), (tier, checkpoint, "matiec")
            assert not differences(values, ironplc), (tier, checkpoint, "ironplc")
