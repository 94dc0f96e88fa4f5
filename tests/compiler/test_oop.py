"""Object orientation of IEC 61131-3 edition 3 (docs/language.md, "Object orientation"):
methods, EXTENDS with THIS and SUPER, interfaces, `?=`; each construct traced cycle by cycle
through `padt sim` (100 ms cycles), and the refusals with their codes. What the runtime
does with such instances (OLT paths, forcing, reload) is in tests/runtime/test_oop.py."""

from __future__ import annotations

from pathlib import Path

from tests.compiler.test_references import diagnostics
from tests.conftest import padt, sim_trace

COUNTER = """
FUNCTION_BLOCK Counter
VAR_INPUT step : INT := 1; END_VAR
VAR_OUTPUT n : INT; END_VAR
VAR calls : INT; END_VAR
METHOD PUBLIC Add : INT
VAR_INPUT k : INT; END_VAR
VAR_OUTPUT before : INT; END_VAR
VAR tmp : INT; END_VAR
tmp := tmp + 1;        (* a method's locals start afresh in every call *)
before := n;
n := n + k * tmp;
THIS^.calls := calls + 1;
Add := n;
END_METHOD
METHOD PRIVATE Wipe
n := 0;
END_METHOD
METHOD PUBLIC Clear
Wipe();
END_METHOD
n := n + step;
END_FUNCTION_BLOCK
"""


COUNTER_CALLS = (
    COUNTER
    + """
PROGRAM Main
VAR c : Counter; r, b : INT; END_VAR
c(step := 2);
r := c.Add(k := 10, before => b);
c.Add(5);
IF r > 50 THEN c.Clear(); END_IF;
END_PROGRAM
"""
)


def test_a_method_sees_its_block_and_gives_a_result_and_outputs(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, COUNTER_CALLS, 5)
    # body +2, Add(10) +10 (its local tmp is 1 in every call), Add(5) +5
    assert t["Main.r"] == [12, 29, 46, 63, 12]
    assert t["Main.b"] == [2, 19, 36, 53, 2]
    # Clear (public) calls Wipe (private) in cycle 4, after both Adds
    assert t["Main.c.n"] == [17, 34, 51, 0, 17]
    assert t["Main.c.calls"] == [2, 4, 6, 8, 10]
    assert "Main.c.tmp" not in t and "Main.c.k" not in t  # temporaries are no members


PUMP_AND_MAIN = """
PROGRAM Pump
VAR runs : INT; END_VAR
METHOD PUBLIC Stop
runs := 0;
END_METHOD
METHOD Twice : INT
VAR_INPUT x : INT; END_VAR
Twice := 2 * x;
END_METHOD
runs := Twice(runs) + 1;
END_PROGRAM
PROGRAM Main
VAR k : INT; END_VAR
k := k + 1;
IF k = 3 THEN Pump.Stop(); END_IF;
END_PROGRAM
CONFIGURATION C
  RESOURCE R ON PLC
    TASK T (INTERVAL := T#100ms, PRIORITY := 1);
    PROGRAM Pump WITH T : Pump;
    PROGRAM Main WITH T : Main;
  END_RESOURCE
END_CONFIGURATION
"""


def test_methods_of_a_program_called_inside_and_from_another_program(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, PUMP_AND_MAIN, 5)
    assert t["Pump.runs"] == [1, 3, 0, 1, 3]


WALKER = """
FUNCTION_BLOCK Walker
VAR i : INT; visits : INT; END_VAR
METHOD Skip
i := i + 1;
END_METHOD
FOR i := 1 TO 6 DO
  visits := visits + 1;
  Skip();
END_FOR;
END_FUNCTION_BLOCK
PROGRAM Main
VAR w : Walker; END_VAR
w();
END_PROGRAM
"""


def test_a_method_called_in_a_for_loop_that_writes_the_counter_slot(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, WALKER, 2)
    assert t["Main.w.visits"] == [3, 6]  # 1, 3, 5: the method moved the counter on


