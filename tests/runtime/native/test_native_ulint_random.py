"""Random programs of ULINT and LWORD (0..2**64-1, a padt_i128 in C) run on the native tier
and on the Python tier: every variable identical after every cycle, the same faults in the
same cycle. Their expressions nest arithmetic whose exact value passes 128 bits before the
wrap (products of ULINTs, shifts left by up to 64), which C computes modulo 2**64, beside
DIV, MOD, MIN, MAX, comparisons, conversions to and from LINT, DWORD and LREAL, shifts and
rotations by counts of 0 to beyond the width, and a FUNCTION of a ULINT.

A literal is never a whole operand of a shift here: the compiler takes a literal shifted
or rotated as a DINT whatever its size (docs/language.md), which both tiers then do alike.
A literal converted is what the conversion's target keeps of it (test_native_runtime.py:
test_a_literal_converted_is_what_its_type_keeps_of_it_on_both_tiers)."""

from __future__ import annotations

import random

import pytest

from runtime.code.native.tier import NativeTier
from tests.support.native_runs import side_by_side

CYCLES = 6
_LITERALS = (0, 1, 2, 3, 7, 255, 2**32 - 1, 2**32, 2**63 - 1, 2**63, 2**63 + 1, 2**64 - 1)
_RELATIONS = ("<", "<=", "=", "<>", ">", ">=")


class _Program:
    def __init__(self, seed: int) -> None:
        self.random = random.Random(seed)

    def literal(self) -> str:
        pick = self.random
        return str(pick.choice([*_LITERALS, pick.randrange(2**64)]))

    def ulint(self, depth: int = 0) -> str:
        pick = self.random
        if depth > 3 or pick.random() < 0.3:
            leaves = ("a", "b", "c", f"(a + {self.literal()})", f"({self.literal()} - b)",
                      "LINT_TO_ULINT(l)", "LWORD_TO_ULINT(w)", "Twice(a)")  # fmt: skip
            return pick.choice(leaves)
        roll = pick.random()
        if roll < 0.6:
            op = pick.choice(("+", "-", "*", "/", "MOD", "+", "*", "-"))
            return f"({self.ulint(depth + 1)} {op} {self.ulint(depth + 1)})"
        if roll < 0.75:
            extreme = pick.choice(("MAX", "MIN"))
            return f"{extreme}({self.ulint(depth + 1)}, {self.ulint(depth + 1)})"
        if roll < 0.85:
            factor = pick.choice(("0.5", "1.0", "3.25", "1.0E-3"))
            return f"LREAL_TO_ULINT(ULINT_TO_LREAL({self.ulint(depth + 1)}) * {factor})"
        return f"LWORD_TO_ULINT({self.lword(depth + 1)})"

    def count(self) -> str:
        return self.random.choice(("i", "n", "3", "63", "64", "65", "0", "ULINT_TO_INT(a MOD 70)"))

    def lword(self, depth: int = 0) -> str:
        pick = self.random
        if depth > 3 or pick.random() < 0.3:
            leaves = ("w", "x", "ULINT_TO_LWORD(a)", "(w XOR 16#8000_0000_0000_0001)",
                      "(x OR 16#FFFF_FFFF_0000_FFFF)", "DWORD_TO_LWORD(dw)")  # fmt: skip
            return pick.choice(leaves)
        roll = pick.random()
        if roll < 0.4:
            op = pick.choice(("AND", "OR", "XOR"))
            return f"({self.lword(depth + 1)} {op} {self.lword(depth + 1)})"
        if roll < 0.5:
            return f"NOT (x XOR {self.lword(depth + 1)})"
        if roll < 0.9:
            shift = pick.choice(("SHL", "SHR", "ROL", "ROR"))
            return f"{shift}({self.lword(depth + 1)}, {self.count()})"
        return f"ULINT_TO_LWORD({self.ulint(depth + 1)})"

    def statement(self) -> str:
        pick = self.random
        roll = pick.random()
        if roll < 0.35:
            return f"{pick.choice('abc')} := {self.ulint()};"
        if roll < 0.6:
            return f"{pick.choice('wx')} := {self.lword()};"
        if roll < 0.7:
            return f"l := ULINT_TO_LINT({self.ulint()});"
        if roll < 0.8:
            return f"f := {self.ulint()} {pick.choice(_RELATIONS)} {self.ulint()};"
        if roll < 0.9:
            return (
                f"r := ULINT_TO_LREAL({self.ulint()}) + ULINT_TO_LREAL(a MOD (b + 1))"
                " - ULINT_TO_LREAL(c / (a + 1));"
            )
        return f"dw := LWORD_TO_DWORD({self.lword()}); si := ULINT_TO_SINT({self.ulint()});"

    def text(self) -> str:
        pick = self.random
        starts = [self.literal() for _ in range(5)]
        body = "\n".join(self.statement() for _ in range(12))
        return f"""
FUNCTION Twice : ULINT
VAR_INPUT v : ULINT; END_VAR
Twice := v * 2 + 1;
END_FUNCTION
PROGRAM Main
VAR
  a : ULINT := {starts[0]}; b : ULINT := {starts[1]}; c : ULINT := {starts[2]};
  w : LWORD := {starts[3]}; x : LWORD := {starts[4]}; l : LINT := {pick.randrange(-(2**63), 2**63)};
  i : INT := {pick.randrange(-3, 70)}; n : DINT := {pick.randrange(-2, 100)};
  dw : DWORD := {pick.randrange(2**32)}; f : BOOL; r : LREAL; si : SINT;
END_VAR
a := a + {self.literal()}; i := i + 7; n := n * 3 + 1;
{body}
END_PROGRAM
"""


@pytest.mark.parametrize("seed", range(1, 9))
def test_random_ulint_and_lword_programs_run_alike_on_both_tiers(
    native_tier: NativeTier, seed: int
) -> None:
    program = _Program(seed).text()
    pair = side_by_side(program, native_tier)
    assert pair.report.bodies == ("Main", "Twice"), pair.report.left
    pair.cycle_and_compare(CYCLES)
