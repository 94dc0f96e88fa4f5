"""References of IEC 61131-3 edition 3 (REF_TO, REF(), `^`, NULL) through the compiler and
`padt sim`: every construct traced cycle by cycle, a dereference of NULL as a program fault
that names file and line, the refusals with their codes. What the runtime does with
references (OLT, writes, forcing, reload, warm start) is in tests/runtime/test_references.py."""

from __future__ import annotations

from pathlib import Path

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from tests.conftest import padt, sim_trace


def diagnostics(source: str) -> list[str]:
    return [str(d) for d in compile_sources([SourceFile("t.st", source)]).diagnostics]


READ_AND_WRITTEN = """VAR_GLOBAL g : INT := 7; END_VAR
PROGRAM Main
VAR_EXTERNAL g : INT; END_VAR
VAR a : INT := 100; arr : ARRAY[1..3] OF INT; k : INT := 2; n, seen : INT; END_VAR
VAR r : REF_TO INT; END_VAR
n := n + 1;
IF n = 2 THEN r := REF(a); ELSIF n = 3 THEN r := REF(arr[k]); ELSIF n = 4 THEN r := REF(g); END_IF;
IF r <> NULL THEN
  seen := r^;
  r^ := r^ + 1;
END_IF;
END_PROGRAM
"""


def test_a_reference_reads_and_writes_what_it_refers_to(tmp_path: Path) -> None:
    trace = sim_trace(tmp_path, READ_AND_WRITTEN, 5)
    assert trace["Main.r"] == ["NULL", "Main.a", "Main.arr[2]", "g", "g"]
    assert trace["Main.seen"] == [0, 100, 0, 7, 8]
    assert trace["Main.a"] == [100, 101, 101, 101, 101]
    assert trace["Main.arr"] == [[0, 0, 0], [0, 0, 0], [0, 1, 0], [0, 1, 0], [0, 1, 0]]
    assert trace["g"] == [7, 7, 7, 8, 9]


PASSED_TO_A_BLOCK = """TYPE Point : STRUCT x, y : INT; END_STRUCT END_TYPE
FUNCTION_BLOCK Bump
VAR_INPUT target : REF_TO INT; point : REF_TO Point; END_VAR
VAR own : INT; mine : REF_TO INT; END_VAR
IF target <> NULL THEN target^ := target^ + 1; END_IF;
IF point <> NULL THEN point^.x := point^.x + 10; END_IF;
mine := REF(own);
mine^ := mine^ + 2;
END_FUNCTION_BLOCK
PROGRAM Main
VAR count : INT; p : Point; bump : Bump; END_VAR
bump(target := REF(count), point := REF(p));
END_PROGRAM
"""


def test_a_reference_passed_to_a_block_changes_the_callers_variable(tmp_path: Path) -> None:
    trace = sim_trace(tmp_path, PASSED_TO_A_BLOCK, 3)
    assert trace["Main.count"] == [1, 2, 3]
    assert trace["Main.p.x"] == [10, 20, 30]
    assert trace["Main.bump.own"] == [2, 4, 6]
    # references read as the path they refer to, also one made inside the block
    assert trace["Main.bump.target"] == ["Main.count"] * 3
    assert trace["Main.bump.point"] == ["Main.p"] * 3
    assert trace["Main.bump.mine"] == ["Main.bump.own"] * 3


BELOW_AN_ASSIGNED_ROOT = """TYPE Point : STRUCT x, y : INT; END_STRUCT END_TYPE
PROGRAM Main
VAR p, q : Point; r : REF_TO INT; n : INT; END_VAR
n := n + 1;
IF n = 1 THEN r := REF(p.y); END_IF;
q.y := 40 + n;
p := q;
n := n + 0;
r^ := r^ + 1000;
END_PROGRAM
"""


def test_a_reference_survives_a_structure_assignment_below_its_root(tmp_path: Path) -> None:
    trace = sim_trace(tmp_path, BELOW_AN_ASSIGNED_ROOT, 3)
    assert trace["Main.r"] == ["Main.p.y"] * 3
    assert trace["Main.p.y"] == [1041, 1042, 1043]


