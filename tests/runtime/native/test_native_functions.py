"""FUNCTION bodies as C (runtime/code/native/function_body.py): with the variables in native
memory, a FUNCTION of numbers and BOOLs is C, called directly from C; every value equal to
the Python tier's after every cycle, the same faults naming the same ST lines."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from runtime.code.native.function_body import IMAGE_LEFT
from runtime.code.native.tier import IN_IMAGE, NativeTier
from runtime.contract.artifact import ProgramConfig
from tests.compiler.test_differential import (
    ACC,
    CYCLES,
    MAIN,
    TEMPLATE,
    Features,
    _declarations,
    _Writer,
)
from tests.support.native_runs import Pair, side_by_side

FUNCTIONS = """
FUNCTION Lerp : REAL
VAR_INPUT a, b : REAL; t : REAL := 0.5; END_VAR
Lerp := a + (b - a) * t;
END_FUNCTION
FUNCTION Smooth : REAL
VAR_INPUT x, target : REAL; steps : INT := 3; END_VAR
VAR k : INT; END_VAR
FOR k := 1 TO steps DO
  x := Lerp(x, target, 0.25);   (* a FUNCTION's C calling another's *)
  IF ABS(x - target) < 0.01 THEN EXIT; END_IF;
END_FOR;
Smooth := x;
END_FUNCTION
FUNCTION Wrap : INT
VAR_INPUT v : DINT; END_VAR
VAR w : INT; END_VAR
w := DINT_TO_INT(v * 3);
WHILE w > 1000 DO w := w - 700; END_WHILE;
Wrap := w;
END_FUNCTION
FUNCTION Count : UDINT
VAR_INPUT on : BOOL; END_VAR
VAR_IN_OUT n : UDINT; seen : BOOL; END_VAR
VAR_OUTPUT twice : ULINT; END_VAR
IF on THEN n := n + 1; END_IF;
seen := seen OR on;
twice := UDINT_TO_ULINT(n) * 2;
Count := n MOD 7;
END_FUNCTION
FUNCTION Later : TIME
VAR_INPUT t : TIME; END_VAR
Later := t + T#250ms;
END_FUNCTION
FUNCTION Shout : STRING
VAR_INPUT s : STRING; END_VAR
Shout := CONCAT(s, '!');
END_FUNCTION
FUNCTION Ratio : DINT
VAR_INPUT a, b : DINT; END_VAR
Ratio := Wrap(a) / b;
END_FUNCTION
PROGRAM Main
VAR
  r, s : REAL := 10.0; i : INT; n : UDINT; seen, on : BOOL; m : UDINT; big : ULINT;
  d : DINT := 40000; t : TIME; text : STRING := 'go'; q : DINT; b : DINT := 4;
