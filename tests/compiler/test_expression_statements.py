"""An expression as a statement (`+x;`): not IEC 61131-3, accepted as CODESYS accepts it
with a warning (W0807) that says what the line likely meant. Traced through `padt sim`
(100 ms cycles): the value is dropped, a function called in it still runs."""

from __future__ import annotations

from pathlib import Path

from tests.compiler.test_checks import diagnostics
from tests.conftest import sim_trace

DIALECT = "(an expression as a statement is CODESYS/TwinCAT, not IEC 61131-3) [W0807]"


def test_the_typo_x_equals_5_is_named_as_the_assignment_it_likely_meant() -> None:
    found = diagnostics(
        """
PROGRAM Main
VAR x : INT; s : STRUCT a : INT; END_STRUCT; arr : ARRAY[1..2] OF INT; END_VAR
x = 5;
s.a = x + 1;
arr[1] = 3;
x + 1 = 2;
END_PROGRAM
"""
    )
    assert found == [
        f"t.st:4:1: warning: 'x = ...' compares and drops the result: "
        f"did you mean 'x := ...'? {DIALECT}",
        f"t.st:5:1: warning: 's.a = ...' compares and drops the result: "
        f"did you mean 's.a := ...'? {DIALECT}",
        f"t.st:6:1: warning: 'arr[...] = ...' compares and drops the result: "
        f"did you mean 'arr[...] := ...'? {DIALECT}",
        f"t.st:7:1: warning: the value of this expression is dropped: it does nothing {DIALECT}",
    ]


def test_an_instance_named_alone_is_named_as_the_call_it_likely_meant() -> None:
    found = diagnostics("PROGRAM Main\nVAR t : TON; x : INT; END_VAR\nt;\n+x;\n(x);\nEND_PROGRAM\n")
    assert found == [
        f"t.st:3:1: warning: 't' alone does nothing: did you mean to call it, 't();'? {DIALECT}",
        f"t.st:4:1: warning: the value of this expression is dropped: it does nothing {DIALECT}",
        f"t.st:5:2: warning: the value of this expression is dropped: it does nothing {DIALECT}",
    ]


def test_expression_statements_are_checked_like_any_expression() -> None:
    found = diagnostics("PROGRAM Main\nVAR x : INT; END_VAR\nx = nothing;\nEND_PROGRAM\n")
    assert "t.st:3:5: error: 'nothing' is not declared [E0201]" in found


def test_calls_as_statements_get_no_warning() -> None:
    source = """
FUNCTION Bump : INT
VAR_IN_OUT n : INT; END_VAR
n := n + 1;
Bump := n;
END_FUNCTION
PROGRAM Main
VAR t : TON; n : INT; END_VAR
t(IN := TRUE, PT := T#1s);
Bump(n);
END_PROGRAM
"""
    assert diagnostics(source) == []


def test_the_value_is_dropped_and_a_call_inside_still_runs(tmp_path: Path) -> None:
    source = """
FUNCTION Bump : INT
VAR_IN_OUT n : INT; END_VAR
n := n + 1;
Bump := n;
END_FUNCTION
PROGRAM Main
VAR x : INT := 7; calls : INT; END_VAR
+x;
x = 5;
-Bump(calls);
Bump(calls) = 100;
END_PROGRAM
"""
    t = sim_trace(tmp_path, source, 3)
    assert t["Main.x"] == [7, 7, 7]
    assert t["Main.calls"] == [2, 4, 6]


def test_a_statement_that_is_no_expression_still_asks_for_the_assignment() -> None:
    # an expression may stand there now, and its operators must not hide `:=` from the hint
    found = diagnostics("PROGRAM Main\nVAR x : INT; END_VAR\nx 5;\nEND_PROGRAM\n")
    assert found == [
        "t.st:3:3: error: syntax error: unexpected '5'; expected ';', ':=', add op, and, '?=', "
        "'^', '.', '=' [E0001]"
    ]