DRIVES = """
FUNCTION_BLOCK Drive
VAR_INPUT speed : INT; END_VAR
VAR_OUTPUT log : INT; END_VAR
METHOD PUBLIC Code : INT
Code := 1;
END_METHOD
METHOD PUBLIC Run
log := log * 10 + THIS^.Code();   (* the instance's own Code: dispatched *)
END_METHOD
log := log + speed;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Servo EXTENDS Drive
VAR turns : INT; END_VAR
METHOD PUBLIC OVERRIDE Code : INT
Code := 2 + SUPER^.Code();
END_METHOD
turns := turns + 1;
SUPER^();                           (* the base's body: log := log + speed *)
END_FUNCTION_BLOCK
"""


DRIVES_CALLS = (
    DRIVES
    + """
PROGRAM Main
VAR d : Drive; s : Servo; x : INT; END_VAR
d(speed := 1); s(speed := 2);
d.Run(); s.Run();
x := s.Code();
END_PROGRAM
"""
)


def test_extends_inherits_members_overrides_and_calls_super(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, DRIVES_CALLS, 3)
    assert t["Main.d.log"] == [11, 121, 1221]
    # Servo: body adds 2 through SUPER^(), Run appends its Code 3 (2 + the base's 1)
    assert t["Main.s.log"] == [23, 253, 2553]
    assert t["Main.s.turns"] == [1, 2, 3]
    assert t["Main.s.speed"] == [2, 2, 2]  # an inherited input is a member like any other
    assert t["Main.x"] == [3, 3, 3]


QUIET_DRIVE = (
    DRIVES
    + """
FUNCTION_BLOCK Quiet EXTENDS Drive
END_FUNCTION_BLOCK
PROGRAM Main
VAR q : Quiet; END_VAR
q(speed := 5);
q.Run();
END_PROGRAM
"""
)


def test_a_derived_block_without_body_runs_none_and_a_base_method_sees_it(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, QUIET_DRIVE, 2)
    assert t["Main.q.log"] == [1, 11]  # its own (empty) body: the base's is not run


def test_the_refusals_of_methods_and_inheritance() -> None:
    source = """
FUNCTION_BLOCK ABSTRACT A
METHOD PUBLIC FINAL F : INT
END_METHOD
METHOD PUBLIC ABSTRACT G : INT
END_METHOD
METHOD PRIVATE P
END_METHOD
METHOD Q
END_METHOD
METHOD PUBLIC NoResult
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
METHOD PUBLIC F : INT
END_METHOD
METHOD PUBLIC G : BOOL
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK C EXTENDS D
END_FUNCTION_BLOCK
FUNCTION_BLOCK D EXTENDS C
END_FUNCTION_BLOCK
FUNCTION_BLOCK E EXTENDS Nothing
END_FUNCTION_BLOCK
PROGRAM Main
VAR a : A; b : B; x : INT; t : TON; END_VAR
b.P();
b.Q();
x := b.NoResult();
b.Missing();
x := THIS;
SUPER^();
x := t.Elapsed();
END_PROGRAM
"""
    found = diagnostics(source)
    expected = [
        "t.st:15:15: error: method 'F' of 'A' is FINAL [E0129]",
        "t.st:17:15: error: method 'G' overrides the one of 'A' with other parameters or "
        "another result type [E0132]",
        "t.st:22:1: error: 'D' extends itself through 'C' [E0128]",
        "t.st:24:1: error: 'E' extends 'Nothing', which is no function block [E0127]",
        "t.st:27:5: error: 'a': 'A' is ABSTRACT and has no instances [E0130]",
        "t.st:28:3: error: method 'P' of 'A' is PRIVATE [E0414]",
        "t.st:29:3: error: method 'Q' of 'A' is PROTECTED (IEC 61131-3 makes a method without "
        "access specifier PROTECTED; declare it METHOD PUBLIC to call it from outside) [E0414]",
        "t.st:30:8: error: method 'NoResult' has no result; call it as a statement [E0415]",
        "t.st:31:3: error: 'Missing' is no method of what it is called on [E0416]",
        "t.st:32:6: error: type mismatch: cannot assign REF_TO Main to INT [E0209]",
        "t.st:33:1: error: SUPER exists only in a block that extends another and its methods "
        "[E0221]",
        "t.st:34:8: error: 'Elapsed' is no method of what it is called on [E0416]",
    ]
    for line in expected:
        assert line in found, (line, found)


