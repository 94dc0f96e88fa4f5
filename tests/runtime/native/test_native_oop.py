"""Object orientation on the native tier (the runtime's default) and on the Python tier
(`padt sim`): SUPER^() of a base's body, SUPER^.method(), THIS^, three generations,
overrides called from a base's body, properties of a base, interfaces and references to a
base: every variable identical after every cycle, no fault, and the values the language
gives. Real C compiles, real resources on virtual clocks."""

from __future__ import annotations

import pytest

from runtime.code.native.tier import NativeTier
from tests.support.native_runs import Pair, program_error, side_by_side


def run_alike(text: str, tier: NativeTier, cycles: int) -> Pair:
    pair = side_by_side(text, tier)
    pair.cycle_and_compare(cycles)
    assert not program_error(pair.python), program_error(pair.python)
    assert not program_error(pair.native), program_error(pair.native)
    return pair


def values(pair: Pair) -> dict[str, object]:
    return pair.native.variables.values()


CHAIN = """
FUNCTION_BLOCK Base
VAR_INPUT step : INT := 1; END_VAR
VAR_OUTPUT n, codes : INT; END_VAR
VAR edge : R_TRIG; up : BOOL; END_VAR
METHOD PUBLIC Code : INT
Code := 1;
END_METHOD
METHOD PUBLIC Count
codes := codes + THIS^.Code();   (* the instance's own Code: an override from the base *)
END_METHOD
up := NOT up;
edge(CLK := up);
IF edge.Q THEN n := n + step; END_IF;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Mid EXTENDS Base
VAR m : INT; END_VAR
METHOD PUBLIC OVERRIDE Code : INT
Code := 10 + SUPER^.Code();
END_METHOD
SUPER^();
m := m + n;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Top EXTENDS Mid
VAR t : INT; END_VAR
METHOD PUBLIC OVERRIDE Code : INT
Code := 100 + SUPER^.Code();
END_METHOD
t := t + 1;
SUPER^();
END_FUNCTION_BLOCK
PROGRAM Main
VAR b : Base; m : Mid; t : Top; END_VAR
b(step := 1);
m(step := 2);
t(step := 3);
b.Count(); m.Count(); t.Count();
END_PROGRAM
"""


def test_a_base_body_called_with_super_runs_on_both_tiers(native_tier: NativeTier) -> None:
    pair = run_alike(CHAIN, native_tier, 4)
    assert "Base" in pair.report.bodies  # as C: called as the others' SUPER^()
    assert "Main" in pair.report.bodies  # its calls of Count look the method up, as Python
    found = values(pair)
    # the edge every other cycle: n grows by the step in cycles 1 and 3
    assert [found["Main.b.n"], found["Main.m.n"], found["Main.t.n"]] == [2, 4, 6]
    assert found["Main.m.m"] == 2 + 2 + 4 + 4  # after each SUPER^(): n of that cycle
    assert found["Main.t.m"] == 3 + 3 + 6 + 6 and found["Main.t.t"] == 4
    # the base's Count calls THIS^.Code(): Base 1, Mid 11, Top 111, each cycle
    assert [found["Main.b.codes"], found["Main.m.codes"], found["Main.t.codes"]] == [4, 44, 444]


OVERRIDE_FROM_THE_BODY = """
FUNCTION_BLOCK Tank
VAR_OUTPUT level : REAL; END_VAR
METHOD PUBLIC Fill : REAL
VAR_INPUT amount : REAL; END_VAR
level := level + amount;
Fill := amount;
END_METHOD
Fill(1.0);
THIS^.Fill(1.0);
END_FUNCTION_BLOCK
FUNCTION_BLOCK BigTank EXTENDS Tank
METHOD PUBLIC Fill : REAL
VAR_INPUT amount : REAL; END_VAR
level := level + 10.0 * amount;
Fill := amount;
END_METHOD
SUPER^();
END_FUNCTION_BLOCK
PROGRAM Main
VAR t : Tank; b : BigTank; END_VAR
t(); b();
END_PROGRAM
"""


# the override reached through a method the derived block does not override
THROUGH_A_METHOD = OVERRIDE_FROM_THE_BODY.replace(
    "Fill(1.0);\nTHIS^.Fill(1.0);", "METHOD PUBLIC Run\nFill(1.0);\nEND_METHOD\nRun();\nRun();"
)


