"""EN and ENO in Structured Text (docs/language.md, "EN and ENO"): every standard and user
FUNCTION takes EN (a BOOL input) and gives ENO (a BOOL output, `ENO => ok`) in a formal
call; every function block instance has ENO. With EN FALSE nothing runs: ENO is FALSE, the
target of `x := F(EN := FALSE, ...)` and of the call's `=>` outputs keep their values (as
Beremiz leaves them), and inside a larger expression the call gives its type's initial
value. The same program runs on the Python tier (`padt sim`) and on the native tier (the
runtime's default), every variable compared after every cycle. Real C compiles, real
resources on virtual clocks."""

from __future__ import annotations

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.code.native.tier import NativeTier
from tests.support.native_runs import Pair, program_error, side_by_side


@pytest.fixture
def tier(native_tier: NativeTier) -> NativeTier:
    """A tier of its own, sharing the session's compiled modules (tests/conftest.py)."""
    return NativeTier(native_tier.cache, native_tier.toolchain)


BLOCKS = """
FUNCTION Twice : INT
VAR_INPUT v : INT; END_VAR
VAR_OUTPUT half : INT; END_VAR
Twice := v * 2;
half := v / 2;
END_FUNCTION
FUNCTION_BLOCK Guard
VAR_INPUT limit : INT; END_VAR
VAR_OUTPUT runs : INT; END_VAR
runs := runs + 1;
IF limit = 5 THEN ENO := FALSE; END_IF;   (* IEC lets a body say it failed *)
END_FUNCTION_BLOCK
"""

PROGRAM = (
    BLOCKS
    + """
PROGRAM Main
VAR
  n : INT;
  c : BOOL;
  a : INT := 3;
  b : INT := 4;
  sum, prod, big, lim : INT := -1;
  nested : INT;
  okAdd, okMul, okMax, okLim, okT, okG : BOOL := TRUE;
  t1 : TON;
  et1 : TIME := T#5s;
  tEno : BOOL := TRUE;
  g, spare : Guard;
  gEno, offEno, onEno, maxFailed, tFailed : BOOL;
  real1 : REAL := -1.0;
END_VAR
n := n + 1;
c := n >= 3;   (* cycles 1 and 2: EN FALSE; then TRUE *)
sum := ADD(EN := c, IN1 := a, IN2 := b, ENO => okAdd);
prod := MUL(EN := c, IN1 := a, IN2 := b, ENO => okMul);
big := MAX(EN := c, IN1 := a, IN2 := b, ENO => okMax, NOT ENO => maxFailed);
lim := LIMIT(EN := c, MN := 0, IN := n, MX := 4, ENO => okLim);
real1 := INT_TO_REAL(EN := c, IN := n);
nested := 100 + ADD(EN := c, IN1 := a, IN2 := b);
t1(EN := c, IN := TRUE, PT := T#1s, ET => et1, ENO => okT, NOT ENO => tFailed);
tEno := t1.ENO;
g(EN := n <> 4, limit := n, ENO => okG);
gEno := g.ENO;
spare(EN := FALSE);
offEno := spare.ENO;
spare();
onEno := spare.ENO;
END_PROGRAM
PROGRAM Outputs   (* a FUNCTION with VAR_OUTPUT: left to Python on the native tier too *)
VAR n : INT; tw, half : INT := -1; okTwice : BOOL := TRUE; END_VAR
n := n + 1;
tw := Twice(EN := n >= 3, v := n, half => half, ENO => okTwice);
END_PROGRAM
"""
)


def run_alike(text: str, tier: NativeTier) -> Pair:
    pair = side_by_side(text, tier)
    assert "Main" in pair.report.bodies and "Guard" in pair.report.bodies, pair.report.left
    assert [pou for pou, _ in pair.report.left] == ["Outputs"]
    return pair


