"""Every compile-time check reports its problem as `file:line:col: severity: message`, all
problems of a run together, and never a traceback."""

from __future__ import annotations

import pytest

from backend.compiler import ast
from backend.compiler.checks.expressions import check_expression
from backend.compiler.infer import Scope
from backend.compiler.pipeline import compile_sources, parse_all
from backend.compiler.resolve import resolve
from backend.compiler.source import SourceFile
from runtime.contract.artifact import ProgramConfig


def diagnostics(text: str, programs: list[ProgramConfig] | None = None) -> list[str]:
    result = compile_sources([SourceFile("t.st", text)], programs=programs)
    return [str(d) for d in result.diagnostics]


CASES = [
    (
        "undeclared name",
        "PROGRAM P\nVAR x : INT; END_VAR\nx := y + 1;\nEND_PROGRAM",
        "t.st:3:6: error: 'y' is not declared [E0201]",
    ),
    (
        "type mismatch",
        "PROGRAM P\nVAR x : INT; s : STRING; END_VAR\nx := s;\nEND_PROGRAM",
        "t.st:3:6: error: type mismatch: cannot assign STRING to INT [E0209]",
    ),
    (
        "assignment to a constant",
        "PROGRAM P\nVAR CONSTANT c : INT := 1; END_VAR\nc := 2;\nEND_PROGRAM",
        "t.st:3:1: error: cannot assign to constant 'c' [E0301]",
    ),
    (
        "assignment to an input inside its block is a warning",
        "FUNCTION_BLOCK F\nVAR_INPUT i : INT; END_VAR\ni := 2;\nEND_FUNCTION_BLOCK",
        "t.st:3:1: warning: assignment to input 'i' inside its block [W0301]",
    ),
    (
        "writing an FB output from outside",
        "PROGRAM P\nVAR t : TON; END_VAR\nt.Q := TRUE;\nEND_PROGRAM",
        "t.st:3:1: error: 'Q' of 'TON' cannot be written from outside [E0305]",
    ),
    (
        "unknown call argument",
        "FUNCTION F : INT\nVAR_INPUT a : INT; END_VAR\nF := a;\nEND_FUNCTION\n"
        "PROGRAM P\nVAR x : INT; END_VAR\nx := F(b := 1);\nEND_PROGRAM",
        "t.st:7:8: error: 'F' has no parameter 'b' [E0403]",
    ),
    (
        "too many arguments",
        "FUNCTION F : INT\nVAR_INPUT a : INT; END_VAR\nF := a;\nEND_FUNCTION\n"
        "PROGRAM P\nVAR x : INT; END_VAR\nx := F(1, 2);\nEND_PROGRAM",
        "t.st:7:6: error: 'F' takes 1 arguments, not 2 [E0404]",
    ),
    (
        "argument of the wrong type",
        "FUNCTION F : INT\nVAR_INPUT a : INT; END_VAR\nF := a;\nEND_FUNCTION\n"
        "PROGRAM P\nVAR x : INT; END_VAR\nx := F(a := 'text');\nEND_PROGRAM",
        "t.st:7:13: error: type mismatch: cannot pass STRING as INT [E0401]",
    ),
    (
        "duplicate CASE label",
        "PROGRAM P\nVAR x : INT; END_VAR\nCASE x OF 1..3: ; 2: ; END_CASE;\nEND_PROGRAM",
        "t.st:3:19: error: CASE label 2 already used at t.st:3:11 [E0311]",
    ),
    (
        "CASE on a REAL",
        "PROGRAM P\nVAR r : REAL; END_VAR\nCASE r OF 1: ; END_CASE;\nEND_PROGRAM",
        "t.st:3:6: error: CASE selector must be an integer or enum, not REAL [E0309]",
    ),
    (
        "constant index out of bounds",
        "PROGRAM P\nVAR a : ARRAY[1..3] OF INT; END_VAR\na[4] := 0;\nEND_PROGRAM",
        "t.st:3:3: error: index 4 is outside the bounds 1..3 [E0215]",
    ),
    (
        "literal out of range",
        "PROGRAM P\nVAR b : SINT; END_VAR\nb := 200;\nEND_PROGRAM",
        "t.st:3:6: error: 200 is out of range for SINT [E0210]",
    ),
    (
        "condition not BOOL",
        "PROGRAM P\nVAR x : INT; END_VAR\nWHILE x DO END_WHILE;\nEND_PROGRAM",
        "t.st:3:7: error: condition must be BOOL, not INT [E0307]",
    ),
    (
        "EXIT outside a loop",
        "PROGRAM P\nEXIT;\nEND_PROGRAM",
        "t.st:2:1: error: EXIT outside of a loop [E0308]",
    ),
    (
        "step flags are read-only",
        "PROGRAM P\nINITIAL_STEP S0: END_STEP\nSTEP S1: END_STEP\n"
        "TRANSITION FROM S0 TO S1 := TRUE; END_TRANSITION\nACTION A: S1.X := TRUE; END_ACTION\n"
        "END_PROGRAM",
        "t.st:5:11: error: step flag 'S1.X' is read-only [E0504]",
    ),
    (
        "SFC without an initial step",
        "PROGRAM P\nSTEP S0: END_STEP\nSTEP S1: END_STEP\n"
        "TRANSITION FROM S0 TO S1 := TRUE; END_TRANSITION\nEND_PROGRAM",
        "t.st:2:6: error: the step chain S0, S1 needs exactly one INITIAL_STEP, not 0 [E0501]",
    ),
    (
        "timed qualifier without a time",
        "PROGRAM P\nVAR b : BOOL; END_VAR\nINITIAL_STEP S0: b(L); END_STEP\nEND_PROGRAM",
        "t.st:3:18: error: qualifier L needs a time: (L, T#1s) [E0507]",
    ),
    (
        "unknown type",
        "PROGRAM P\nVAR x : MOTOR; END_VAR\nEND_PROGRAM",
        "t.st:2:9: error: unknown type 'MOTOR' [E0107]",
    ),
    (
        "duplicate declaration",
        "PROGRAM P\nVAR x : INT; x : BOOL; END_VAR\nEND_PROGRAM",
        "t.st:2:14: error: 'x' is already declared at t.st:2:5 [E0104]",
    ),
    (
        "bad string escape",
        "PROGRAM P\nVAR s : STRING := 'a$Qb'; END_VAR\nEND_PROGRAM",
        "t.st:2:19: error: invalid escape '$Q' in string literal [E0002]",
    ),
    (
        "an initial value reads a constant set after it",
        "VAR_GLOBAL CONSTANT c : INT := c + 1; END_VAR\nPROGRAM P\nEND_PROGRAM",
        "t.st:1:34: error: initial value of 'c' must be a constant expression [E0117]",
    ),
    (
        "blocks of C code are skipped with a warning",
        "PROGRAM P\n{{ int x; }}\nEND_PROGRAM",
        "t.st:2:1: warning: pragma skipped [W0001]",
    ),
    (
        "CODESYS pragmas are ignored with a note",
        "PROGRAM P\n{attribute 'x'}\nEND_PROGRAM",
        "t.st:2:1: note: pragma 'attribute' ignored: CODESYS/TwinCAT, not IEC 61131-3 [N0801]",
    ),
]