@pytest.mark.parametrize("text", [OVERRIDE_FROM_THE_BODY, THROUGH_A_METHOD])
def test_a_base_body_calling_an_overridden_method_takes_the_override_on_both_tiers(
    native_tier: NativeTier, text: str
) -> None:
    """The base's body, run on a derived instance by its SUPER^(), calls the derived
    block's Fill (directly, or through a method of its own). In native memory the bytes
    do not say whose instance they are (the C called the base's Fill there: 2.0 where
    20.0 is right), so such a configuration stays on objects, and says why."""
    pair = run_alike(text, native_tier, 3)
    assert (values(pair)["Main.t.level"], values(pair)["Main.b.level"]) == (6.0, 60.0)
    assert "a derived block overriding M__FILL" in pair.report.memory


def test_methods_with_outputs_and_properties_are_called_from_c_a_fault_in_one_named(
    native_tier: NativeTier,
) -> None:
    text = """
FUNCTION_BLOCK Tank
VAR level : REAL; high : REAL := 10.0; calls : INT; END_VAR
METHOD PUBLIC Fill : BOOL
VAR_INPUT amount : REAL; END_VAR
VAR_OUTPUT over : REAL; END_VAR
level := level + amount;
over := MAX(level - high, 0.0);
Fill := over = 0.0;
calls := calls + 1;
END_METHOD
METHOD PUBLIC Ratio : INT
VAR_INPUT d : INT; END_VAR
Ratio := REAL_TO_INT(level) / d;
END_METHOD
PROPERTY PUBLIC Limit : REAL
GET Limit := high; END_GET
SET high := Limit; END_SET
END_PROPERTY
END_FUNCTION_BLOCK
FUNCTION_BLOCK BigTank EXTENDS Tank
VAR_OUTPUT own, base : INT; END_VAR
METHOD PUBLIC OVERRIDE Ratio : INT
VAR_INPUT d : INT; END_VAR
Ratio := 1000 + d;
END_METHOD
own := THIS^.Ratio(2);
base := SUPER^.Ratio(d := 1);
END_FUNCTION_BLOCK
PROGRAM Main
VAR t : Tank; big : BigTank; ok : BOOL; over : REAL; n, r : INT; cap : REAL; END_VAR
n := n + 1;
big.Fill(amount := 4.0);
big();
ok := t.Fill(amount := 2.5, over => over);
t.Fill(1.0);
IF n = 3 THEN t.Limit := 20.0; END_IF;
cap := t.Limit;
r := t.Ratio(d := 5 - n);
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert set(pair.report.bodies) >= {"Main", "BigTank"}
    pair.cycle_and_compare(4)  # n = 5 in the fifth cycle: Ratio divides by zero
    found = values(pair)
    assert (found["Main.t.calls"], found["Main.cap"], found["Main.ok"]) == (8, 20.0, True)
    assert (found["Main.big.own"], found["Main.big.base"]) == (1002, 16)  # its level 16.0
    assert "division by zero in POU Tank (prog.st:14)" in pair.fault_of_the_next_cycle()


def test_a_block_extending_a_standard_block_runs_its_timer_on_both_tiers(
    native_tier: NativeTier,
) -> None:
    text = """