COMPARED = """PROGRAM Main
VAR a, b : INT; r1, r2 : REF_TO INT; same, isnull : BOOL; n : INT; END_VAR
n := n + 1;
isnull := r1 = NULL;
r1 := REF(a);
IF n = 1 THEN r2 := REF(a); ELSE r2 := REF(b); END_IF;
same := r1 = r2;
END_PROGRAM
"""


def test_references_compare_equal_when_they_refer_to_the_same_place(tmp_path: Path) -> None:
    trace = sim_trace(tmp_path, COMPARED, 2)
    assert trace["Main.isnull"] == [True, False]
    assert trace["Main.same"] == [True, False]


NULL_DEREFERENCED = """PROGRAM Main
VAR r : REF_TO INT; n : INT; END_VAR
n := n + 1;
IF n = 3 THEN
  n := r^;
END_IF;
END_PROGRAM
"""


def test_a_dereference_of_null_is_a_program_fault_naming_the_line(tmp_path: Path) -> None:
    path = tmp_path / "null.st"
    path.write_text(NULL_DEREFERENCED)
    run = padt("sim", str(path), "--cycles", "4", "--trace", "Main.n")
    assert run.returncode == 3, run.stderr
    assert f"cycle 3: program Main: dereference of NULL in POU Main ({path}:5)" in run.stderr
    values = [line for line in run.stdout.splitlines() if line]
    assert '"Main.n": 3' in values[-1]  # the program stopped in ERROR at its third cycle


def test_what_references_may_not_do_is_refused_with_its_code() -> None:
    found = diagnostics("""FUNCTION F : INT
VAR x : INT; r : REF_TO INT; END_VAR
r := REF(x);
END_FUNCTION
PROGRAM Main
VAR CONSTANT c : INT := 1; END_VAR
VAR_TEMP t : INT; END_VAR
VAR r : REF_TO INT; d : REF_TO DINT; n : INT; w : WORD; b : BOOL; END_VAR
r := REF(t);
r := REF(c);
r := REF(w.3);
n := n^;
d := REF(n);
b := r = d;
b := r < NULL;
r := 5;
END_PROGRAM
""")
    assert found == [
        "t.st:3:6: error: REF of 'x', a variable of a function (it is gone when the call ends)"
        " [E0219]",
        "t.st:9:6: error: REF of 't', a VAR_TEMP (it is gone when the call ends) [E0219]",
        "t.st:10:6: error: REF of constant 'c' [E0219]",
        "t.st:11:6: error: REF of a single bit [E0219]",
        "t.st:11:6: error: type mismatch: cannot assign REF_TO BOOL to REF_TO INT [E0209]",
        "t.st:12:6: error: '^' needs a reference, not a value of type INT [E0218]",
        "t.st:13:6: error: type mismatch: cannot assign REF_TO INT to REF_TO DINT [E0209]",
        "t.st:14:8: error: '=' cannot be applied to REF_TO INT and REF_TO DINT [E0211]",
        "t.st:15:8: error: '<' cannot be applied to REF_TO INT and NULL [E0211]",
        "t.st:16:6: error: type mismatch: cannot assign ANY_INT to REF_TO INT [E0209]",
    ]


POINTERS = """PROGRAM Main
VAR a : ARRAY[0..2] OF INT; p : POINTER TO INT; i : INT; valid : INT; END_VAR
IF p <> 0 THEN valid := valid + 1; END_IF;
i := i + 1;
p := ADR(a[i MOD 3]);
p^ := p^ + 10;
END_PROGRAM
"""


def test_codesys_pointers_are_references_with_a_warning(tmp_path: Path) -> None:
    trace = sim_trace(tmp_path, POINTERS, 3)
    assert trace["Main.p"] == ["Main.a[1]", "Main.a[2]", "Main.a[0]"]
    assert trace["Main.a"] == [[0, 10, 0], [0, 10, 10], [10, 10, 10]]
    assert trace["Main.valid"] == [0, 1, 2]  # NULL before the first ADR
    assert diagnostics(POINTERS) == [
        "t.st:2:33: warning: POINTER TO is CODESYS/TwinCAT; IEC 61131-3 writes REF_TO [W0805]",
        "t.st:5:6: warning: ADR is CODESYS/TwinCAT; IEC 61131-3 writes REF (no address "
        "arithmetic) [W0805]",
    ]