@pytest.mark.parametrize(("title", "source", "expected"), CASES, ids=[c[0] for c in CASES])
def test_check_reports_position(title: str, source: str, expected: str) -> None:
    assert expected in diagnostics(source)


def test_all_errors_of_a_run_are_reported() -> None:
    source = "PROGRAM P\nVAR x : INT; END_VAR\nx := a;\nx := b;\nx := 'c';\nEND_PROGRAM"
    errors = [d for d in diagnostics(source) if ": error: " in d]
    assert len(errors) == 3


def test_a_global_has_one_writer() -> None:
    source = (
        "VAR_GLOBAL shared : INT; END_VAR\n"
        "FUNCTION_BLOCK Bump\nVAR_EXTERNAL shared : INT; END_VAR\nshared := shared + 1;\n"
        "END_FUNCTION_BLOCK\n"
        "PROGRAM A\nVAR b : Bump; END_VAR\nb();\nEND_PROGRAM\n"
        "PROGRAM B\nshared := 5;\nEND_PROGRAM\n"
    )
    assert (
        "t.st:4:1: error: global 'shared' is written by the user programs A, B; "
        "global data must have one writer [E0606]"
    ) in diagnostics(source)


def test_a_global_passed_to_an_in_out_is_written() -> None:
    source = (
        "VAR_GLOBAL shared : INT; END_VAR\n"
        "FUNCTION Inc : INT\nVAR_IN_OUT x : INT; END_VAR\nx := x + 1;\nEND_FUNCTION\n"
        "PROGRAM A\nVAR y : INT; END_VAR\ny := Inc(shared);\nEND_PROGRAM\n"
        "PROGRAM B\nVAR y : INT; END_VAR\ny := shared + 1;\nEND_PROGRAM\n"
        "PROGRAM C\nVAR y : INT; END_VAR\ny := Inc(x := shared);\nEND_PROGRAM\n"
    )
    assert diagnostics(source) == [
        "t.st:8:10: error: global 'shared' is written by the user programs A, C; "
        "global data must have one writer [E0606]"
    ]


def test_an_instance_named_like_a_program_does_not_call_it() -> None:
    source = (
        "VAR_GLOBAL shared : INT; END_VAR\n"
        "FUNCTION_BLOCK Tick\nVAR n : INT; END_VAR\nn := n + 1;\nEND_FUNCTION_BLOCK\n"
        "PROGRAM A\nVAR b : Tick; END_VAR\nb();\nEND_PROGRAM\n"
        "PROGRAM B\nshared := shared + 1;\nEND_PROGRAM\n"
    )
    assert diagnostics(source) == []


