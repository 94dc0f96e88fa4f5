"""Drawn logic against the same logic written in ST by hand (docs/language.md, "Graphical
bodies"): each FBD and LD construct is a pair of programs, one drawn, one written, over the
same inputs; `padt sim` runs them side by side and every variable they share must be equal
after every cycle. Each drawn program also runs on the Python tier and on the native tier,
every variable equal after every cycle."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from runtime.code.native.tier import NativeTier
from runtime.contract.artifact import ProgramConfig
from tests.conftest import padt
from tests.support.native_runs import side_by_side

CYCLES = 40

# the inputs every pair reads, changed each cycle by a program that runs before them
STIMULUS = """
VAR_GLOBAL
  a, b, c : BOOL;
  i, j : INT;
  k : DINT;
END_VAR
PROGRAM Stimulus
k := k + 1;
a := (k MOD 2) = 0;
b := (k MOD 3) = 0;
c := (k MOD 5) < 2;
i := DINT_TO_INT((k * 7) MOD 23) - 11;
j := DINT_TO_INT(k MOD 4);
END_PROGRAM
"""

# (what the pair shows, the drawn program, the written one): both named by the key
PAIRS: dict[str, tuple[str, str]] = {
    # functions in a chain (kept in typed temporaries, or written into their consumer when
    # the drawing cannot tell their type), an output wired to two inputs, a negated input
    "functions": (
        """
PROGRAM Drawn_functions
VAR x, y, n : INT; z : BOOL; END_VAR
FBD
  1: IN i {at 0 0}
  2: IN j {at 0 40}
  3: BLOCK ADD (IN1 := 1, IN2 := 2) -> (OUT) {at 100 0}
  4: BLOCK MUL (IN1 := 3, IN2 := 2) -> (OUT) {at 200 0}
  5: OUT x := 4 {at 300 0}
  6: BLOCK GT (IN1 := 3, IN2 := 2) -> (OUT) {at 200 60}
  7: OUT z := NOT 6 {at 300 60}
  8: IN 3 {at 0 100}
  9: BLOCK SUB (IN1 := 8, IN2 := 1) -> (OUT) {at 100 100}
  10: OUT y := 9 {at 300 100}
  11: IN n {at 0 140}
  12: BLOCK ADD (IN1 := 11, IN2 := 2) -> (OUT) {at 100 140}
  13: BLOCK MAX (IN1 := 12, IN2 := 12) -> (OUT) {at 200 140}
  14: OUT n := 13 {at 300 140}
END_FBD
END_PROGRAM
""",
        """
PROGRAM Text_functions
VAR x, y, n : INT; z : BOOL; END_VAR
x := (i + j) * j;
z := NOT (i + j > j);
y := 3 - i;
n := MAX(n + j, n + j);
END_PROGRAM
""",
    ),
    # FB instances, an edge-sensing input pin, a negated output, EN and ENO of a FUNCTION
    # and of an FB instance
    "blocks": (
        """
FUNCTION_BLOCK Count
VAR_INPUT tick : BOOL; END_VAR
VAR_OUTPUT n : INT; END_VAR
IF tick THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK
PROGRAM Drawn_blocks
VAR t1, t2 : TON; counter : Count; q, nq, q2, ok, ok2 : BOOL; et : TIME; acc, m : INT; END_VAR
FBD
  1: IN a {at 0 0}
  2: IN T#250ms {at 0 40}
  3: BLOCK TON t1 (IN := 1, PT := 2) -> (NOT Q, ET) {at 100 0}
  4: OUT nq := 3.Q {at 300 0}
  5: OUT et := 3.ET {at 300 30}
  6: IN b {at 0 100}
  7: BLOCK Count counter (tick := R_EDGE 6) -> (n) {at 100 100}
  8: OUT m := 7.n {at 300 100}
  9: IN i {at 0 160}
  10: BLOCK ADD (EN := 6, IN1 := 9, IN2 := 11) -> (ENO, OUT) {at 100 160}
  11: IN m {at 0 200}
  12: OUT acc := 10.OUT {at 300 160}
  13: OUT ok := 10.ENO {at 300 190}
  14: IN c {at 0 260}
  15: BLOCK TON t2 (EN := 14, IN := 1, PT := 2) -> (ENO, Q, ET) {at 100 260}
  16: OUT q2 := 15.Q {at 300 260}
  17: OUT ok2 := 15.ENO {at 300 290}