def test_protected_methods_are_called_from_derived_blocks() -> None:
    source = (
        DRIVES
        + """
FUNCTION_BLOCK Helper
METHOD Inner : INT
Inner := 7;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Special EXTENDS Helper
VAR v : INT; END_VAR
v := Inner() + THIS^.Inner();
END_FUNCTION_BLOCK
PROGRAM Main
VAR s : Special; END_VAR
s();
END_PROGRAM
"""
    )
    assert [d for d in diagnostics(source) if "error" in d] == []


MACHINES = """
INTERFACE IRunnable
METHOD Run : INT
VAR_INPUT k : INT; END_VAR
END_METHOD
END_INTERFACE
INTERFACE INamed EXTENDS IRunnable
METHOD Code : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK Mixer IMPLEMENTS INamed
VAR n : INT; END_VAR
METHOD PUBLIC Run : INT
VAR_INPUT k : INT; END_VAR
n := n + k;
Run := n;
END_METHOD
METHOD PUBLIC Code : INT
Code := 1;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK FastMixer EXTENDS Mixer
METHOD PUBLIC OVERRIDE Run : INT
VAR_INPUT k : INT; END_VAR
n := n + 100 * k;
Run := n;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Valve
END_FUNCTION_BLOCK
"""


MACHINES_THROUGH_AN_INTERFACE = (
    MACHINES
    + """
PROGRAM Main
VAR slow : Mixer; fast : FastMixer; i : IRunnable; k, r : INT; END_VAR
k := k + 1;
IF k MOD 2 = 1 THEN i := slow; ELSE i := fast; END_IF;
r := i.Run(1);
END_PROGRAM
"""
)


def test_calls_through_an_interface_dispatch_on_the_instance_assigned(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, MACHINES_THROUGH_AN_INTERFACE, 4)
    assert t["Main.i"] == ["Main.slow", "Main.fast", "Main.slow", "Main.fast"]
    assert t["Main.r"] == [1, 100, 2, 200]
    assert t["Main.slow.n"] == [1, 1, 2, 2]
    assert t["Main.fast.n"] == [0, 100, 100, 200]


MACHINES_THROUGH_A_REFERENCE = (
    MACHINES
    + """
PROGRAM Main
VAR slow : Mixer; fast : FastMixer; r : REF_TO Mixer; k, got : INT; END_VAR
k := k + 1;
IF k = 1 THEN r := REF(slow); ELSE r := REF(fast); END_IF;
got := r^.Run(2);
END_PROGRAM
"""
)


def test_a_reference_to_a_base_block_calls_the_override(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, MACHINES_THROUGH_A_REFERENCE, 3)
    assert t["Main.r"] == ["Main.slow", "Main.fast", "Main.fast"]
    assert t["Main.got"] == [2, 200, 400]


MACHINES_ATTEMPTED = (
    MACHINES
    + """
PROGRAM Main
VAR slow : Mixer; fast : FastMixer; i : IRunnable; named : INamed; k : INT;
    asFast : REF_TO FastMixer; asValve : REF_TO Valve; valve : Valve; code : INT; END_VAR
k := k + 1;
IF k = 1 THEN i := slow; ELSIF k = 2 THEN i := fast; ELSE i := NULL; END_IF;
named ?= i;             (* both implement INamed *)
asFast ?= i;            (* only fast is a FastMixer *)
asValve ?= valve;
IF named <> NULL THEN code := named.Code(); ELSE code := -1; END_IF;
END_PROGRAM
"""
)


def test_an_assignment_attempt_gives_null_where_the_instance_does_not_fit(
    tmp_path: Path,
) -> None:
    t = sim_trace(tmp_path, MACHINES_ATTEMPTED, 3)
    assert t["Main.named"] == ["Main.slow", "Main.fast", "NULL"]
    assert t["Main.asFast"] == ["NULL", "Main.fast", "NULL"]
    assert t["Main.asValve"] == ["Main.valve"] * 3
    assert t["Main.code"] == [1, 1, -1]


MACHINES_UNASSIGNED = (
    MACHINES
    + """
PROGRAM Main
VAR i : IRunnable; r : INT; END_VAR
r := i.Run(1);
END_PROGRAM
"""
)