END_VAR
r := Lerp(r, 20.0);
s := Smooth(s, r, steps := 5);
i := Wrap(d);
d := d + 12345;
on := NOT on;
m := Count(on, n, seen, twice => big);
t := Later(t);
text := Shout(LEFT(text, 5));
b := b - 1;
q := Ratio(d, b);
END_PROGRAM
"""


def in_memory(text: str, tier: NativeTier, memory: str, after: str) -> Pair:
    """`text` side by side on both tiers, the native one in native memory ("image") or on
    the slots of Python objects ("slots"): there with a reference declared `after` the
    given declaration, which keeps a configuration on objects (image_plan.py)."""
    if memory == "slots":
        assert after in text
        text = text.replace(after, f"{after} onObjects : REF_TO INT;", 1)
    pair = side_by_side(text, tier)
    assert (pair.report.memory == IN_IMAGE) == (memory == "image"), pair.report.memory
    return pair


@pytest.mark.parametrize("memory", ["image", "slots"])
def test_functions_of_numbers_run_as_c_with_the_python_values(
    native_tier: NativeTier, memory: str
) -> None:
    pair = in_memory(FUNCTIONS, native_tier, memory, "b : DINT := 4;")
    c = ("Count", "Later", "Lerp", "Main", "Ratio", "Shout", "Smooth", "Wrap")
    assert pair.report.bodies == c, pair.report.left
    pair.cycle_and_compare(3)
    values = pair.native.variables.values()
    assert (values["Main.m"], values["Main.big"], values["Main.text"]) == (2, 4, "go!!!")
    # b is 0 in the fourth cycle: the fault names Ratio's line on both tiers
    assert "division by zero in POU Ratio (prog.st:41)" in pair.fault_of_the_next_cycle()


def python_broken(pair: Pair, functions: tuple[str, ...]) -> None:
    """The Python of each FUNCTION named replaced, on the native tier, by one that fails:
    a call that reaches it (not its C) faults the program, and the tiers differ."""
    namespace: dict[str, Any] = pair.native.variables.code.namespace  # type: ignore[union-attr]

    def broken(**_: object) -> None:
        raise AssertionError("the Python of a FUNCTION whose C is in place")

    for name in functions:
        assert f"FN_{name.upper()}" in namespace
        namespace[f"FN_{name.upper()}"] = broken


@pytest.mark.parametrize("memory", ["image", "slots"])
def test_c_calls_the_functions_c_not_their_python(native_tier: NativeTier, memory: str) -> None:
    """The call goes to the FUNCTION's C: with its Python replaced by one that fails,
    the native resource runs on with the Python tier's values."""
    pair = in_memory(FUNCTIONS, native_tier, memory, "b : DINT := 4;")
    python_broken(pair, ("Lerp", "Smooth", "Wrap", "Count", "Later", "Shout"))
    pair.cycle_and_compare(3)


# The random bodies of the differential test's function block, as the body of a FUNCTION
# whose in-outs are the block's variables (the block calls it): the same statements, on
# the locals of a C function instead of an instance's bytes.
FUNCTION_OF_ACC = """\
FUNCTION AccF : BOOL
VAR_INPUT inc : INT; reset : BOOL; gain : REAL; END_VAR
VAR_IN_OUT total : DINT; big : BOOL; n : UINT; x : REAL; j : INT; END_VAR
VAR k0, k1, w0, w1 : INT; END_VAR
{acc_body}
AccF := big AND NOT reset;
END_FUNCTION

FUNCTION_BLOCK Acc
VAR_INPUT inc : INT; reset : BOOL; gain : REAL; END_VAR
VAR_OUTPUT total : DINT; big : BOOL; END_VAR
VAR n : UINT; x : REAL; j : INT; last : BOOL; END_VAR
last := AccF(inc := inc, reset := reset, gain := gain, total := total, big := big,
             n := n, x := x, j := j);
END_FUNCTION_BLOCK

"""


@st.composite
def function_programs(draw: st.DrawFn) -> str:
    acc = _Writer(draw, ACC, Features())
    main = _Writer(draw, MAIN, Features())
    acc_body = "\n".join(acc.block(2, (), most=4))
    program = TEMPLATE[TEMPLATE.index("PROGRAM Main") :].format(
        main_vars="\n".join(_declarations(draw)), main_body="\n".join(main.block(3, (), most=8))
    )
    return FUNCTION_OF_ACC.format(acc_body=acc_body) + program