def test_program_ids_unique_and_at_most_32() -> None:
    source = "PROGRAM P\nEND_PROGRAM\n"
    same_id = [ProgramConfig("a", "P", 1), ProgramConfig("b", "P", 1)]
    assert "padt.toml:1:1: error: program ID 1 of 'b' is used by 'a' [E0603]" in diagnostics(
        source, same_id
    )
    many = [ProgramConfig(f"p{i}", "P", i) for i in range(1, 34)]
    found = diagnostics(source, many)
    assert "padt.toml:1:1: error: 33 user programs; at most 32 [E0604]" in found
    assert "padt.toml:1:1: error: program ID 33 of 'p33' is not in 1..32 [E0602]" in found


def test_typing_reports_nothing_the_expression_rules_do() -> None:
    """`infer.Scope` only computes types; the rules of `checks/` report, once per node."""
    source = "PROGRAM P\nVAR x : INT; END_VAR\nx := y + TRUE;\nEND_PROGRAM"
    units, _ = parse_all([SourceFile("t.st", source)])
    resolved = resolve(units)
    pou = resolved.pous["P"]
    assignment = pou.pou.body[0]
    assert isinstance(assignment, ast.Assign) and isinstance(assignment.value, ast.Binary)
    value = assignment.value
    silent = Scope(resolved, pou)
    assert silent.type_of(value) is None
    assert silent.diagnostics == []
    checked = Scope(resolved, pou, check_expression)
    checked.type_of(value)
    checked.type_of(value)
    assert [str(d) for d in checked.diagnostics] == ["t.st:3:6: error: 'y' is not declared [E0201]"]


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        (
            "CASE x OF 1.5: ; END_CASE;",
            "t.st:4:11: error: CASE label must be an integer or enum, not ANY_REAL [E0310]",
        ),
        ("nothing[1] := 0;", "t.st:4:1: error: 'nothing' is not declared [E0201]"),
        ("p.z[1] := 0;", "t.st:4:1: error: 'Point' has no member 'z' [E0204]"),
    ],
)
def test_a_problem_is_reported_once_where_its_node_is_reached_twice(
    body: str, expected: str
) -> None:
    source = (
        "TYPE Point : STRUCT x : ARRAY[1..2] OF INT; END_STRUCT; END_TYPE\n"
        f"PROGRAM P\nVAR x : INT; p : Point; END_VAR\n{body}\nEND_PROGRAM"
    )
    assert diagnostics(source) == [expected]


def test_bool_and_numbers_do_not_mix() -> None:
    """`b := 42` and `i := TRUE` are mistakes, in statements, initial values and arguments;
    the literals 0 and 1 are BOOL values and a BOOL widens to a bit string."""
    source = (
        "FUNCTION F : INT\nVAR_INPUT a : INT; c : BOOL; END_VAR\nF := a;\nEND_FUNCTION\n"
        "PROGRAM P\n"
        "VAR b : BOOL; i : INT; w : WORD; r : REAL; e : BOOL := 2; ok : BOOL := 1; END_VAR\n"
        "b := 42;\ni := TRUE;\nr := b;\ni := F(a := FALSE, c := 7);\n"
        "b := 0;\nb := 1;\nw := b;\ni := F(a := 3, c := 1);\nb := i > 0;\n"
        "END_PROGRAM"
    )
    assert diagnostics(source) == [
        "t.st:6:56: error: type mismatch: cannot assign ANY_INT to BOOL [E0209]",
        "t.st:7:6: error: type mismatch: cannot assign ANY_INT to BOOL [E0209]",
        "t.st:8:6: error: type mismatch: cannot assign BOOL to INT [E0209]",
        "t.st:9:6: error: type mismatch: cannot assign BOOL to REAL [E0209]",
        "t.st:10:13: error: type mismatch: cannot pass BOOL as INT [E0401]",
        "t.st:10:25: error: type mismatch: cannot pass ANY_INT as BOOL [E0401]",
    ]


def test_subranges_are_checked() -> None:
    """A subrange needs an integer base type and constant bounds of it, the lower first; a
    valid one (also through a constant) compiles without a word."""
    source = (
        "TYPE Bad : INT ('foo' .. 'bar'); Rev : INT (10 .. 1); R : REAL (0 .. 1);\n"
        "Big : SINT (0 .. 1000); Pct : INT (0 .. 100); END_TYPE\n"
        "VAR_GLOBAL CONSTANT top : INT := 7; END_VAR\n"
        "PROGRAM P\nVAR x : INT (-5 .. top); y : UINT (1 .. n); p : Pct; n : INT; END_VAR\n"
        "END_PROGRAM"
    )
    assert diagnostics(source) == [
        "t.st:1:17: error: subrange bounds must be constant integers of INT [E0124]",
        "t.st:1:45: error: subrange 10..1 is empty [E0125]",
        "t.st:1:59: error: a subrange needs an integer base type, not 'REAL' [E0123]",
        "t.st:2:18: error: subrange bound 1000 is outside SINT [E0124]",
        "t.st:5:41: error: subrange bounds must be constant integers of UINT [E0124]",
    ]