def test_a_call_through_an_unassigned_interface_is_a_program_error(tmp_path: Path) -> None:
    path = tmp_path / "sim.st"
    path.write_text(MACHINES_UNASSIGNED)
    run = padt("sim", str(path), "--cycles", "2")
    assert run.returncode == 3
    assert "dereference of NULL in POU Main" in run.stderr and "sim.st:34)" in run.stderr


def test_the_refusals_of_interfaces() -> None:
    source = """
INTERFACE IRun
METHOD Run : INT
END_METHOD
METHOD Stop
END_METHOD
END_INTERFACE
INTERFACE IBad EXTENDS Nope
METHOD Go
Go();
END_METHOD
END_INTERFACE
FUNCTION_BLOCK A IMPLEMENTS IRun, Missing
METHOD PUBLIC Run : BOOL
END_METHOD
METHOD Stop
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK C
END_FUNCTION_BLOCK
PROGRAM Main
VAR a : A; c : C; i : IRun; x : INT; END_VAR
i := c;
i ?= x;
i.Fly();
END_PROGRAM
"""
    found = diagnostics(source)
    expected = [
        "t.st:8:11: error: 'IBad' extends 'Nope', which is no interface [E0133]",
        "t.st:9:8: error: method 'Go' of an interface has no body [E0134]",
        "t.st:13:1: error: 'A' implements 'Missing', which is no interface [E0133]",
        "t.st:13:1: error: method 'Run' of interface 'IRun': 'A' implements it with other "
        "parameters or another result type [E0134]",
        "t.st:13:1: error: method 'Stop' of interface 'IRun': 'A' implements it PROTECTED; "
        "an interface's methods are PUBLIC [E0134]",
        "t.st:23:6: error: type mismatch: cannot assign C to IRun [E0209]",
        "t.st:24:1: error: ?= assigns an instance, an interface or a reference to an instance "
        "to an interface or a REF_TO a function block [E0209]",
        "t.st:25:3: error: 'Fly' is no method of what it is called on [E0416]",
    ]
    for line in expected:
        assert line in found, (line, found)


MOTOR = """
FUNCTION_BLOCK Motor
VAR speed : INT; limit : INT := 100; writes : INT; END_VAR
PROPERTY PUBLIC Velocity : INT
GET
  Velocity := speed;
END_GET
SET
  VAR clipped : INT; END_VAR
  clipped := MIN(Velocity, limit);
  speed := clipped;
  writes := writes + 1;
END_SET
END_PROPERTY
PROPERTY PUBLIC MaxSpeed : INT
GET
  MaxSpeed := limit;
END_GET
END_PROPERTY
speed := speed + 1;
IF Velocity > 50 THEN Velocity := 10; END_IF;  (* inside the block: by its name *)
END_FUNCTION_BLOCK
"""


MOTOR_CALLS = (
    MOTOR
    + """
PROGRAM Main
VAR m : Motor; k, seen, most : INT; END_VAR
k := k + 1;
m();
IF k = 2 THEN m.Velocity := 500; END_IF;
seen := m.Velocity;
most := m.MaxSpeed;
END_PROGRAM
"""
)


def test_a_property_runs_its_get_when_read_and_its_set_when_written(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, MOTOR_CALLS, 4)
    # cycle 2: the SET clips 500 to the limit; cycle 3: the body's own write sets 10
    assert t["Main.m.speed"] == [1, 100, 10, 11]
    assert t["Main.seen"] == [1, 100, 10, 11]
    assert t["Main.m.writes"] == [0, 1, 2, 2]
    assert t["Main.most"] == [100] * 4
    assert "Main.m.Velocity" not in t and "Main.m.clipped" not in t  # no variables


BOX = """FUNCTION_BLOCK Box
VAR v : INT; set : BOOL; END_VAR
METHOD PUBLIC Get : INT
VAR n : INT; END_VAR
Get := v + 1;
END_METHOD
METHOD PUBLIC Put
VAR_INPUT x : INT; END_VAR
VAR get : INT; END_VAR
get := x;
v := get;
set := TRUE;
END_METHOD
PROPERTY PUBLIC Value : INT
GET
Value := v * 10;
END_GET
SET // the value written
v := Value;
END_SET
END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM Main
VAR b : Box; r : INT; set, get : INT; END_VAR
set := set + 1;
b.Put(x := set);
r := b.Get();
get := b.Value;
IF set = 2 THEN b.Value := 7; END_IF;
END_PROGRAM
"""