FUNCTION_BLOCK HalfTon EXTENDS TON
VAR_OUTPUT half : BOOL; END_VAR
SUPER^();
half := ET >= PT / 2;
END_FUNCTION_BLOCK
PROGRAM Main
VAR t : HalfTon; END_VAR
t(IN := TRUE, PT := T#400ms);
END_PROGRAM
"""
    pair = run_alike(text, native_tier, 6)
    assert "TON" in pair.report.bodies
    assert values(pair)["Main.t.Q"] is True and values(pair)["Main.t.half"] is True


def test_properties_interfaces_and_references_to_a_base_run_on_both_tiers(
    native_tier: NativeTier,
) -> None:
    text = """
INTERFACE IGauge
PROPERTY Value : INT
GET END_GET
END_PROPERTY
METHOD Run : INT
VAR_INPUT k : INT; END_VAR
END_METHOD
END_INTERFACE
FUNCTION_BLOCK Tank IMPLEMENTS IGauge
VAR fill, calls : INT; END_VAR
PROPERTY PUBLIC Value : INT
GET Value := fill; END_GET
SET fill := Value; END_SET
END_PROPERTY
METHOD PUBLIC Run : INT
VAR_INPUT k : INT; END_VAR
fill := fill + k;
Run := fill;
END_METHOD
calls := calls + 1;
END_FUNCTION_BLOCK
FUNCTION_BLOCK BigTank EXTENDS Tank
PROPERTY PUBLIC Value : INT
GET Value := 1000 + SUPER^.Value; END_GET
SET SUPER^.Value := Value * 2; END_SET
END_PROPERTY
METHOD PUBLIC OVERRIDE Run : INT
VAR_INPUT k : INT; END_VAR
Run := SUPER^.Run(k * 100);
END_METHOD
SUPER^();
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  t : Tank; b : BigTank; g : IGauge; r : REF_TO Tank;
  k, x, y, z : INT;
END_VAR
k := k + 1;
IF k MOD 2 = 1 THEN g := t; r := REF(b); ELSE g := b; r := REF(t); END_IF;
t(); b();
x := g.Value;
y := g.Run(1);
r^();
r^.Value := 7;
z := r^.Run(2);
END_PROGRAM
"""
    pair = run_alike(text, native_tier, 4)
    found = values(pair)
    # cycle 4: g is b, r refers to t; each block's body ran 4 times, and twice through r^()
    assert found["Main.b.calls"] == 4 + 2 and found["Main.t.calls"] == 4 + 2
    assert found["Main.x"] == 1000 + 214  # BigTank's GET over its base's
    assert found["Main.y"] == found["Main.b.fill"] == 214 + 100  # its Run: SUPER^.Run(100)
    assert found["Main.z"] == 7 + 2  # Tank's SET, then its Run


ANIMALS = """
INTERFACE ISpeaker
METHOD Speak : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK Animal IMPLEMENTS ISpeaker
VAR_INPUT sound : INT; END_VAR
VAR_OUTPUT legs : INT; END_VAR
METHOD PUBLIC Speak : INT
Speak := 1;
END_METHOD
legs := 4;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Dog EXTENDS Animal
VAR barks : INT; END_VAR
METHOD PUBLIC OVERRIDE Speak : INT
Speak := 2;
END_METHOD
barks := barks + 1;
SUPER^();
END_FUNCTION_BLOCK
FUNCTION_BLOCK Vet
VAR_IN_OUT patient : Animal; END_VAR
VAR_OUTPUT heard, legs : INT; END_VAR
METHOD PUBLIC Listen
heard := patient.Speak();   (* dispatched on what it is *)
END_METHOD
legs := patient.legs;       (* a member of the base, on whatever instance it is *)
patient.sound := patient.sound + 1;
patient();                  (* the instance's own body *)
END_FUNCTION_BLOCK
FUNCTION Hear : INT
VAR_IN_OUT a : Animal; s : ISpeaker; END_VAR
a.sound := a.sound + 10;
Hear := a.Speak() * 10 + s.Speak();
END_FUNCTION
PROGRAM Main
VAR d : Dog; a : Animal; v, w : Vet; i : ISpeaker; x, y, z, l : INT; END_VAR
v(patient := d);
w(patient := a);
v.Listen(); w.Listen();
x := v.heard * 10 + w.heard;
l := v.legs;
i := d;
y := Hear(d, i);
z := Hear(a := a, s := i);
END_PROGRAM
"""


def test_a_derived_instance_is_an_in_out_of_its_base_type_on_both_tiers(
    native_tier: NativeTier,
) -> None:
    pair = run_alike(ANIMALS, native_tier, 3)
    # an in-out of a block that another extends may hold either: its members are read by
    # name, as Python
    assert "Vet" not in pair.report.bodies
    assert any("patient" in reason for pou, reason in pair.report.left if pou == "Vet")
    assert "Main" not in pair.report.bodies  # it binds v's patient
    found = values(pair)
    assert found["Main.x"] == 2 * 10 + 1  # Dog's Speak through v, Animal's through w
    assert found["Main.y"] == 2 * 10 + 2 and found["Main.z"] == 1 * 10 + 2
    assert found["Main.d.barks"] == 3 and found["Main.l"] == 4
    assert found["Main.d.sound"] == 3 * 11 and found["Main.a.sound"] == 3 * 11


def test_an_in_out_of_a_block_nobody_extends_is_read_as_c(native_tier: NativeTier) -> None:
    text = """
FUNCTION_BLOCK Tank
VAR_INPUT fill : INT; END_VAR
END_FUNCTION_BLOCK
FUNCTION_BLOCK Pump
VAR_IN_OUT tank : Tank; END_VAR
tank.fill := tank.fill + 1;
END_FUNCTION_BLOCK
PROGRAM Main
VAR t : Tank; p : Pump; END_VAR
p(tank := t);
END_PROGRAM
"""
    pair = run_alike(text, native_tier, 3)
    assert "Pump" in pair.report.bodies
    assert values(pair)["Main.t.fill"] == 3


def test_a_function_in_out_is_the_instance_itself_not_a_copy(native_tier: NativeTier) -> None:
    text = """
FUNCTION_BLOCK Animal
VAR_INPUT sound : INT; END_VAR
METHOD PUBLIC Speak : INT
Speak := sound;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Dog EXTENDS Animal
METHOD PUBLIC OVERRIDE Speak : INT
Speak := 1000 + sound;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION Louder : INT
VAR_IN_OUT a : Animal; END_VAR
a.sound := a.sound + 1;
Louder := a.Speak();
END_FUNCTION
FUNCTION_BLOCK Vet
VAR_IN_OUT patient : Animal; END_VAR
VAR_OUTPUT heard : INT; END_VAR
METHOD PUBLIC Listen
heard := patient.Speak();
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR d : Dog; v : Vet; x : INT; END_VAR
v(patient := d);
x := Louder(d);      (* d itself: the vet's patient hears it in this cycle *)
v.Listen();
END_PROGRAM
"""
    pair = run_alike(text, native_tier, 3)
    found = values(pair)
    assert found["Main.x"] == 1003 and found["Main.v.heard"] == 1003
    assert found["Main.d.sound"] == found["Main.v.patient.sound"] == 3


INTERFACES = """
INTERFACE IShape
PROPERTY Sides : INT
GET END_GET
END_PROPERTY
METHOD Area : REAL
VAR_INPUT scale : REAL; END_VAR
END_METHOD
END_INTERFACE
FUNCTION_BLOCK Square IMPLEMENTS IShape
VAR_INPUT side : REAL; END_VAR
PROPERTY PUBLIC Sides : INT
GET Sides := 4; END_GET
END_PROPERTY
METHOD PUBLIC Area : REAL
VAR_INPUT scale : REAL; END_VAR
Area := side * side * scale;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Triangle IMPLEMENTS IShape
VAR_INPUT base, height : REAL; END_VAR
PROPERTY PUBLIC Sides : INT
GET Sides := 3; END_GET
END_PROPERTY
METHOD PUBLIC Area : REAL
VAR_INPUT scale : REAL; END_VAR
Area := base * height / 2.0 * scale;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  sq : Square := (side := 3.0); tr : Triangle := (base := 4.0, height := 5.0);
  shape, none : IShape; k, sides : INT; area : REAL;
END_VAR
k := k + 1;
IF k MOD 2 = 1 THEN shape := sq; ELSE shape := tr; END_IF;
sides := shape.Sides;
area := shape.Area(scale := INT_TO_REAL(k));
IF k = 5 THEN sides := none.Sides; END_IF;  (* never assigned: NULL, a fault *)
END_PROGRAM
"""


def test_methods_and_properties_through_an_interface_run_as_c(native_tier: NativeTier) -> None:
    pair = side_by_side(INTERFACES, native_tier)
    assert pair.report.bodies == ("Main", "Square", "Triangle"), pair.report.left
    pair.cycle_and_compare(4)
    found = values(pair)
    assert found["Main.sides"] == 3 and found["Main.area"] == 4.0 * 5.0 / 2.0 * 4
    assert "dereference of NULL in POU Main (prog.st:39)" in pair.fault_of_the_next_cycle()