def test_pointer_arithmetic_is_refused() -> None:
    found = diagnostics("""PROGRAM Main
VAR a : ARRAY[0..2] OF INT; p : POINTER TO INT; r : REF_TO INT; n : DWORD; END_VAR
p := ADR(a[0]) + 2;
n := p - 1;
r := REF(a[0]);
r := r + 1;
p := REF(a[1]);
END_PROGRAM
""")
    arithmetic = [d for d in found if "[E0701]" in d]
    assert [d.split(": error:")[0] for d in arithmetic] == ["t.st:3:16", "t.st:4:8", "t.st:6:8"]
    assert "padt has no pointer arithmetic" in arithmetic[0]
    # a POINTER is not a REF_TO: the two do not mix
    assert (
        "t.st:7:6: error: type mismatch: cannot assign REF_TO INT to POINTER TO INT [E0209]"
    ) in found


REFERENCE_TO_BOUND = """TYPE Point : STRUCT x, y : INT; END_STRUCT END_TYPE
PROGRAM Main
VAR a, b, n : INT; p : Point; END_VAR
VAR ra : REFERENCE TO INT; rp : REFERENCE TO Point; r : REF_TO INT; END_VAR
n := n + 1;
IF n = 1 THEN ra REF= a; ELSIF n = 3 THEN ra REF= b; END_IF;
ra := ra + 10;
rp REF= p;
rp.x := rp.x + 1;
r := REF(ra);
r^ := r^ + 100;
END_PROGRAM
"""


def test_codesys_reference_to_reads_and_writes_what_it_is_bound_to(tmp_path: Path) -> None:
    trace = sim_trace(tmp_path, REFERENCE_TO_BOUND, 3)
    assert trace["Main.ra"] == ["Main.a", "Main.a", "Main.b"]
    assert trace["Main.a"] == [110, 220, 220]
    assert trace["Main.b"] == [0, 0, 110]
    assert trace["Main.p.x"] == [1, 2, 3]
    assert trace["Main.r"] == ["Main.a", "Main.a", "Main.b"]  # REF of a REFERENCE TO
    found = diagnostics(REFERENCE_TO_BOUND)
    assert (
        "t.st:4:10: warning: REFERENCE TO is CODESYS/TwinCAT; IEC 61131-3 writes REF_TO and ^ "
        "[W0806]"
    ) in found
    assert sum("REF= is CODESYS/TwinCAT" in d for d in found) == 3


UNBOUND_REFERENCE_TO = """PROGRAM Main
VAR ra : REFERENCE TO INT; END_VAR
ra := 5;
END_PROGRAM
"""


def test_an_unbound_reference_to_is_a_program_fault(tmp_path: Path) -> None:
    path = tmp_path / "unbound.st"
    path.write_text(UNBOUND_REFERENCE_TO)
    run = padt("sim", str(path), "--cycles", "2")
    assert run.returncode == 3, run.stderr
    assert f"program Main: dereference of NULL in POU Main ({path}:3)" in run.stderr


def test_misused_reference_to_is_refused() -> None:
    found = diagnostics("""FUNCTION_BLOCK Fb
VAR_OUTPUT ro : REFERENCE TO INT; END_VAR
END_FUNCTION_BLOCK
PROGRAM Main
VAR a : INT; d : DINT; ra : REFERENCE TO INT; fb : Fb; END_VAR
a REF= d;
ra REF= d;
fb();
END_PROGRAM
""")
    assert (
        "t.st:2:12: error: 'ro': a REFERENCE TO cannot be a VAR_OUTPUT in padt; declare it "
        "VAR_IN_OUT of the type it refers to [E0220]"
    ) in found
    assert (
        "t.st:6:1: error: REF= needs a REFERENCE TO on its left, not a variable of type INT [E0220]"
        in found
    )
    assert (
        "t.st:7:1: error: type mismatch: REFERENCE TO INT cannot refer to a DINT [E0209]"
    ) in found