def test_get_and_set_are_names_outside_a_property(tmp_path: Path) -> None:
    """GET and SET begin a property's accessor only there: a method called Get assigns its
    result (`Get := ...;` right after its VAR block), variables may be called get and set,
    and the property beside them still has its accessors."""
    trace = sim_trace(tmp_path, BOX, 3)
    assert trace["Main.r"] == [2, 3, 4]
    assert trace["Main.get"] == [10, 20, 30]
    assert trace["Main.b.set"] == [True, True, True]
    assert trace["Main.b.v"] == [1, 7, 3]
    assert not [d for d in diagnostics(BOX) if "error" in d]


TANKS = """
INTERFACE IGauge
PROPERTY Value : INT
GET END_GET
END_PROPERTY
END_INTERFACE
INTERFACE ISettable EXTENDS IGauge
PROPERTY Value : INT
GET END_GET
SET END_SET
END_PROPERTY
END_INTERFACE
FUNCTION_BLOCK Tank IMPLEMENTS ISettable
VAR fill : INT; END_VAR
PROPERTY PUBLIC Value : INT
GET Value := fill; END_GET
SET fill := Value; END_SET
END_PROPERTY
END_FUNCTION_BLOCK
FUNCTION_BLOCK BigTank EXTENDS Tank
PROPERTY PUBLIC Value : INT
GET Value := 1000 + SUPER^.Value; END_GET
SET SUPER^.Value := Value * 2; END_SET
END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM Main
VAR t : Tank; b : BigTank; g : IGauge; s : ISettable; x : INT; k : INT; END_VAR
k := k + 1;
IF k = 1 THEN s := t; ELSE s := b; END_IF;
g := s;
s.Value := s.Value + 1;
x := g.Value;
END_PROGRAM
"""


def test_properties_through_interfaces_overrides_and_super(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, TANKS, 3)
    assert t["Main.g"] == ["Main.t", "Main.b", "Main.b"]
    assert t["Main.t.fill"] == [1, 1, 1]
    # BigTank reads 1000 + fill and stores twice what it is given: (1000 + 0 + 1) * 2
    assert t["Main.b.fill"] == [0, 2002, 6006]
    assert t["Main.x"] == [1, 3002, 7006]


def test_the_refusals_of_properties() -> None:
    source = """
INTERFACE ISettable
PROPERTY Value : INT
GET END_GET
SET END_SET
END_PROPERTY
END_INTERFACE
TYPE P : STRUCT x : INT; END_STRUCT END_TYPE
FUNCTION_BLOCK Tank
VAR p0 : P; END_VAR
PROPERTY PRIVATE Secret : INT
GET Secret := 1; END_GET
END_PROPERTY
PROPERTY PUBLIC RO : INT
GET RO := 1; END_GET
END_PROPERTY
PROPERTY PUBLIC WO : INT
SET p0.x := WO; END_SET
END_PROPERTY
PROPERTY PUBLIC Pt : P
GET Pt := p0; END_GET
SET p0 := Pt; END_SET
END_PROPERTY
END_FUNCTION_BLOCK
FUNCTION_BLOCK Bad IMPLEMENTS ISettable
PROPERTY PUBLIC Value : INT
GET Value := 1; END_GET
END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM Main
VAR t : Tank; b : Bad; x : INT; r : REF_TO INT; END_VAR
x := t.Secret;
t.RO := 3;
x := t.WO;
t.Pt.x := 5;
r := REF(t.RO);
END_PROGRAM
"""
    found = diagnostics(source)
    expected = [
        "t.st:25:1: error: property 'Value' of interface 'ISettable': 'Bad' implements it "
        "without the GET or SET the interface declares [E0134]",
        "t.st:32:6: error: property 'Secret' of 'Tank' is PRIVATE [E0414]",
        "t.st:33:1: error: property 'RO' is read-only: it has no SET [E0313]",
        "t.st:34:6: error: property 'WO' is write-only: it has no GET [E0313]",
        "t.st:35:1: error: a property is written whole: read it, change the copy, write it "
        "back [E0313]",
        "t.st:36:6: error: REF of a property, which is no variable [E0219]",
    ]
    for line in expected:
        assert line in found, (line, found)


