"""rusty's INF_REAL, NAN_REAL, INF_LREAL, NAN_LREAL (W0808): IEEE infinity and NaN as
constants where no declaration takes the name (IEC wins), read-only, traced through
`padt sim` (whose JSON lines write them as the strings "Infinity" and "NaN")."""

from __future__ import annotations

from pathlib import Path

from tests.compiler.test_checks import diagnostics
from tests.conftest import sim_trace


def test_they_are_ieee_values_of_their_type(tmp_path: Path) -> None:
    source = """
PROGRAM Main
VAR r : REAL; l : LREAL; nan_seen, above, as_bool : BOOL; i : DINT; END_VAR
r := -INF_REAL;
l := NAN_LREAL;
nan_seen := l <> l;
above := INF_LREAL > 1.0E308;
as_bool := REAL_TO_BOOL(NAN_REAL);
i := i + 1;
END_PROGRAM
"""
    t = sim_trace(tmp_path, source, 2)
    assert t["Main.r"] == ["-Infinity", "-Infinity"]
    assert t["Main.l"] == ["NaN", "NaN"]
    assert t["Main.nan_seen"] == t["Main.above"] == t["Main.as_bool"] == [True, True]


def test_a_declaration_of_the_name_wins_and_the_constants_are_read_only() -> None:
    # IEC wins: a variable called INF_REAL is that variable, without a warning
    assert diagnostics("PROGRAM P\nVAR inf_real : REAL := 1.0; END_VAR\nEND_PROGRAM\n") == []
    found = diagnostics(
        "PROGRAM P\nVAR r : REF_TO REAL; END_VAR\n"
        "NAN_REAL := 1.0;\nr := REF(INF_REAL);\nEND_PROGRAM\n"
    )
    assert found[0] == "t.st:3:1: error: cannot assign to 'NAN_REAL' [E0302]"
    assert found[1] == "t.st:4:6: error: REF of 'INF_REAL', which is no variable [E0219]"