def test_en_false_runs_nothing_and_keeps_the_targets_on_both_tiers(tier: NativeTier) -> None:
    pair = run_alike(PROGRAM, tier)
    pair.cycle_and_compare(2)
    found = pair.native.variables.values()
    assert not program_error(pair.native), program_error(pair.native)
    kept = ("Main.sum", "Main.prod", "Main.big", "Main.lim", "Outputs.tw", "Outputs.half")
    assert [found[path] for path in kept] == [-1] * 6
    assert found["Main.real1"] == -1.0
    flags = ("okAdd", "okMul", "okMax", "okLim", "okT", "tEno")
    assert [found[f"Main.{name}"] for name in flags] == [False] * 6
    assert found["Outputs.okTwice"] is False
    assert found["Main.nested"] == 100  # the call inside an expression gives INT's 0
    assert found["Main.maxFailed"] is True and found["Main.tFailed"] is True
    # the timer's body never ran: its elapsed time and the target of ET => keep theirs
    assert found["Main.t1.ET"] == 0 and found["Main.et1"] == 5_000_000_000
    assert found["Main.t1.ENO"] is False
    # an instance called with EN FALSE, then without EN: ENO FALSE, then TRUE
    assert found["Main.offEno"] is False and found["Main.onEno"] is True
    assert found["Main.spare.runs"] == 2  # the call without EN ran, each cycle


def test_en_true_runs_the_call_and_sets_eno_on_both_tiers(tier: NativeTier) -> None:
    pair = run_alike(PROGRAM, tier)
    pair.cycle_and_compare(3)
    found = pair.native.variables.values()
    assert not program_error(pair.native), program_error(pair.native)
    ran = ("Main.sum", "Main.prod", "Main.big", "Main.lim", "Outputs.tw", "Outputs.half")
    assert [found[path] for path in ran] == [7, 12, 4, 3, 6, 1]
    assert found["Main.real1"] == 3.0 and found["Main.nested"] == 107
    flags = ("okAdd", "okMul", "okMax", "okLim", "okT", "tEno")
    assert [found[f"Main.{name}"] for name in flags] == [True] * 6
    assert found["Outputs.okTwice"] is True
    assert found["Main.et1"] == 0  # the timer ran: ET => copied its elapsed time
    assert found["Main.maxFailed"] is False and found["Main.tFailed"] is False


def test_a_block_body_may_set_its_eno_and_en_false_skips_it(tier: NativeTier) -> None:
    pair = run_alike(PROGRAM, tier)
    seen = []
    for _ in range(6):
        pair.cycle_and_compare(1)
        found = pair.native.variables.values()
        seen.append((found["Main.g.runs"], found["Main.okG"], found["Main.gEno"]))
    assert seen == [
        (1, True, True),
        (2, True, True),
        (3, True, True),
        (3, False, False),  # n = 4: EN FALSE, the body did not run
        (4, False, False),  # n = 5: the body set ENO FALSE
        (5, True, True),  # a call that runs starts with ENO TRUE
    ]


def diagnostics(source: str) -> list[str]:
    return [str(d) for d in compile_sources([SourceFile("t.st", source)]).diagnostics]


def test_en_and_eno_are_bool_and_eno_needs_a_variable() -> None:
    source = """PROGRAM Main
VAR a, b, x : INT; ok : BOOL; t : TON; END_VAR
x := ADD(EN := a, IN1 := a, IN2 := b);
x := MAX(IN1 := a, IN2 := b, ENO => x);
x := MUL(EN => ok, IN1 := a, IN2 := b);
t(EN := b, IN := ok);
x := t.ENO;
END_PROGRAM
"""
    assert [d.removeprefix("t.st:") for d in diagnostics(source)] == [
        "3:16: error: type mismatch: cannot pass INT as BOOL [E0401]",
        "4:37: error: cannot store BOOL output in INT [E0402]",
        "5:10: error: 'EN' of 'MUL' is an input, not an output [E0407]",
        "6:9: error: type mismatch: cannot assign INT to BOOL [E0401]",
        "7:6: error: type mismatch: cannot assign BOOL to INT [E0209]",
    ]