TEMPORARIES_AND_METHODS = """
FUNCTION_BLOCK F
VAR_TEMP t : INT; END_VAR
VAR n : INT; END_VAR
METHOD PUBLIC Two : INT
Two := 2;
END_METHOD
t := Two();
n := n + t;
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : F; END_VAR
f();
END_PROGRAM
"""


def test_a_block_with_temporaries_and_methods_compiles_and_runs(tmp_path: Path) -> None:
    assert sim_trace(tmp_path, TEMPORARIES_AND_METHODS, 2)["Main.f.n"] == [2, 4]


def test_a_global_a_method_writes_is_written_by_each_program_that_calls_it() -> None:
    source = """
VAR_GLOBAL g : INT; END_VAR
FUNCTION_BLOCK F
VAR_EXTERNAL g : INT; END_VAR
METHOD PUBLIC Bump
g := g + 1;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Pump
VAR_EXTERNAL g : INT; END_VAR
METHOD PUBLIC Reset
g := 0;
END_METHOD
END_PROGRAM
PROGRAM A
VAR f : F; END_VAR
f.Bump();
END_PROGRAM
PROGRAM B
Pump.Reset();
END_PROGRAM
"""
    found = [d for d in diagnostics(source) if "[E0606]" in d]
    assert found == [
        "t.st:12:1: error: global 'g' is written by the user programs Pump, A, B; global data "
        "must have one writer [E0606]"
    ]


HALF_TON = """
FUNCTION_BLOCK HalfTon EXTENDS TON
VAR_OUTPUT half : BOOL; END_VAR
SUPER^();                 (* the timer itself *)
half := ET >= PT / 2;
END_FUNCTION_BLOCK
PROGRAM Main
VAR t : HalfTon; END_VAR
t(IN := TRUE, PT := T#400ms);
END_PROGRAM
"""


def test_a_block_extends_a_standard_function_block(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, HALF_TON, 6)
    assert t["Main.t.ET"] == [0, 100, 200, 300, 400, 400]
    assert t["Main.t.half"] == [False, False, True, True, True, True]
    assert t["Main.t.Q"] == [False, False, False, False, True, True]


PRIMED_PUMP = """
FUNCTION_BLOCK Pump
VAR strokes : INT; END_VAR
METHOD PUBLIC Prime
Stroke();
Stroke();
END_METHOD
ACTION Stroke:
  strokes := strokes + 1;
END_ACTION
END_FUNCTION_BLOCK
PROGRAM Main
VAR p : Pump; END_VAR
p.Prime();
END_PROGRAM
"""


def test_a_method_calls_an_action_of_its_block(tmp_path: Path) -> None:
    assert sim_trace(tmp_path, PRIMED_PUMP, 2)["Main.p.strokes"] == [2, 4]


TWINCAT_ORDER = """
INTERFACE I_Counter
END_INTERFACE

METHOD Tick : INT
END_METHOD

FUNCTION_BLOCK FB_Counter
VAR
    iLast : INT;
    calls : INT;
END_VAR
calls := calls + 1;
END_FUNCTION_BLOCK

METHOD PUBLIC Tick : INT
iLast := iLast + 1;
Tick := iLast;
END_METHOD

PROPERTY PUBLIC Count : INT
GET
Count := calls;
END_GET
END_PROPERTY

FUNCTION_BLOCK FB_Ten IMPLEMENTS I_Counter
VAR n : INT; END_VAR
END_FUNCTION_BLOCK

METHOD PUBLIC Tick : INT
n := n + 10;
Tick := n;
END_METHOD

PROGRAM Main
VAR fb : FB_Counter; ten : FB_Ten; c : I_Counter; a, b : INT; END_VAR
fb();
a := fb.Tick() + fb.Count;
c := ten;
b := c.Tick();
END_PROGRAM
"""