BUMP = """FUNCTION_BLOCK Bump
VAR_INPUT target : REFERENCE TO INT; END_VAR
target := target + 1;
END_FUNCTION_BLOCK
"""


REFERENCE_TO_INPUTS = (
    BUMP
    + """FUNCTION Twice : BOOL
VAR_INPUT out : REFERENCE TO DINT; END_VAR
out := out * 2;
Twice := TRUE;
END_FUNCTION
FUNCTION_BLOCK Holder
VAR own : INT; END_VAR
METHOD PUBLIC Add : INT
VAR_INPUT r : REFERENCE TO INT; step : INT; END_VAR
r := r + step;
Add := r;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR x : INT := 5; y : INT; d : DINT := 3; b : Bump; ok : BOOL; h : Holder; got : INT; END_VAR
VAR n : INT; END_VAR
n := n + 1;
IF n = 1 THEN b(target := x); ELSIF n = 3 THEN b(target := y); ELSE b(); END_IF;
ok := Twice(out := d);
got := h.Add(r := h.own, step := 10);
END_PROGRAM
"""
)


def test_a_reference_to_input_is_bound_to_the_callers_variable(tmp_path: Path) -> None:
    """CODESYS `VAR_INPUT r : REFERENCE TO T`: the call binds r to the variable passed (it
    is not a copy), the instance keeps the binding until the next call binds it anew; a
    function and a method are bound likewise."""
    trace = sim_trace(tmp_path, REFERENCE_TO_INPUTS, 4)
    assert trace["Main.x"] == [6, 7, 7, 7]  # bound by the first call, kept by b()
    assert trace["Main.y"] == [0, 0, 1, 2]
    assert trace["Main.b.target"] == ["Main.x", "Main.x", "Main.y", "Main.y"]
    assert trace["Main.d"] == [6, 12, 24, 48]
    assert trace["Main.h.own"] == [10, 20, 30, 40]
    assert trace["Main.got"] == [10, 20, 30, 40]
    found = diagnostics(REFERENCE_TO_INPUTS)
    assert not [d for d in found if "error" in d or "W0301" in d]  # writing through is meant
    assert sum("[W0806]" in d for d in found) == 3  # each REFERENCE TO declared


UNBOUND_REFERENCE_TO_INPUT = (
    BUMP
    + """PROGRAM Main
VAR b : Bump; END_VAR
b();
END_PROGRAM
"""
)


def test_an_unbound_reference_to_input_is_a_program_fault(tmp_path: Path) -> None:
    path = tmp_path / "unbound.st"
    path.write_text(UNBOUND_REFERENCE_TO_INPUT)
    run = padt("sim", str(path), "--cycles", "2")
    assert run.returncode == 3, run.stderr
    assert f"dereference of NULL in POU Bump ({path}:3)" in run.stderr


def test_a_reference_to_input_needs_a_lasting_variable_of_its_type() -> None:
    found = diagnostics(
        BUMP
        + """FUNCTION F : INT
VAR_INPUT v : INT; END_VAR
VAR b : Bump; END_VAR
b(target := v);
END_FUNCTION
PROGRAM Main
VAR x : INT; d : DINT; b : Bump; w : WORD; END_VAR
VAR CONSTANT k : INT := 1; END_VAR
b(target := x + 1);
b(target := d);
b(target := k);
b(target := w.0);
END_PROGRAM
"""
    )
    prefix = "error: REFERENCE TO input 'target' binds to a variable, not to"
    assert (
        f"t.st:8:13: {prefix} 'v', a variable of a function (it is gone when the call ends) [E0220]"
    ) in found
    assert f"t.st:13:15: {prefix} an expression; it needs a variable [E0220]" in found
    assert "t.st:14:13: error: type mismatch: REFERENCE TO INT cannot refer to a DINT [E0401]" in (
        found
    )
    assert f"t.st:15:13: {prefix} constant 'k' [E0220]" in found
    assert f"t.st:16:13: {prefix} a single bit [E0220]" in found