@settings(
    max_examples=16,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(function_programs(), st.booleans())
def test_random_function_bodies_run_alike_on_both_tiers(
    native_tier: NativeTier, program: str, on_slots: bool
) -> None:
    if on_slots:  # slot mode's C of the FUNCTION (a reference keeps the image away)
        program = program.replace("  acc : Acc;", "  acc : Acc;\n  p : REF_TO INT;")
    pair = side_by_side(program, native_tier)
    assert (pair.report.memory == IN_IMAGE) != on_slots, pair.report.memory
    assert "AccF" in pair.report.bodies, pair.report.left
    pair.cycle_and_compare(CYCLES)


STRUCTURE_GIVEN = """
TYPE Pt : STRUCT x : REAL; y : REAL; END_STRUCT; END_TYPE
FUNCTION Moved : REAL
VAR_INPUT a : Pt; END_VAR
a.x := a.x + 99.0;   (* its own copy: the caller's p stays *)
Moved := a.x + a.y;
END_FUNCTION
PROGRAM Main
VAR p : Pt := (x := 1.0, y := 0.5); r : REAL; END_VAR
p.y := p.y + 1.0;
r := Moved(p);
END_PROGRAM
"""


@pytest.mark.parametrize("memory", ["image", "slots"])
def test_a_structure_given_to_a_function_is_its_own_copy(
    native_tier: NativeTier, memory: str
) -> None:
    """In native memory the FUNCTION (Python: it takes a structure) once got a view of the
    caller's bytes, and its write to its input changed the caller's p.x (100 for 1)."""
    pair = in_memory(STRUCTURE_GIVEN, native_tier, memory, "r : REAL;")
    pair.cycle_and_compare(3)
    values = pair.native.variables.values()
    assert (values["Main.p.x"], values["Main.r"]) == (1.0, 100.0 + 3.5)


LEFT_OUT = """
TYPE Pt : STRUCT x : REAL := 0.5; END_STRUCT; END_TYPE
FUNCTION Bump : REAL
VAR_INPUT a : Pt; n : ARRAY[1..2] OF INT; END_VAR
a.x := a.x + 1.0; n[1] := n[1] + 1;
Bump := a.x + INT_TO_REAL(n[1]);
END_FUNCTION
FUNCTION_BLOCK Box
VAR_OUTPUT y : REAL; END_VAR
METHOD PUBLIC Grow : REAL
VAR_INPUT a : Pt; END_VAR
a.x := a.x * 2.0; Grow := a.x;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR r, q : REAL; b : Box; END_VAR
r := Bump(); q := b.Grow();
END_PROGRAM
"""


@pytest.mark.parametrize("memory", ["image", "slots"])
def test_an_input_left_out_takes_its_initial_value_at_every_call_on_both_tiers(
    native_tier: NativeTier, memory: str
) -> None:
    """A structure or array input left out of a call is a fresh initial value at every
    call (tests/compiler/test_compiler_regressions.py), on the native tier too: the caller
    that leaves one out makes the fresh value in C on slots, and stays Python in native
    memory (a structure made afresh is an object, not bytes of the image)."""
    pair = in_memory(LEFT_OUT, native_tier, memory, "b : Box;")
    pair.cycle_and_compare(3)
    values = pair.native.variables.values()
    assert (values["Main.r"], values["Main.q"]) == (2.5, 1.0)


# the length of a vector, which both programs of vectors below have
V_LEN = """
FUNCTION VLen : REAL
VAR_INPUT a : Vec; END_VAR
VLen := SQRT(a.x * a.x + a.y * a.y + a.z * a.z);
END_FUNCTION
"""

TEXTS_AND_STRUCTURES = (
    """
TYPE Vec : STRUCT x, y, z : REAL; END_STRUCT; END_TYPE
FUNCTION VAdd : Vec
VAR_INPUT a, b : Vec; END_VAR
VAdd.x := a.x + b.x; VAdd.y := a.y + b.y; VAdd.z := a.z + b.z;
END_FUNCTION
"""
    + V_LEN
    + """
FUNCTION VScale : Vec
VAR_INPUT a : Vec; m : REAL := 2.0; END_VAR
VAR len : REAL; END_VAR
len := VLen(a);
IF len > 0.0 THEN
  VScale := VAdd(a, a);   (* a FUNCTION's C given another's structure *)
  VScale.x := VScale.x * m;
END_IF;
END_FUNCTION
FUNCTION Bump : REAL
VAR_INPUT a : Vec; END_VAR
a.x := a.x + 100.0;       (* its own copy: the caller's stays *)
Bump := a.x;
END_FUNCTION
FUNCTION Tag : STRING
VAR_INPUT s : STRING; n : INT := 1; sep : STRING := '-'; END_VAR
VAR t : STRING; k : INT; END_VAR
t := s;
FOR k := 1 TO n MOD 3 DO t := CONCAT(t, sep); END_FOR;
Tag := CONCAT(t, INT_TO_STRING(n));
END_FUNCTION
FUNCTION Short : STRING[4]
VAR_INPUT s : STRING; END_VAR
Short := s;
END_FUNCTION
FUNCTION Interp : REAL
VAR_INPUT x : REAL; xy : ARRAY[1..4, 0..1] OF REAL; END_VAR
VAR i : INT := 2; END_VAR
WHILE i < 4 AND xy[i, 0] < x DO i := i + 1; END_WHILE;
Interp := xy[i - 1, 1] + (xy[i, 1] - xy[i - 1, 1]) * (x - xy[i - 1, 0])
          / (xy[i, 0] - xy[i - 1, 0]);
END_FUNCTION
FUNCTION Table : REAL
VAR_INPUT x : REAL; END_VAR
VAR data : ARRAY[1..4, 0..1] OF REAL := [0.0, 1.0, 10.0, 3.0, 20.0, 4.0]; END_VAR
Table := Interp(x, data);  (* a constant array, the rest at 0, given to another's C *)
END_FUNCTION
FUNCTION Sort : BOOL
VAR_IN_OUT a : ARRAY[1..3] OF INT; END_VAR
VAR t, k : INT; END_VAR
FOR k := 1 TO 2 DO
  IF a[k] > a[k + 1] THEN t := a[k]; a[k] := a[k + 1]; a[k + 1] := t; END_IF;
END_FOR;
Sort := a[1] <= a[2];
END_FUNCTION
PROGRAM Main
VAR
  p : Vec := (x := 1.0, y := 2.0, z := 2.0); q, r : Vec; l, b : REAL;
  s : STRING := 'a'; u, w : STRING; n : INT;
  x, t : REAL; arr : ARRAY[1..3] OF INT := [5, 3, 9]; sorted : BOOL;
END_VAR
q := VAdd(p, q);
r := VScale(q, m := 0.5);
l := VLen(r);
b := Bump(p);
n := n + 1;
s := Tag(RIGHT(s, 6), n);
u := Short(s);
w := Tag(u, sep := '+');
t := Table(x);
x := x + 2.5;
sorted := Sort(arr);
arr[3] := arr[3] - 7;
END_PROGRAM
"""
)


@pytest.mark.parametrize("memory", ["image", "slots"])
def test_functions_of_texts_structures_and_arrays_run_as_c_on_slots(
    native_tier: NativeTier, memory: str
) -> None:
    """On slots a text, a structure or an array is a Python object, which a FUNCTION's C
    takes and gives: each C body is called from C, with the Python replaced by one that
    fails. In native memory the FUNCTIONs of texts and structures are C too (their C
    called from C: `test_functions_of_structures_are_c_in_native_memory_too`); those of
    arrays stay Python (an array is bytes of the image there), and Main with them, which
    calls the others' Python, and a structure one gives is stored into the image whole
    (which faulted before: "a variable of STRUCT_VEC cannot hold <STRUCT_VEC object>")."""
    pair = in_memory(TEXTS_AND_STRUCTURES, native_tier, memory, "sorted : BOOL;")
    texts = ("Short", "Tag")
    arrays = ("Interp", "Sort", "Table")
    functions = ("Bump", "VAdd", "VLen", "VScale", *arrays, *texts)
    if memory == "image":
        left = dict(pair.report.left)
        assert {pou for pou in functions if pou in left} == set(arrays)
        assert left["Interp"] == left["Sort"] == IMAGE_LEFT
        assert left["Table"].startswith("a list of values")  # its constant array
        assert set(functions) - set(arrays) <= set(pair.report.bodies)
        in_c: tuple[str, ...] = ()  # Main stays Python there: it calls their Python
    else:
        assert pair.report.bodies == tuple(sorted((*functions, "Main"))), pair.report.left
        in_c = functions
    python_broken(pair, in_c)
    pair.cycle_and_compare(4)
    values = pair.native.variables.values()
    assert values["Main.p.x"] == 1.0 and values["Main.b"] == 101.0
    assert values["Main.q.x"] == 4.0 and values["Main.r.x"] == 4.0
    assert (values["Main.s"], values["Main.u"], values["Main.w"]) == ("-1--23-4", "-1--", "-1--+1")
    assert (values["Main.t"], values["Main.arr"]) == (2.5, [-2, -4, -5])


STRUCTURES = (
    """
TYPE Vec : STRUCT x, y, z : REAL; tag : STRING[8] := 'v'; n : INT := 7; END_STRUCT; END_TYPE
FUNCTION VAdd : Vec
VAR_INPUT a, b : Vec; END_VAR
VAdd.x := a.x + b.x; VAdd.y := a.y + b.y; VAdd.z := a.z + b.z;
VAdd.n := a.n + b.n;
END_FUNCTION
"""
    + V_LEN
    + """
FUNCTION VScale : Vec
VAR_INPUT a : Vec; k : REAL; END_VAR
VAR t : Vec; END_VAR
t := a;
t.x := t.x * k; t.y := t.y * k; t.z := t.z * k;
a.x := 0.0;  (* its own copy: the caller's stays *)
VScale := t;
END_FUNCTION
FUNCTION VNorm : Vec
VAR_INPUT a : Vec; END_VAR
VAR l : REAL; END_VAR
l := VLen(a);
IF l > 0.0 THEN VNorm := VScale(a, 1.0 / l); ELSE VNorm := a; END_IF;
END_FUNCTION
FUNCTION Split : BOOL
VAR_INPUT a : Vec; END_VAR
VAR_OUTPUT left, right : Vec; END_VAR
VAR_IN_OUT count : Vec; END_VAR
left := a; left.x := 0.0;
right := a; right.y := 0.0; right.tag := 'right';
count.n := count.n + 1;
Split := a.x > a.y;
END_FUNCTION
PROGRAM Main
VAR
  p : Vec := (x := 1.0, y := 2.0, z := 2.0); q, r, fresh, l, rr, c : Vec; len : REAL;
  more : BOOL;
END_VAR
q := VAdd(p, q);
len := VLen(q);
r := VNorm(q);
p.x := p.x + 0.5;
fresh := VScale(fresh, 2.0);
more := Split(p, left => l, right => rr, count := c);
END_PROGRAM
"""
)


@pytest.mark.parametrize("memory", ["image", "slots"])
def test_functions_of_structures_are_c_in_native_memory_too(
    native_tier: NativeTier, memory: str
) -> None:
    """In native memory a structure is bytes: a FUNCTION's C takes the caller's (copied
    into its frame as it begins), writes its result and outputs into bytes the caller's
    frame holds, and makes a fresh one from bytes made once as its module binds (the
    members' initial values: `tag`, `n`). Each C body is called from C, with the Python
    replaced by one that fails."""
    pair = in_memory(STRUCTURES, native_tier, memory, "more : BOOL;")
    functions = ("Split", "VAdd", "VLen", "VNorm", "VScale")
    assert pair.report.bodies == ("Main", *functions), pair.report.left
    python_broken(pair, functions)
    pair.cycle_and_compare(4)
    values = pair.native.variables.values()
    assert (values["Main.p.x"], values["Main.q.x"], values["Main.q.n"]) == (3.0, 7.0, 35)
    assert (values["Main.fresh.tag"], values["Main.fresh.n"]) == ("v", 7)
    assert (values["Main.rr.tag"], values["Main.l.x"], values["Main.c.n"]) == ("right", 0.0, 11)
    assert (
        round(values["Main.r.x"] ** 2 + values["Main.r.y"] ** 2 + values["Main.r.z"] ** 2, 5) == 1
    )


GLOBALS = """
VAR_GLOBAL gain : REAL := 2.0; calls : DINT; END_VAR
FUNCTION Scaled : REAL
VAR_INPUT x : REAL; END_VAR
VAR_EXTERNAL gain : REAL; END_VAR
Scaled := x * gain;
END_FUNCTION
FUNCTION Counted : DINT
VAR_EXTERNAL calls : DINT; END_VAR
calls := calls + 1;
Counted := calls;
END_FUNCTION
PROGRAM Main
VAR r : REAL := 1.0; n : DINT; END_VAR
r := Scaled(r);
n := Counted();
gain := gain + 0.5;
END_PROGRAM
PROGRAM Other
VAR s : REAL := 3.0; seen : DINT; END_VAR
s := Scaled(s) - 1.0;
seen := calls;
END_PROGRAM
"""


def test_a_function_reads_and_writes_the_globals_of_the_program_that_calls_it(
    native_tier: NativeTier,
) -> None:
    """Two programs, each with its own view of the globals during its cycle: the FUNCTION's
    C reads and writes the calling program's, as its Python does."""
    programs = [ProgramConfig(name="Main", pou="Main", program_id=1),
                ProgramConfig(name="Other", pou="Other", program_id=2)]  # fmt: skip
    pair = side_by_side(GLOBALS, native_tier, programs)
    assert pair.report.memory == IN_IMAGE
    assert {"Counted", "Scaled"} <= set(pair.report.bodies)
    pair.cycle_and_compare(4)
    assert pair.native.variables.values()["calls"] == 4


METHODS = """
FUNCTION_BLOCK Tank
VAR_INPUT cap : REAL := 100.0; END_VAR
VAR_OUTPUT level : REAL; END_VAR
VAR n : INT; END_VAR
METHOD PUBLIC Fill : REAL
VAR_INPUT amount : REAL; END_VAR
VAR room : REAL; END_VAR
room := cap - level;
IF amount > room THEN amount := room; END_IF;
level := level + amount;
n := n + 1;
Fill := amount;
END_METHOD
METHOD PUBLIC Drain
VAR_INPUT by : REAL := 1.0; END_VAR
VAR_OUTPUT left : REAL; END_VAR
level := level - by;
IF level < 0.0 THEN level := 0.0; END_IF;
left := level;
END_METHOD
METHOD PUBLIC Share : DINT
VAR_INPUT parts : DINT; END_VAR
Share := REAL_TO_DINT(level) / parts;   (* parts 0: a fault in the method *)
END_METHOD
METHOD PUBLIC Label : STRING
VAR_INPUT prefix : STRING := 'T'; END_VAR
Label := CONCAT(prefix, INT_TO_STRING(n));
END_METHOD
level := level * 0.99;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Mixer EXTENDS Tank
VAR speed : INT; END_VAR
speed := speed + 1;
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  t : Tank; m : Mixer; got, l : REAL; k : INT; parts : DINT := 3; s : DINT; a, b : STRING;
END_VAR
FOR k := 1 TO 10 DO
  got := got + t.Fill(5.0) + m.Fill(1.0);   (* m: Tank's Fill on a Mixer's bytes *)
END_FOR;
t.Drain(by := 2.0, left => l);
m.Drain();
parts := parts - 1;
s := t.Share(parts) + m.Share(1);
a := t.Label('tank ');
b := m.Label();
t(); m();
END_PROGRAM
"""


@pytest.mark.parametrize("memory", ["image", "slots"])
def test_methods_of_numbers_and_texts_run_as_c(native_tier: NativeTier, memory: str) -> None:
    """In native memory, and on objects (where a call takes the C when the instance is
    exactly of its declared class, else looks the method up as Python does)."""
    pair = in_memory(METHODS, native_tier, memory, "a, b : STRING;")
    assert pair.report.bodies == ("Main", "Mixer", "Tank")
    methods = ("M__DRAIN", "M__FILL", "M__LABEL", "M__SHARE")
    assert pair.report.methods == tuple(f"Tank.{method}" for method in methods)
    assert "3 of 3 POU bodies run as C (and 4 methods)" in pair.report.summary()
    # with the methods' Python failing (on the views of the image, or the classes), C
    # calls the C
    code = pair.native.variables.code
    assert code is not None
    classes = code.image.views if code.image is not None else code.namespace

    def broken(*_: object, **__: object) -> None:
        raise AssertionError("the Python of a method whose C is in place")

    for method in methods:
        setattr(classes["POU_TANK"], method, broken)
        setattr(classes["POU_MIXER"], method, broken)
    pair.cycle_and_compare(2)
    values = pair.native.variables.values()
    assert (values["Main.t.n"], values["Main.m.n"]) == (20, 20)  # ten Fills a cycle each
    assert (values["Main.a"], values["Main.b"]) == ("tank 20", "T20")  # a method of texts
    # parts is 0 in the third cycle: the fault names the method's line, on both tiers
    assert "division by zero in POU Tank (prog.st:24)" in pair.fault_of_the_next_cycle()


INHERITED = """
FUNCTION_BLOCK Base
VAR_OUTPUT n : INT; END_VAR
METHOD PUBLIC Step : INT
Step := THIS^.Size() + 1;     (* on a Derived: Derived's Size *)
n := n + Step;
END_METHOD
METHOD PUBLIC Size : INT
Size := 1;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Derived EXTENDS Base
METHOD PUBLIC OVERRIDE Size : INT
Size := 10;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR b : Base; d : Derived; x, y : INT; r : REF_TO INT; END_VAR
x := b.Step();
y := d.Step();                (* Base's Step, inherited, on a Derived *)
END_PROGRAM
"""


def test_an_inherited_method_on_slots_calls_the_override_of_its_instance(
    native_tier: NativeTier,
) -> None:
    """Base's Step runs as C on a Derived (its declared class's method, inherited), and
    its call of THIS^.Size() takes Derived's override: the object's class is not exactly
    Base there, so the call looks the method up as Python does."""
    pair = side_by_side(INHERITED, native_tier)
    assert pair.report.memory != IN_IMAGE  # the reference keeps it on objects
    assert "Base.M__STEP" in pair.report.methods
    pair.cycle_and_compare(2)
    values = pair.native.variables.values()
    assert (values["Main.x"], values["Main.y"], values["Main.d.n"]) == (2, 11, 22)


RECURSION = """
FUNCTION Deeper : DINT
VAR_INPUT n : DINT; END_VAR
Deeper := Deeper(n + 1);
END_FUNCTION
FUNCTION Fact : LREAL
VAR_INPUT n : INT; END_VAR
IF n <= 1 THEN Fact := 1.0; ELSE Fact := INT_TO_LREAL(n) * Fact(n - 1); END_IF;
END_FUNCTION
PROGRAM Main
VAR r : DINT; f : LREAL; k : INT; END_VAR
k := k + 10;
f := Fact(k);
IF k > 30 THEN r := Deeper(0); END_IF;
END_PROGRAM
"""


@pytest.mark.parametrize("memory", ["image", "slots"])
def test_a_recursion_in_c_is_a_program_error_as_in_python(
    native_tier: NativeTier, memory: str
) -> None:
    """A FUNCTION's C calls itself on the C stack: an endless recursion once ran it out (the
    process died of SIGSEGV); now it is the program error of the Python tier, at the same
    ST line, and a recursion that ends gives the Python tier's values."""
    pair = in_memory(RECURSION, native_tier, memory, "k : INT;")
    assert {"Deeper", "Fact"} <= set(pair.report.bodies)
    pair.cycle_and_compare(3)  # Fact(10), Fact(20), Fact(30) as C
    fault = pair.fault_of_the_next_cycle()
    assert fault == "calls nested too deep (recursion) in POU Deeper (prog.st:4)"