def test_methods_and_properties_after_the_block_as_twincat_writes_them(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, TWINCAT_ORDER, 2)
    assert t["Main.a"] == [2, 4]
    assert t["Main.b"] == [10, 20]
    orphan = "METHOD PUBLIC Start\nEND_METHOD\n" + TWINCAT_ORDER
    assert diagnostics(orphan) == [
        "t.st:1:15: error: method 'Start' follows no FUNCTION_BLOCK, PROGRAM or INTERFACE [E0135]"
    ]


LISTENER = """
INTERFACE IListener
METHOD Notify
VAR_INPUT v : INT; END_VAR
END_METHOD
END_INTERFACE
FUNCTION_BLOCK Bus
VAR listener : IListener; END_VAR
METHOD PUBLIC Subscribe
VAR_INPUT who : IListener; END_VAR
listener := who;
END_METHOD
METHOD PUBLIC Send
VAR_INPUT v : INT; END_VAR
IF listener <> NULL THEN listener.Notify(v); END_IF;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Display IMPLEMENTS IListener
VAR shown : INT; me : REF_TO Display; field : REF_TO INT; END_VAR
METHOD PUBLIC Notify
VAR_INPUT v : INT; END_VAR
shown := v;
END_METHOD
METHOD PUBLIC Attach
VAR_IN_OUT bus : Bus; END_VAR
bus.Subscribe(THIS^);      (* the instance, as the interface it implements *)
me := THIS;                (* THIS alone: a REF_TO the block *)
field := REF(THIS^.shown);
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR bus : Bus; d : Display; k : INT; END_VAR
k := k + 1;
IF k = 1 THEN d.Attach(bus); END_IF;
bus.Send(k * 7);
END_PROGRAM
"""


def test_an_instance_hands_itself_over_as_this(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, LISTENER, 2)
    assert t["Main.bus.listener"] == ["Main.d", "Main.d"]
    assert t["Main.d.shown"] == [7, 14]
    assert t["Main.d.me"] == ["Main.d", "Main.d"]
    assert t["Main.d.field"] == ["Main.d.shown", "Main.d.shown"]


ACCUMULATOR = """
FUNCTION_BLOCK Acc
VAR total : DINT; END_VAR
METHOD PUBLIC SumTo : DINT
VAR_INPUT n : INT; END_VAR
VAR_IN_OUT calls : INT; END_VAR
VAR i : INT; END_VAR
FOR i := 1 TO n DO
  SumTo := SumTo + i;
END_FOR;
calls := calls + 1;
total := total + SumTo;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR a : Acc; c : INT; r : DINT; go : BOOL; END_VAR
r := a.SumTo(n := 4, calls := c);
a.SumTo(n := 2, calls := c, EN := go);   (* runs from cycle 2 on *)
END_PROGRAM
"""


def test_a_method_with_an_in_out_a_loop_and_en(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, ACCUMULATOR, 3, "Main.go=TRUE@2")
    assert t["Main.r"] == [10, 10, 10]  # the result starts at 0 in every call
    assert t["Main.c"] == [1, 3, 5]
    assert t["Main.a.total"] == [10, 23, 36]


GENERATIONS = """
FUNCTION_BLOCK Zeta
VAR n : INT; END_VAR
METHOD PUBLIC Step : INT
n := n + 1;
Step := n;
END_METHOD
METHOD PUBLIC Twice : INT
Twice := 2 * Step();
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Mid EXTENDS Zeta
METHOD PUBLIC OVERRIDE Step : INT
n := n + 10;
Step := n;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Alpha EXTENDS Mid
END_FUNCTION_BLOCK
PROGRAM Main
VAR a : Alpha; r : INT; END_VAR
r := a.Twice();     (* Zeta's Twice, Mid's Step *)
END_PROGRAM
"""


def test_three_generations_whose_names_sort_against_their_order(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, GENERATIONS, 2)
    assert t["Main.r"] == [20, 40]
    assert t["Main.a.n"] == [10, 20]


VARIABLE_LENGTH_ARRAY = """
FUNCTION_BLOCK A
VAR calls : INT; END_VAR
METHOD PUBLIC Sum : INT
VAR_INPUT x : ARRAY[*] OF INT; END_VAR
VAR i : DINT; END_VAR
FOR i := LOWER_BOUND(x, 1) TO UPPER_BOUND(x, 1) DO Sum := Sum + x[i]; END_FOR;
calls := calls + 1;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR a : A; v : ARRAY[1..3] OF INT := [1, 2, 3]; w : ARRAY[0..1] OF INT := [10, 20];
    r : INT; END_VAR
r := a.Sum(v) + a.Sum(x := w);
END_PROGRAM
"""