GLOBAL_KEEPER = """TYPE Point : STRUCT x, y : INT; END_STRUCT END_TYPE
FUNCTION_BLOCK Keep
VAR own : INT; spot : Point; mine, there : REF_TO INT; END_VAR
mine := REF(own);
there := REF(spot.y);
END_FUNCTION_BLOCK
VAR_GLOBAL keeper : Keep; END_VAR
PROGRAM Main
VAR_EXTERNAL keeper : Keep; END_VAR
keeper();
END_PROGRAM
"""


def test_a_reference_made_in_a_global_block_reads_as_its_global_path(tmp_path: Path) -> None:
    trace = sim_trace(tmp_path, GLOBAL_KEEPER, 1)
    assert trace["keeper.mine"] == ["keeper.own"]
    assert trace["keeper.there"] == ["keeper.spot.y"]


LAMP_COMMAND = """FUNCTION_BLOCK Lamp
VAR_OUTPUT level : INT; END_VAR
METHOD PUBLIC SetLevel
VAR_INPUT l : INT; END_VAR
level := l;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Cmd
VAR refLamp : REFERENCE TO Lamp; END_VAR
METHOD PUBLIC Bind
VAR_INPUT refLamp : REFERENCE TO Lamp; END_VAR
IF __ISVALIDREF(refLamp) THEN
  THIS^.refLamp REF= refLamp;
ELSE
  THIS^.refLamp REF= 0;
END_IF
END_METHOD
METHOD PUBLIC Run
IF __ISVALIDREF(THIS^.refLamp) THEN
  THIS^.refLamp.SetLevel(THIS^.refLamp.level + 1);
END_IF
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR lamp : Lamp; c : Cmd; n : INT; bound : BOOL; END_VAR
n := n + 1;
IF n = 2 THEN c.Bind(refLamp := lamp); ELSIF n = 4 THEN c.Bind(); END_IF;
bound := __ISVALIDREF(c.refLamp);
c.Run();
END_PROGRAM
"""


def test_ref_assign_zero_unbinds_and_isvalidref_tells(tmp_path: Path) -> None:
    """CODESYS `r REF= 0;` makes a REFERENCE TO refer to nothing; `__ISVALIDREF(r)` is
    TRUE while it is bound (the pattern of the TwinCAT command samples: a method binds or
    unbinds the reference it is given, another uses it only when it is valid)."""
    trace = sim_trace(tmp_path, LAMP_COMMAND, 5)
    assert trace["Main.bound"] == [False, True, True, False, False]
    assert trace["Main.c.refLamp"] == ["NULL", "Main.lamp", "Main.lamp", "NULL", "NULL"]
    assert trace["Main.lamp.level"] == [0, 1, 2, 2, 2]
    found = diagnostics(LAMP_COMMAND)
    assert not [d for d in found if "error" in d]
    assert (
        "t.st:12:4: warning: __ISVALIDREF is CODESYS/TwinCAT; IEC 61131-3 writes r <> NULL "
        "with r : REF_TO [W0806]"
    ) in found
    assert "t.st:15:3: warning: REF= is CODESYS/TwinCAT; IEC 61131-3 writes r := REF(x) with " in (
        "".join(found)
    )


def test_ref_assign_of_a_number_and_isvalidref_of_a_value_are_refused() -> None:
    found = diagnostics("""PROGRAM Main
VAR x : INT; r : REFERENCE TO INT; p : REF_TO INT; ok : BOOL; END_VAR
r REF= 5;
ok := __ISVALIDREF(x);
ok := __ISVALIDREF(p);
ok := __ISVALIDREF();
END_PROGRAM
""")
    assert "t.st:3:8: error: REF of an expression; it needs a variable [E0219]" in found
    needs = "error: __ISVALIDREF needs a REFERENCE TO; compare a REF_TO or POINTER TO with NULL"
    assert f"t.st:4:7: {needs} [E0220]" in found
    assert f"t.st:5:7: {needs} [E0220]" in found
    assert "t.st:6:7: error: __ISVALIDREF takes one REFERENCE TO, unnamed [E0220]" in found
