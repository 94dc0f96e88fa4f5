"""No user name can clash with the generated code: names IEC 61131-3 forbids (`__init__`,
`x_`) are refused, and so is a name that the code of its POU uses itself (`_ix` in a
function that indexes an array); any other name compiles into code that runs.

Before, a variable or member named `__init__` compiled, passed check-twice and killed the
runtime when it created the instance; a FUNCTION local `_ix` compiled and failed at run
time, hiding the helper of the same name.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from backend.compiler.pipeline import CompileResult, compile_sources
from backend.compiler.source import SourceFile
from runtime.code.code_image import CodeImage
from runtime.code.intrinsics import SystemView, namespace
from tests.conftest import padt

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")

# A function whose code calls on as many helpers of the runtime as ST can reach: array
# indices, integer and real division, MOD, powers, structure initializers, rounding,
# rotations, MUX, string functions and conversions, a function with outputs (temporaries),
# a block with an edge input, a loop, bit access, copies, math, a global and SYS.
KITCHEN_SINK = """
TYPE Pair : STRUCT a : INT; b : INT; END_STRUCT; END_TYPE
VAR_GLOBAL g : INT; END_VAR
FUNCTION_BLOCK Counter
VAR_INPUT up : BOOL R_EDGE; END_VAR
VAR_OUTPUT n : INT; END_VAR
IF up THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK
FUNCTION Helper : INT
VAR_INPUT v : INT; END_VAR
VAR_OUTPUT twice : INT; END_VAR
twice := v * 2;
Helper := v;
END_FUNCTION
FUNCTION Sink : DINT
VAR_INPUT i : INT; END_VAR
VAR
  {names}
  arr, copy : ARRAY[0..3] OF INT; p : Pair; r : REAL; lr : LREAL := 2.0; text : STRING;
  t : TIME := T#1s; w : WORD; c : Counter; d : DINT; o : INT; ws : WSTRING;