def test_a_method_takes_a_variable_length_array(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, VARIABLE_LENGTH_ARRAY, 1)
    assert (t["Main.r"], t["Main.a.calls"]) == ([36], [2])


CALLED_THROUGH_A_REFERENCE = """
FUNCTION_BLOCK Cnt
VAR_INPUT step : INT := 1; END_VAR
VAR_OUTPUT n : INT; END_VAR
n := n + step;
END_FUNCTION_BLOCK
PROGRAM Main
VAR a, b : Cnt; r : REF_TO Cnt; k, out : INT; END_VAR
k := k + 1;
IF k MOD 2 = 1 THEN r := REF(a); ELSE r := REF(b); END_IF;
r^(step := 10, n => out);
END_PROGRAM
"""


def test_a_block_called_through_a_reference(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, CALLED_THROUGH_A_REFERENCE, 3)
    assert t["Main.a.n"] == [10, 10, 20]
    assert t["Main.b.n"] == [0, 10, 10]
    assert t["Main.out"] == [10, 10, 20]
    refusals = """
PROGRAM Main
VAR r : REF_TO INT; END_VAR
r^(1);
THIS^();
END_PROGRAM
FUNCTION_BLOCK B
END_FUNCTION_BLOCK
FUNCTION_BLOCK D EXTENDS B
SUPER^(1);
END_FUNCTION_BLOCK
"""
    assert diagnostics(refusals) == [
        "t.st:4:1: error: r^() calls the function block r refers to, not a value of type INT "
        "[E0218]",
        "t.st:5:1: error: THIS^() would run the block's body from inside it: call a method [E0221]",
        "t.st:10:8: error: SUPER^() runs the base's body: it takes no arguments [E0221]",
    ]


CALLED_THROUGH_A_REFERENCE_TO = """
FUNCTION_BLOCK Cnt
VAR_INPUT step : INT := 1; END_VAR
VAR_OUTPUT n : INT; END_VAR
n := n + step;
END_FUNCTION_BLOCK
PROGRAM Main
VAR a : Cnt; ref : REFERENCE TO Cnt; END_VAR
ref REF= a;
ref(step := 2);
END_PROGRAM
"""


def test_a_block_called_through_a_reference_to_of_codesys(tmp_path: Path) -> None:
    assert sim_trace(tmp_path, CALLED_THROUGH_A_REFERENCE_TO, 2)["Main.a.n"] == [2, 4]


def test_a_derived_block_cannot_reuse_its_bases_names() -> None:
    source = """
FUNCTION_BLOCK B
VAR x : INT; END_VAR
METHOD PUBLIC M
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK D EXTENDS B
VAR m : INT; END_VAR
METHOD PUBLIC X
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR d : D; END_VAR
END_PROGRAM
"""
    assert diagnostics(source) == [
        "t.st:8:5: error: 'm' is a method or property of 'B' [E0126]",
        "t.st:9:15: error: 'x' is a variable of 'B' (declared at t.st:3:5) [E0126]",
    ]


INTERFACE_OUTPUTS = """
INTERFACE IBase
END_INTERFACE
INTERFACE IMore EXTENDS IBase
END_INTERFACE
FUNCTION_BLOCK Impl IMPLEMENTS IMore
END_FUNCTION_BLOCK
FUNCTION_BLOCK Giver
VAR_OUTPUT out : IMore; END_VAR
VAR own : Impl; END_VAR
METHOD PUBLIC Give
VAR_OUTPUT o : IMore; END_VAR
o := own;
END_METHOD
out := own;
END_FUNCTION_BLOCK
PROGRAM Main
VAR g : Giver; b, c : IBase; END_VAR
g(out => b);
g.Give(o => c);
END_PROGRAM
"""


def test_an_interface_output_goes_to_an_interface_it_extends(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, INTERFACE_OUTPUTS, 1)
    assert (t["Main.b"], t["Main.c"]) == (["Main.g.own"], ["Main.g.own"])