SWEEP = """
PROGRAM Main
VAR
  n : INT; c, ok, b : BOOL; i : INT := 5; d : DINT := 7; r : REAL := 2.0; s : STRING := 'abc';
  w : WORD := 3; t : TIME;
  i1, i2, i3, i4, i5, i6, i7, i8, i9 : INT := -1;
  s1, s2, s3 : STRING := 'keep';
  r1, r2 : REAL := -1.0;
  w1 : WORD := 7;
  b1, b2, b3 : BOOL := TRUE;
  t1 : TIME := T#9s;
  eno : ARRAY[1..22] OF BOOL := [22(TRUE)];
END_VAR
n := n + 1;
c := n >= 2;
i1 := SEL(EN := c, G := b, IN0 := 1, IN1 := 2, ENO => eno[1]);
i2 := MUX(EN := c, K := 0, IN0 := 1, IN1 := 2, ENO => eno[2]);
i3 := LEN(EN := c, IN := s, ENO => eno[3]);
s1 := LEFT(EN := c, IN := s, L := 2, ENO => eno[4]);
s2 := CONCAT(EN := c, IN1 := s, IN2 := 'x', ENO => eno[5]);
r1 := SQRT(EN := c, IN := r * 2.0, ENO => eno[6]);
i4 := ABS(EN := c, IN := -i, ENO => eno[7]);
w1 := SHL(EN := c, IN := w, N := 2, ENO => eno[8]);
b1 := AND(EN := c, IN1 := b, IN2 := b, ENO => eno[9]);
b2 := GT(EN := c, IN1 := i, IN2 := 20, ENO => eno[10]);
i5 := MOVE(EN := c, IN := i, ENO => eno[11]);
i6 := TRUNC(EN := c, IN := r, ENO => eno[12]);
i7 := DINT_TO_INT(EN := c, IN := d, ENO => eno[13]);
r2 := TO_REAL(EN := c, IN := i, ENO => eno[14]);
s3 := MID(EN := c, IN := s, L := 1, P := 2, ENO => eno[15]);
b3 := EQ(EN := c, IN1 := s, IN2 := 'abd', ENO => eno[16]);
i8 := MIN(EN := c, IN1 := 4, IN2 := 2, IN3 := 3, ENO => eno[17]);
i9 := SUB(EN := c, IN1 := 1, IN2 := i, ENO => eno[18]);
t1 := ADD(EN := c, IN1 := t, IN2 := T#1s, ENO => eno[19]);
i1 := i1 + DIV(EN := c, IN1 := 7, IN2 := 2, ENO => eno[20]);
i2 := i2 + MOD(EN := c, IN1 := 7, IN2 := 2, ENO => eno[21]);
i3 := i3 + LIMIT(EN := c, MN := 1, IN := 9, MX := 3, ENO => eno[22]);
END_PROGRAM
"""
SWEPT: tuple[str, ...] = (
    "i1",
    "i2",
    "i3",
    "i4",
    "i5",
    "i6",
    "i7",
    "i8",
    "i9",
    "s1",
    "s2",
    "s3",
    "r1",
    "r2",
)
SWEPT += ("w1", "b1", "b2", "b3", "t1")


def test_every_kind_of_standard_function_takes_en_and_eno_on_both_tiers(tier: NativeTier) -> None:
    """Selection, strings, numerics, bit shifts, logic, comparisons, MOVE, conversions,
    variadic MIN, TIME arithmetic; the last three inside an expression (their default, 0,
    is added in the cycle with EN FALSE)."""
    pair = side_by_side(SWEEP, tier)
    pair.cycle_and_compare(1)  # EN FALSE: every target as it was, every ENO FALSE
    found = pair.python.variables.values()
    kept = [-1] * 9 + ["keep"] * 3 + [-1.0] * 2 + [7, True, True, True, 9_000_000_000]
    assert [found[f"Main.{name}"] for name in SWEPT] == kept
    assert found["Main.eno"] == [False] * 22
    pair.cycle_and_compare(1)  # EN TRUE
    found = pair.python.variables.values()
    assert [found[f"Main.{name}"] for name in SWEPT[:9]] == [1 + 3, 1 + 1, 3 + 3, 5, 5, 2, 7, 2, -4]
    assert [found[f"Main.{name}"] for name in SWEPT[9:]] == [
        "ab", "abcx", "b", 2.0, 5.0, 12, False, False, False, 1_000_000_000,
    ]  # fmt: skip
    assert found["Main.eno"] == [True] * 22
    assert not program_error(pair.python) and not program_error(pair.native)
