"""The CODESYS/TwinCAT extensions padt accepts, each with a warning that names the dialect
(docs/language.md, "CODESYS and TwinCAT extensions"): behaviour traced cycle by cycle
through `padt sim`, the diagnostics through the compiler."""

from __future__ import annotations

from pathlib import Path

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from tests.conftest import padt, sim_trace


def diagnostics(source: str) -> list[str]:
    return [str(d) for d in compile_sources([SourceFile("t.st", source)]).diagnostics]


def codes(source: str) -> list[str]:
    return [d.code for d in compile_sources([SourceFile("t.st", source)]).diagnostics]


def test_set_and_reset_assignments_latch_until_the_other_condition(tmp_path: Path) -> None:
    source = """PROGRAM Main
VAR start, stop, motor : BOOL; END_VAR
motor S= start;
motor R= stop;
END_PROGRAM
"""
    trace = sim_trace(
        tmp_path,
        source,
        6,
        "Main.start=TRUE@2",
        "Main.start=FALSE@3",
        "Main.stop=TRUE@5",
        "Main.stop=FALSE@6",
    )
    assert trace["Main.motor"] == [False, True, True, True, False, False]
    assert [c for c in codes(source) if c == "W0803"] == ["W0803", "W0803"]


def test_s_and_r_stay_names_where_no_assignment_can_stand() -> None:
    # IEC wins: a variable called S compared with 1, and `S := ...`, are not the extension
    source = """PROGRAM Main
VAR S, R : INT; b : BOOL; END_VAR
S := 1;
R := S;
IF S=1 THEN b := R=1; END_IF;
END_PROGRAM
"""
    result = compile_sources([SourceFile("t.st", source)])
    assert result.ok and not result.diagnostics, [str(d) for d in result.diagnostics]


def test_set_assignment_needs_a_bool_condition_and_target() -> None:
    source = "PROGRAM Main\nVAR n : INT; c : INT; END_VAR\nn S= c;\nEND_PROGRAM\n"
    found = codes(source)
    assert "E0307" in found  # the condition is no BOOL
    assert "E0209" in found  # TRUE stored in an INT


def test_qualified_enum_values_read_as_typed_literals(tmp_path: Path) -> None:
    source = """TYPE Mode : (Idle, Run := 5, Fault); END_TYPE
PROGRAM Main
VAR state : Mode := Mode.Idle; step : INT; code : INT; END_VAR
step := step + 1;
IF step = 2 THEN state := Mode.Run; ELSIF step = 3 THEN state := Mode.Fault; END_IF;
CASE state OF
  Mode.Idle: code := 0;
  Mode.Run: code := 50;
  Mode.Fault: code := 99;
END_CASE;
END_PROGRAM
"""
    trace = sim_trace(tmp_path, source, 4)
    assert trace["Main.state"] == [0, 5, 6, 6]
    assert trace["Main.code"] == [0, 50, 99, 99]
    found = diagnostics(source)
    assert (
        "t.st:3:21: warning: 'Mode.Idle' is CODESYS/TwinCAT; IEC 61131-3 writes 'Mode#Idle' [W0801]"
    ) in found
    assert sum("W0801" in d for d in found) == 6


def test_a_variable_named_like_the_enum_type_keeps_its_members() -> None:
    # IEC wins: `Mode.Run` is the member Run of the structure variable Mode
    source = """TYPE Mode : (Idle, Run); END_TYPE
TYPE Flags : STRUCT Run : BOOL; END_STRUCT END_TYPE
PROGRAM Main
VAR Mode : Flags; b : BOOL; END_VAR
b := Mode.Run;
END_PROGRAM
"""
    result = compile_sources([SourceFile("t.st", source)])
    assert result.ok and not result.diagnostics, [str(d) for d in result.diagnostics]


def test_sizeof_counts_bytes_as_codesys_does(tmp_path: Path) -> None:
    source = """TYPE Pair : STRUCT flag : BOOL; count : DINT; tag : BYTE; END_STRUCT END_TYPE
TYPE Level : (Low, High); END_TYPE
PROGRAM Main
VAR
  pair : Pair; table : ARRAY[1..3] OF INT; text : STRING[10]; wide : WSTRING[4];
  level : Level; t : TIME; lt : LTIME; r : LREAL; pairs : ARRAY[0..1] OF Pair;
  sizes : ARRAY[1..9] OF UDINT;
END_VAR
sizes[1] := SIZEOF(pair);
sizes[2] := SIZEOF(table);
sizes[3] := SIZEOF(text);
sizes[4] := SIZEOF(wide);
sizes[5] := SIZEOF(level);
sizes[6] := SIZEOF(t);
sizes[7] := SIZEOF(lt);
sizes[8] := SIZEOF(r);
sizes[9] := SIZEOF(pairs);
END_PROGRAM
"""
    trace = sim_trace(tmp_path, source, 2)
    assert trace["Main.sizes"] == [[12, 6, 11, 10, 2, 4, 8, 8, 24]] * 2
    assert codes(source).count("W0802") == 9


def test_sizeof_of_an_instance_or_of_two_arguments_is_refused() -> None:
    source = """PROGRAM Main
VAR t : TON; n : UDINT; a, b : INT; END_VAR
n := SIZEOF(t);
n := SIZEOF(a, b);
END_PROGRAM
"""
    found = diagnostics(source)
    assert any(":3:6: error: SIZEOF of a TON (a function block instance)" in d for d in found)
    assert "t.st:4:6: error: SIZEOF takes one variable or expression, unnamed [E0801]" in found


def test_a_user_function_called_sizeof_replaces_the_extension() -> None:
    source = """FUNCTION SIZEOF : INT
VAR_INPUT x : INT; END_VAR
SIZEOF := 7;
END_FUNCTION
PROGRAM Main
VAR n : INT; END_VAR
n := SIZEOF(n);
END_PROGRAM
"""
    assert "W0802" not in codes(source)


def test_a_trailing_comma_in_a_call_is_ignored_with_a_warning(tmp_path: Path) -> None:
    source = """FUNCTION Scale : INT
VAR_INPUT x, factor : INT; END_VAR
Scale := x * factor;
END_FUNCTION
PROGRAM Main
VAR n : INT; t : TON; END_VAR
n := Scale(n + 1, 2,);
t(IN := TRUE, PT := T#200ms,);
END_PROGRAM
"""
    trace = sim_trace(tmp_path, source, 4)
    assert trace["Main.n"] == [2, 6, 14, 30]
    assert trace["Main.t.Q"] == [False, False, True, True]
    found = diagnostics(source)
    assert (
        "t.st:7:20: warning: a comma after the last argument is CODESYS/TwinCAT, "
        "not IEC 61131-3 [W0804]"
    ) in found
    assert sum("W0804" in d for d in found) == 2


def test_pragmas_are_ignored_with_a_note_and_change_nothing(tmp_path: Path) -> None:
    source = """{attribute 'qualified_only'}
TYPE Mode : (Idle, Run); END_TYPE
PROGRAM Main
VAR
  {attribute 'hide'}
  n : INT;
END_VAR
{warning 'to do'}
n := n + 1;
END_PROGRAM
"""
    trace = sim_trace(tmp_path, source, 3)
    assert trace["Main.n"] == [1, 2, 3]
    run = padt("compile", str(tmp_path / "sim.st"))
    assert run.returncode == 0
    assert (
        "sim.st:5:3: note: pragma 'attribute' ignored: CODESYS/TwinCAT, not IEC 61131-3 [N0801]"
    ) in run.stdout
    assert "sim.st:8:1: note: pragma 'warning' ignored" in run.stdout