END_VAR
arr[i MOD 4] := i;
d := i / 3;
r := REAL#1.5 / INT_TO_REAL(i);
lr := lr ** 2.0 + SQRT(lr) + EXP(lr);
p := (a := 1, b := 2);
d := REAL_TO_DINT(r) + MUX(i MOD 2, 1, 2) + MAX(i, 3) + MIN(i, 3) + ABS(i) + LIMIT(0, i, 9);
w := ROR(ROL(w, 3), 1);
w.3 := TRUE;
text := CONCAT(REAL_TO_STRING(r), TIME_TO_STRING(t));
d := d + STRING_TO_DINT('12') + LEN(LEFT(text, 2)) + LEN(RIGHT(text, 2)) + FIND(text, '1');
text := INSERT(DELETE(REPLACE(MID(text, 2, 1), 'x', 1, 1), 1, 1), 'y', 0);
r := STRING_TO_REAL('1.5');
ws := STRING_TO_WSTRING(text);
text := WSTRING_TO_STRING(ws);
t := t / 2.5;
c(up := i > 0);
d := d + Helper(v := i, twice => o) + o;
FOR d := 1 TO 2 DO arr[0] := 0; END_FOR;
copy := arr;
g := g + 1;
IF SYS.COLDSTART THEN d := 0; END_IF;
Sink := d;
END_FUNCTION
PROGRAM Main
VAR x : DINT; END_VAR
x := Sink(1);
END_PROGRAM
"""


def sink(*names: str) -> CompileResult:
    declared = " ".join(f"{name} : INT;" for name in names)
    return compile_sources([SourceFile("sink.st", KITCHEN_SINK.replace("{names}", declared))])


def runs(result: CompileResult) -> None:
    """The programs load as a resource loads them, and run cycles."""
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    image = CodeImage(result.artifact, SystemView())
    for program in result.artifact.programs:
        instance = image.new_instance(program.pou)
        for _ in range(3):
            instance()


def test_the_kitchen_sink_runs() -> None:
    runs(sink())


def test_every_name_of_the_runtime_is_refused_where_it_clashes_and_runs_elsewhere() -> None:
    """Each name of the generated code's namespace (helpers and built-ins), as a local of a
    function that uses most of them: refused (E0122) or running."""
    names = {*namespace(SystemView()), *namespace(SystemView())["__builtins__"], "_G"}
    names |= {"s", "now", "FN_HELPER", "POU_COUNTER", "STRUCT_PAIR", "GLOBALS"}
    candidates = sorted(
        n for n in names if IDENTIFIER.fullmatch(n) and "__" not in n and n[-1] != "_"
    )
    refused = {d.message.split("'")[1] for d in sink(*candidates).diagnostics if d.code == "E0122"}
    assert {"_ix", "_idiv", "_imod", "_init", "min", "max", "FN_HELPER", "_G", "_SYS"} <= refused
    assert refused <= set(candidates)
    runs(sink(*(n for n in candidates if n not in refused)))


@pytest.mark.parametrize(
    "source",
    [
        "PROGRAM P\nVAR __init__ : INT; END_VAR\n__init__ := 1;\nEND_PROGRAM\n",
        "TYPE S : STRUCT __init__ : INT; END_STRUCT; END_TYPE\n"
        "PROGRAM P\nVAR s : S; END_VAR\ns.__init__ := 1;\nEND_PROGRAM\n",
        "FUNCTION_BLOCK F\nVAR_INPUT __call__ : INT; END_VAR\nEND_FUNCTION_BLOCK\n"
        "PROGRAM P\nVAR f : F; END_VAR\nf(__call__ := 1);\nEND_PROGRAM\n",
        "VAR_GLOBAL __slots__ : INT; END_VAR\nPROGRAM P\n__slots__ := 1;\nEND_PROGRAM\n",
        "PROGRAM P\nVAR_TEMP __t1 : INT; END_VAR\n__t1 := 1;\nEND_PROGRAM\n",
        "PROGRAM P\nVAR class : INT; class_ : INT; END_VAR\nclass := class_;\nEND_PROGRAM\n",
        "TYPE E : (a__b, c); END_TYPE\nPROGRAM P\nEND_PROGRAM\n",
        "PROGRAM P\nVAR b : BOOL; END_VAR\nINITIAL_STEP Start_: END_STEP\nEND_PROGRAM\n",
    ],
)
def test_names_iec_forbids_are_refused(source: str) -> None:
    result = compile_sources([SourceFile("t.st", source)])
    assert result.artifact is None
    assert "E0004" in [d.code for d in result.diagnostics], [str(d) for d in result.diagnostics]


@pytest.mark.parametrize(
    "source",
    [
        # a FUNCTION local named like the helper of array indices, in a function that indexes
        "FUNCTION F : INT\nVAR_INPUT i : INT; END_VAR\nVAR _ix : INT; a : ARRAY[0..3] OF INT;"
        " END_VAR\nF := a[i];\nEND_FUNCTION\nPROGRAM P\nVAR x : INT; END_VAR\nx := F(1);\n"
        "END_PROGRAM\n",
        # the instance of a PROGRAM's code is `s`; the time of a chart `now`
        "PROGRAM P\nVAR_TEMP s : INT; END_VAR\nVAR x : INT; END_VAR\nx := 1;\nEND_PROGRAM\n",
        "PROGRAM P\nVAR_TEMP now : INT; END_VAR\nINITIAL_STEP S0: END_STEP\nEND_PROGRAM\n",
        # parts of a block's class: the memory of an edge input, an action and its control
        "FUNCTION_BLOCK F\nVAR_INPUT x : BOOL R_EDGE; END_VAR\nVAR _edge_x : BOOL; END_VAR\n"
        "END_FUNCTION_BLOCK\nPROGRAM P\nVAR f : F; END_VAR\nf(x := TRUE);\nEND_PROGRAM\n",
        "PROGRAM P\nVAR b : BOOL; _action_FILL : INT; END_VAR\nINITIAL_STEP S0: FILL(N); "
        "END_STEP\nACTION FILL: b := TRUE; END_ACTION\nEND_PROGRAM\n",
        "PROGRAM P\nVAR b : BOOL; _ac_FILL : INT; END_VAR\nINITIAL_STEP S0: FILL(N); "
        "END_STEP\nACTION FILL: b := TRUE; END_ACTION\nEND_PROGRAM\n",
    ],
)
def test_names_the_generated_code_uses_are_refused(source: str) -> None:
    result = compile_sources([SourceFile("t.st", source)])
    assert result.artifact is None
    assert "E0122" in [d.code for d in result.diagnostics], [str(d) for d in result.diagnostics]


@pytest.mark.parametrize(
    "source",
    [
        # the same names where nothing generated uses them: valid programs keep their code
        "FUNCTION F : INT\nVAR_INPUT i : INT; END_VAR\nVAR _ix, min : INT; END_VAR\n"
        "_ix := i; min := _ix; F := min;\nEND_FUNCTION\n"
        "PROGRAM P\nVAR x : INT; _ix : INT; s : INT; END_VAR\nx := F(1) + _ix + s;\nEND_PROGRAM\n",
        "PROGRAM P\nVAR_TEMP now : INT; END_VAR\nVAR x : INT; END_VAR\nnow := 1; x := now;\n"
        "END_PROGRAM\n",
        "FUNCTION_BLOCK F\nVAR_INPUT x : BOOL; END_VAR\nVAR _edge_x : BOOL; END_VAR\n"
        "_edge_x := x;\nEND_FUNCTION_BLOCK\nPROGRAM P\nVAR f : F; END_VAR\nf(x := TRUE);\n"
        "END_PROGRAM\n",
    ],
)
def test_the_same_names_compile_where_nothing_uses_them(source: str) -> None:
    runs(compile_sources([SourceFile("t.st", source)]))


def test_padt_load_refuses_such_names_before_it_reaches_a_resource(tmp_path: Path) -> None:
    """`padt load` compiles twice first: nothing reaches a runtime (none listens here)."""
    project = tmp_path / "clash"
    project.mkdir()
    (project / "main.st").write_text(
        "TYPE S : STRUCT __init__ : INT; END_STRUCT; END_TYPE\n"
        "FUNCTION F : INT\nVAR_INPUT i : INT; END_VAR\nVAR _ix : INT; a : ARRAY[0..3] OF INT;"
        " END_VAR\nF := a[i];\nEND_FUNCTION\n"
        "PROGRAM P\nVAR s : S; x : INT; END_VAR\nx := F(1) + s.__init__;\nEND_PROGRAM\n"
    )
    run = padt("load", str(project), "--resource", "Tank1", "--zenoh", "tcp/127.0.0.1:9")
    assert run.returncode != 0 and "Traceback" not in run.stderr, run.stderr
    assert "[E0004]" in run.stdout + run.stderr, run.stdout + run.stderr
    assert "check-twice: OK" not in run.stdout