END_FBD
END_PROGRAM
""",
        """
PROGRAM Text_blocks
VAR t1, t2 : TON; counter : Count; q, nq, q2, ok, ok2 : BOOL; et : TIME; acc, m : INT;
  edge : R_TRIG; sum : INT;
END_VAR
t1(IN := a, PT := T#250ms);
nq := NOT t1.Q;
et := t1.ET;
edge(CLK := b);
counter(tick := edge.Q);
m := counter.n;
IF b THEN sum := i + m; ok := TRUE; acc := sum; ELSE ok := FALSE; END_IF;
IF c THEN t2(IN := a, PT := T#250ms); ok2 := TRUE; q2 := t2.Q; ELSE ok2 := FALSE; END_IF;
END_PROGRAM
""",
    ),
    # connector and continuation, set and reset outputs, an in-out variable, a jump to a
    # label, a return, and the order of elements on the sheet
    "flow": (
        """
PROGRAM Drawn_flow
VAR x, y, w, z : INT; s, r2 : BOOL; END_VAR
FBD
  1: IN i {at 0 0}
  2: CONNECTOR val := 1 {at 60 0}
  3: CONTINUATION val {at 0 200}
  4: OUT x := 3 {at 100 200}
  5: IN a {at 0 20}
  6: OUT[SET] s := 5 {at 100 20}
  7: IN b {at 0 40}
  8: OUT[RESET] s := 7 {at 100 40}
  9: IN c {at 0 60}
  10: JUMP skip := 9 {at 100 60}
  11: IN j {at 0 80}
  12: OUT y := 11 {at 100 80}
  13: LABEL skip {at 0 300}
  16: IN j {at 0 320}
  15: INOUT w := 16 {at 100 320}
  17: OUT z := 15 {at 200 320}
  18: RETURN := 5 {at 0 400}
  19: OUT r2 := 7 {at 100 500}
END_FBD
END_PROGRAM
""",
        """
PROGRAM Text_flow
VAR x, y, w, z : INT; s, r2 : BOOL; END_VAR
IF a THEN s := TRUE; END_IF;
IF b THEN s := FALSE; END_IF;
IF NOT c THEN
  y := j;
  x := i;
END_IF;
w := j;
z := w;
IF a THEN RETURN; END_IF;
r2 := b;
END_PROGRAM
""",
    ),
    # the order of execution given (TC6 executionOrderId) and no places: a jump past the
    # elements before its label, edge-sensing outputs, a FUNCTION's output read after the
    # jump skipped it (its last value)
    "ordered": (
        """
PROGRAM Drawn_ordered
VAR n, m : INT; up, down : BOOL; END_VAR
FBD
  1: IN a
  2: JUMP L := 1 {order 1}
  4: IN n
  5: IN 1
  6: BLOCK ADD (IN1 := 4, IN2 := 5) -> (OUT) {order 2}
  7: OUT n := 6.OUT {order 3}
  3: LABEL L {order 4}
  8: IN b
  9: OUT up := R_EDGE 8 {order 5}
  10: OUT down := F_EDGE 8 {order 6}
  11: OUT m := 6.OUT {order 7}
END_FBD
END_PROGRAM
""",
        """
PROGRAM Text_ordered
VAR n, m : INT; up, down : BOOL; sum : INT; last : BOOL; END_VAR
IF NOT a THEN sum := n + 1; n := sum; END_IF;
up := b AND NOT last;
down := NOT b AND last;
last := b;
m := sum;
END_PROGRAM
""",
    ),
    # drawn actions, called from the body and run by a step of a chart; each keeps its
    # own hidden variables (both have a contact 2)
    "actions": (
        """
PROGRAM Drawn_actions
VAR m1, m2 : BOOL; n : INT; END_VAR
Latch();
INITIAL_STEP Waiting : Count(N); END_STEP
STEP Counting : Count(N); END_STEP
TRANSITION FROM Waiting TO Counting := c; END_TRANSITION
TRANSITION FROM Counting TO Waiting := NOT c; END_TRANSITION
ACTION Latch :
LD
  1: LEFT_RAIL
  2: CONTACT[RISING] a := 1
  3: COIL[SET] m1 := 2
  4: CONTACT b := 1
  5: COIL[RESET] m1 := 4
END_LD
END_ACTION
ACTION Count :
LD
  1: LEFT_RAIL
  2: CONTACT[FALLING] a := 1
  3: COIL m2 := 2
  6: IN n
  7: IN 1
  8: BLOCK ADD (EN := 2, IN1 := 6, IN2 := 7) -> (ENO, OUT)
  9: OUT n := 8.OUT
END_LD
END_ACTION
END_PROGRAM
""",
        """
PROGRAM Text_actions
VAR m1, m2 : BOOL; n : INT; last_a, last_a2 : BOOL; fell : BOOL; END_VAR
Latch();
INITIAL_STEP Waiting : Count(N); END_STEP
STEP Counting : Count(N); END_STEP
TRANSITION FROM Waiting TO Counting := c; END_TRANSITION
TRANSITION FROM Counting TO Waiting := NOT c; END_TRANSITION
ACTION Latch :
IF a AND NOT last_a THEN m1 := TRUE; END_IF;
last_a := a;
IF b THEN m1 := FALSE; END_IF;
END_ACTION
ACTION Count :
fell := NOT a AND last_a2;
last_a2 := a;
m2 := fell;
IF fell THEN n := n + 1; END_IF;
END_ACTION
END_PROGRAM
""",
    ),
    # LD: contacts in series and parallel, negated, rising and falling; coils normal,
    # negated, set, reset, rising and falling; a coil's power flowing on; an FB in a rung
    # with EN from a contact and ENO into a coil
    "ladder": (
        """
PROGRAM Drawn_ladder
VAR m1, m2, m3, m4, m5, m6, m7 : BOOL; t1 : TON; END_VAR
LD
  1: LEFT_RAIL -> (_, _, _, _, _) {at 0 0}
  2: CONTACT a := 1 {at 40 0}
  3: CONTACT[NEGATED] b := 2 {at 80 0}
  4: CONTACT c := 1 {at 40 30}
  5: COIL m1 := 3 | 4 {at 200 0}
  6: COIL[NEGATED] m2 := 5 {at 240 0}
  7: CONTACT[RISING] a := 1 {at 40 60}
  8: COIL[SET] m3 := 7 {at 200 60}
  9: CONTACT[FALLING] c := 1 {at 40 90}
  10: COIL[RESET] m3 := 9 {at 200 90}
  11: CONTACT b := 1 {at 40 120}
  12: COIL[RISING] m4 := 11 {at 200 120}
  13: COIL[FALLING] m5 := 11 {at 240 120}
  14: RIGHT_RAIL (6, 8, 10, 12, 13) {at 300 0}
  15: CONTACT c := 1 {at 40 160}
  16: IN T#300ms {at 40 200}
  18: IN a {at 40 230}
  17: BLOCK TON t1 (EN := 15, IN := 18, PT := 16) -> (ENO, Q, ET) {at 100 160}
  19: COIL m6 := 17.Q {at 200 160}
  20: COIL m7 := 17.ENO {at 240 160}
END_LD
END_PROGRAM
""",
        """
PROGRAM Text_ladder
VAR m1, m2, m3, m4, m5, m6, m7 : BOOL; t1 : TON;
  power : BOOL; last_a, last_c, last_b, last_b2 : BOOL;
END_VAR
power := (a AND NOT b) OR c;
m1 := power;
m2 := NOT power;
IF a AND NOT last_a THEN m3 := TRUE; END_IF;
last_a := a;
IF NOT c AND last_c THEN m3 := FALSE; END_IF;
last_c := c;
m4 := b AND NOT last_b;
last_b := b;
m5 := NOT b AND last_b2;
last_b2 := b;
IF c THEN t1(IN := a, PT := T#300ms); m7 := TRUE; m6 := t1.Q; ELSE m7 := FALSE; END_IF;
END_PROGRAM
""",
    ),
}


def _project(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "stimulus.st").write_text(STIMULUS)
    programs = ['[[resource.program]]\nname = "Stimulus"\npou = "Stimulus"\nid = 1\npriority = 1\n']
    for number, (name, (drawn, text)) in enumerate(sorted(PAIRS.items()), start=1):
        (folder / f"{name}.st").write_text(drawn + text)
        for side, pou in (("D", f"Drawn_{name}"), ("T", f"Text_{name}")):
            program_id = 2 * number + (side == "T")
            programs.append(
                f'[[resource.program]]\nname = "{side}_{name}"\npou = "{pou}"\n'
                f"id = {program_id}\npriority = 2\n"
            )
    toml = '[project]\nname = "drawn"\n[resource]\nname = "R"\n' + "\n".join(programs)
    (folder / "padt.toml").write_text(toml)
    return folder


@pytest.fixture(scope="module")
def traced(tmp_path_factory: pytest.TempPathFactory) -> list[dict[str, object]]:
    """Every cycle's values of the pairs, as `padt sim` prints them."""
    folder = _project(tmp_path_factory.mktemp("drawn") / "project")
    run = padt("sim", str(folder), "--cycles", str(CYCLES), "--cycle-ms", "100")
    assert run.returncode == 0, run.stdout + run.stderr
    return [json.loads(line)["values"] for line in run.stdout.splitlines()]


@pytest.mark.parametrize("name", sorted(PAIRS))
def test_the_drawing_does_every_cycle_what_the_text_does(
    traced: list[dict[str, object]], name: str
) -> None:
    drawn, written = f"D_{name}.", f"T_{name}."
    compared = 0
    for cycle, values in enumerate(traced, start=1):
        shared = [
            path.removeprefix(drawn)
            for path in values
            if path.startswith(drawn) and f"{written}{path.removeprefix(drawn)}" in values
        ]
        assert shared, f"{name}: no variables in common"
        for variable in shared:
            found, wanted = values[drawn + variable], values[written + variable]
            assert found == wanted, f"{name}, cycle {cycle}: {variable} is {found}, not {wanted}"
            compared += 1
    # the inputs change: a pair that saw one state only would prove little
    changing = {
        path
        for path in traced[0]
        if path.startswith(drawn) and len({json.dumps(v[path]) for v in traced}) > 1
    }
    assert len(changing) >= 2, f"{name}: too few of its variables change ({changing})"
    assert compared > CYCLES


@pytest.mark.parametrize("name", sorted(PAIRS))
def test_a_drawing_runs_alike_on_both_tiers(native_tier: NativeTier, name: str) -> None:
    drawn = PAIRS[name][0]
    text = STIMULUS + drawn
    programs = [
        ProgramConfig(name="Stimulus", pou="Stimulus", program_id=1, priority=1),
        ProgramConfig(name="D", pou=f"Drawn_{name}", program_id=2, priority=2),
    ]
    pair = side_by_side(text, NativeTier(native_tier.cache, native_tier.toolchain), programs)
    pair.cycle_and_compare(CYCLES)
    translated = f"Drawn_{name}".upper() in {b.upper() for b in pair.report.bodies}
    # the native tier leaves a POU with a chart or actions to Python (docs/native-code.md)
    assert translated or name == "actions", pair.report.left
