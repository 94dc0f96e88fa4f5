"""Differential testing: random programs run compiled and through the tree-walking oracle.

Hypothesis writes small programs (a FUNCTION_BLOCK and a PROGRAM that calls it and a TON)
over INT, UINT, DINT, BOOL and REAL variables: wrapping arithmetic, comparisons, logic, IF,
CASE, FOR, WHILE and REPEAT with constant bounds, EXIT and CONTINUE. Each program runs for
a few cycles on a virtual clock, compiled (compile_sources -> Resource) and in the
`tests.support.oracle.tree_walker.TreeWalker`; every variable must be identical after every cycle
(REAL bit for bit), and a program must fault in the same cycle on both sides.

Constructs where the compiler once differed from IEC semantics (NOT of signed integers,
narrow results inside wider operations, integers and literals in REAL arithmetic, FB
outputs into narrower variables) are each switched on by a `Features` flag in a test of its
own, with the explicit example that used to fail.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import VirtualClock
from runtime.resource import Resource
from tests.support.oracle.tree_walker import TreeWalker

CYCLES = 6
CYCLE_NS = 100_000_000

NARROW = ("INT", "UINT")
INTEGERS = ("INT", "UINT", "DINT")
REALS = ("REAL", "LREAL", "RLIT")  # RLIT: an untyped REAL literal (ANY_REAL)
LIMITS = {"INT": (-32768, 32767), "UINT": (0, 65535), "DINT": (-(2**31), 2**31 - 1)}
# integer literals that sit at the edges of the types used
EDGES = (32767, 32768, -32768, 65535, 65536, 100000, 2147483647, -2147483648)


@dataclass(frozen=True)
class Features:
    """Constructs the compiler is known to get wrong; off in the main test."""

    # NOT of a signed integer (INT, DINT)
    signed_not: bool = False
    # an integer + - * / or negation whose type is narrower than the operation it feeds
    unwrapped_operands: bool = False
    # DINT operands in REAL arithmetic and comparisons
    dint_in_real: bool = False
    # REAL literals that a single-precision REAL cannot hold exactly (0.1)
    inexact_real_literals: bool = False
    # FB outputs connected with => to variables of a narrower type
    narrowing_outputs: bool = False


@dataclass(frozen=True)
class Expr:
    text: str
    type: str  # INT UINT DINT LIT (untyped integer literal) BOOL REAL LREAL RLIT
    # an integer result that the compiled code does not wrap until it is consumed
    unwrapped: bool = False
    literal: int | None = None  # the value of a bare integer literal


@dataclass(frozen=True)
class Names:
    """The variables one POU body may use."""

    ints: dict[str, tuple[str, ...]]  # assignable, by type
    bools: tuple[str, ...]
    reals: tuple[str, ...]
    read_ints: dict[str, tuple[str, ...]]  # read-only (FOR counters, FB outputs), by type
    read_bools: tuple[str, ...]
    read_reals: tuple[str, ...]
    calls: bool  # may call the FB instance and the timer


MAIN = Names(
    ints={"INT": ("i0", "i1", "i2"), "UINT": ("u0", "u1"), "DINT": ("d0", "d1")},
    bools=("b0", "b1", "b2"),
    reals=("r0", "r1"),
    read_ints={"INT": ("k0", "k1"), "DINT": ("acc.total",)},
    read_bools=("acc.big", "t.Q"),
    read_reals=(),
    calls=True,
)
ACC = Names(
    ints={"INT": ("j",), "UINT": ("n",), "DINT": ("total",)},
    bools=("big",),
    reals=("x",),
    read_ints={"INT": ("inc", "k0", "k1")},
    read_bools=("reset",),
    read_reals=("gain",),
    calls=False,
)
COUNTERS = ("k0", "k1")  # FOR counters by nesting depth
WHILE_COUNTERS = ("w0", "w1")

TEMPLATE = """\
FUNCTION_BLOCK Acc
VAR_INPUT
  inc : INT;
  reset : BOOL;
  gain : REAL;
END_VAR
VAR_OUTPUT
  total : DINT;
  big : BOOL;
END_VAR
VAR
  n : UINT;
  x : REAL;
  j : INT;
  k0, k1, w0, w1 : INT;
END_VAR
{acc_body}
END_FUNCTION_BLOCK

PROGRAM Main
VAR
{main_vars}
  k0, k1, w0, w1 : INT;
  acc : Acc;
  t : TON;
END_VAR
{main_body}
END_PROGRAM
"""


def _join(a: str, b: str) -> str:
    """The type of `a op b` (IEC typing as the compiler does it: an untyped integer literal
    makes a narrow integer operation DINT; a REAL literal with an integer makes LREAL)."""
    if a == b:
        return a
    if a in REALS or b in REALS:
        if "LREAL" in (a, b):
            return "LREAL"
        if "REAL" in (a, b):
            return "REAL"
        return "LREAL"  # a REAL literal with an integer
    if "DINT" in (a, b) or "LIT" in (a, b):
        return "DINT"
    return "DINT"  # INT with UINT: DINT holds both


def _real_text(eighths: int) -> str:
    return f"{eighths / 8:.3f}"


class _Writer:
    """Writes one POU body; `draw` is hypothesis's."""

    def __init__(self, draw: st.DrawFn, names: Names, features: Features) -> None:
        self.draw = draw
        self.names = names
        self.features = features

    def pick(self, options: tuple[str, ...] | list[str]) -> str:
        return self.draw(st.sampled_from(list(options)))

    def flip(self, chance: float = 0.5) -> bool:
        return self.draw(st.integers(0, 999)) < chance * 1000

    # ---- integer expressions
    def int_var(self, type_name: str | None = None) -> Expr:
        types = [type_name] if type_name else list(INTEGERS)
        choices = [
            (name, t)
            for t in types
            for name in (*self.names.ints.get(t, ()), *self.names.read_ints.get(t, ()))
        ]
        name, t = self.draw(st.sampled_from(choices))
        return Expr(name, t)

    def int_literal(self, small: bool = False) -> Expr:
        if small or self.flip(0.8):
            value = self.draw(st.integers(-100, 100))
        else:
            value = self.draw(st.sampled_from(EDGES))
        text = f"({value})" if value < 0 else str(value)
        return Expr(text, "LIT", literal=value)

    def int_leaf(self) -> Expr:
        return self.int_var() if self.flip(0.65) else self.int_literal()

    def settle(self, operand: Expr, result_type: str) -> Expr:
        """An operand of an operation of `result_type`: an unwrapped narrower result is
        swapped for a variable of its type unless the flag allows it."""
        if self.features.unwrapped_operands or not operand.unwrapped:
            return operand
        if operand.type == result_type or operand.type == "LIT":
            return operand
        return self.int_var(operand.type)

    def int_expr(self, depth: int) -> Expr:
        if depth <= 0 or self.flip(0.3):
            return self.int_leaf()
        kind = self.pick(["binary", "binary", "binary", "negate", "not"])
        if kind == "negate":
            operand = self.int_expr(depth - 1)
            return Expr(f"(-{operand.text})", operand.type, unwrapped=operand.type != "LIT")
        if kind == "not":
            signed = self.features.signed_not and self.flip()
            operand = self.int_var(self.pick(["INT", "DINT"]) if signed else "UINT")
            return Expr(f"(NOT {operand.text})", operand.type)
        op = self.pick(["+", "-", "*", "/", "MOD"])
        left = self.int_expr(depth - 1)
        if op in ("/", "MOD") and self.flip(0.7):
            divisor = self.draw(st.sampled_from([-7, -3, -1, 1, 2, 3, 10, 100]))
            right = Expr(f"({divisor})" if divisor < 0 else str(divisor), "LIT", literal=divisor)
        else:
            right = self.int_expr(depth - 1)
        result = _join(left.type, right.type)
        if op in ("+", "-", "*"):
            # `/` and MOD wrap their operands in the compiled code too
            left, right = self.settle(left, result), self.settle(right, result)
            result = _join(left.type, right.type)
        unwrapped = op != "MOD" and result != "LIT"
        return Expr(f"({left.text} {op} {right.text})", result, unwrapped)

    # ---- REAL expressions
    def real_literal(self) -> Expr:
        if self.features.inexact_real_literals and self.flip(0.5):
            return Expr(self.pick(["0.1", "0.3", "1.1", "2.2", "0.7", "3.3"]), "RLIT")
        return Expr(_real_text(self.draw(st.integers(0, 80))), "RLIT")

    def real_leaf(self) -> Expr:
        choice = self.draw(st.integers(0, 9))
        reals = (*self.names.reals, *self.names.read_reals)
        if choice < 4:
            return Expr(self.pick(reals), "REAL")
        if choice < 6:
            return self.real_literal()
        if choice < 8:
            return self.int_var(self.pick(NARROW))
        if choice < 9 and self.features.dint_in_real:
            return self.int_var("DINT")
        return self.int_literal(small=True)

    def real_operand(self, operand: Expr, result_type: str) -> Expr:
        """An integer operand of REAL arithmetic: kept exact in single precision (narrow
        and wrapped, or a small literal) unless a flag allows otherwise."""
        if operand.type == "LIT":
            big = operand.literal is None or abs(operand.literal) > 2**24
            if big and not self.features.inexact_real_literals:
                return self.int_literal(small=True)
            return operand
        if operand.type not in INTEGERS:
            return operand
        if operand.unwrapped and not self.features.unwrapped_operands:
            return self.int_var(self.pick(NARROW))
        if operand.type == "DINT" and result_type == "REAL" and not self.features.dint_in_real:
            return self.int_var(self.pick(NARROW))
        return operand

    def real_expr(self, depth: int) -> Expr:
        if depth <= 0 or self.flip(0.3):
            leaf = self.real_leaf()
            return leaf if leaf.type in REALS else Expr(self.pick(self.names.reals), "REAL")
        if self.flip(0.15):
            operand = self.real_expr(depth - 1)
            return Expr(f"(-{operand.text})", operand.type)
        op = self.pick(["+", "-", "*", "/"])
        left = self.real_expr(depth - 1)
        right = self.real_expr(depth - 1) if self.flip() else self.int_expr(depth - 1)
        if self.flip():
            left, right = right, left
        if left.type == right.type == "RLIT" and not self.features.inexact_real_literals:
            # literal arithmetic is done in LREAL: 0.5 / 3.0 would be inexact in a REAL
            left = Expr(self.pick(self.names.reals), "REAL")
        result = _join(left.type, right.type)
        left, right = self.real_operand(left, result), self.real_operand(right, result)
        return Expr(f"({left.text} {op} {right.text})", _join(left.type, right.type))

    # ---- BOOL expressions
    def bool_leaf(self) -> Expr:
        if self.flip(0.15):
            return Expr(self.pick(["TRUE", "FALSE"]), "BOOL")
        return Expr(self.pick((*self.names.bools, *self.names.read_bools)), "BOOL")

    def bool_expr(self, depth: int) -> Expr:
        if depth <= 0 or self.flip(0.25):
            return self.bool_leaf()
        kind = self.pick(["compare", "compare", "real_compare", "logic", "logic", "not"])
        if kind == "not":
            return Expr(f"(NOT {self.bool_expr(depth - 1).text})", "BOOL")
        if kind == "logic":
            op = self.pick(["AND", "OR", "XOR", "&"])
            left, right = self.bool_expr(depth - 1), self.bool_expr(depth - 1)
            return Expr(f"({left.text} {op} {right.text})", "BOOL")
        op = self.pick(["=", "<>", "<", ">", "<=", ">="])
        if kind == "compare":
            left, right = self.int_expr(depth - 1), self.int_expr(depth - 1)
        else:
            left = self.real_expr(depth - 1)
            right = self.real_expr(depth - 1) if self.flip() else self.int_leaf()
            if left.type == "REAL" or right.type == "REAL":
                # the integer side is converted to REAL: exact only for narrow integers
                left, right = self.real_operand(left, "REAL"), self.real_operand(right, "REAL")
        return Expr(f"({left.text} {op} {right.text})", "BOOL")

    # ---- statements
    def value_for(self, target_type: str, depth: int) -> Expr:
        if target_type == "BOOL":
            return self.bool_expr(depth)
        if target_type == "REAL":
            return self.real_expr(depth) if self.flip(0.7) else self.int_expr(depth)
        value = self.int_expr(depth) if self.flip(0.8) else self.real_expr(depth)
        if value.type == "RLIT":  # a REAL literal is no integer (E0222): a REAL converts
            value = Expr(self.pick(self.names.reals), "REAL")
        if value.literal is not None:  # a bare literal must fit (the checker says so)
            low, high = LIMITS[target_type]
            value = Expr(str(min(max(abs(value.literal), low), high)), "LIT")
        return value

    def assignment(self, depth: int) -> list[str]:
        names = self.names
        targets = [(n, t) for t, group in names.ints.items() for n in group]
        targets += [(n, "BOOL") for n in names.bools] + [(n, "REAL") for n in names.reals]
        target, target_type = self.draw(st.sampled_from(targets))
        return [f"{target} := {self.value_for(target_type, depth).text};"]

    def block(self, depth: int, loops: tuple[str, ...], most: int = 3) -> list[str]:
        count = self.draw(st.integers(1, most))
        lines: list[str] = []
        for _ in range(count):
            lines.extend(self.statement(depth, loops))
        return lines

    def statement(self, depth: int, loops: tuple[str, ...]) -> list[str]:
        kinds = ["assign", "assign", "assign"]
        if depth > 0:
            kinds += ["if", "case"]
            if len(loops) < len(COUNTERS):
                kinds += ["for", "while", "repeat"]
        if loops:
            kinds.append("exit")
        if loops and loops[-1] == "FOR":
            kinds.append("continue")
        if self.names.calls:
            kinds += ["acc", "timer"]
        kind = self.pick(kinds)
        if kind == "assign":
            return self.assignment(2)
        if kind == "exit":
            return [f"IF {self.bool_expr(1).text} THEN", "  EXIT;", "END_IF;"]
        if kind == "continue":
            return [f"IF {self.bool_expr(1).text} THEN", "  CONTINUE;", "END_IF;"]
        if kind == "acc":
            return [self.acc_call()]
        if kind == "timer":
            pt = self.draw(st.sampled_from([100, 200, 250, 300, 400]))
            output = " , Q => b2" if self.flip(0.3) else ""
            return [f"t(IN := {self.bool_expr(1).text}, PT := T#{pt}ms{output});"]
        if kind == "if":
            return self.if_statement(depth, loops)
        if kind == "case":
            return self.case_statement(depth, loops)
        return self.loop(kind, depth, loops)

    def if_statement(self, depth: int, loops: tuple[str, ...]) -> list[str]:
        lines = [f"IF {self.bool_expr(2).text} THEN"]
        lines += _indent(self.block(depth - 1, loops))
        for _ in range(self.draw(st.integers(0, 2))):
            lines.append(f"ELSIF {self.bool_expr(2).text} THEN")
            lines += _indent(self.block(depth - 1, loops))
        if self.flip():
            lines.append("ELSE")
            lines += _indent(self.block(depth - 1, loops))
        return [*lines, "END_IF;"]

    def case_statement(self, depth: int, loops: tuple[str, ...]) -> list[str]:
        lines = [f"CASE {self.int_expr(2).text} OF"]
        values = self.draw(st.lists(st.integers(-3, 12), min_size=1, max_size=6, unique=True))
        branches = self.draw(st.integers(1, min(3, len(values))))
        for index in range(branches):
            labels = [str(v) for v in values[index::branches]]
            if self.flip(0.3):  # a range, in a band no single label uses
                low = 20 + 10 * index
                labels.append(f"{low}..{low + self.draw(st.integers(0, 4))}")
            lines.append(f"{', '.join(labels)}:")
            lines += _indent(self.block(depth - 1, loops))
        if self.flip():
            lines.append("ELSE")
            lines += _indent(self.block(depth - 1, loops))
        return [*lines, "END_CASE;"]

    def loop(self, kind: str, depth: int, loops: tuple[str, ...]) -> list[str]:
        level = len(loops)
        if kind == "for":
            counter = COUNTERS[level]
            start = self.draw(st.integers(-3, 3))
            step = self.draw(st.sampled_from([None, 1, 2, 3, -1, -2]))
            stop = start + self.draw(st.integers(-2, 6)) * (1 if (step or 1) > 0 else -1)
            by = "" if step is None else f" BY {step}"
            lines = [f"FOR {counter} := {start} TO {stop}{by} DO"]
            lines += _indent(self.block(depth - 1, (*loops, "FOR")))
            return [*lines, "END_FOR;"]
        counter = WHILE_COUNTERS[level]
        limit = self.draw(st.integers(0, 4))
        body = _indent([*self.block(depth - 1, (*loops, "WHILE")), f"{counter} := {counter} + 1;"])
        if kind == "while":
            condition = f"{counter} < {limit}"
            if self.flip(0.3):
                condition += f" AND {self.bool_expr(1).text}"
            return [f"{counter} := 0;", f"WHILE {condition} DO", *body, "END_WHILE;"]
        until = f"{counter} >= {limit}"
        if self.flip(0.3):
            until += f" OR {self.bool_expr(1).text}"
        return [f"{counter} := 0;", "REPEAT", *body, f"UNTIL {until}", "END_REPEAT;"]

    def acc_call(self) -> str:
        args: list[str] = []
        if self.flip(0.8):
            args.append(f"inc := {self.int_expr(2).text}")
        if self.flip(0.7):
            args.append(f"reset := {self.bool_expr(1).text}")
        if self.flip(0.5):
            args.append(f"gain := {self.real_expr(1).text}")
        if self.flip(0.4):
            targets = ["d1", "i1", "u1"] if self.features.narrowing_outputs else ["d1"]
            args.append(f"total => {self.pick(targets)}")
        if self.flip(0.3):
            args.append("big => b1")
        return f"acc({', '.join(args)});"


def _indent(lines: list[str]) -> list[str]:
    return [f"  {line}" for line in lines]


def _declarations(draw: st.DrawFn) -> list[str]:
    lines = []
    for name, low, high in (
        ("i0", -32768, 32767), ("i1", -32768, 32767), ("i2", -300, 300),
        ("u0", 0, 65535), ("u1", 0, 300),
        ("d0", -(2**31), 2**31 - 1), ("d1", -100000, 100000),
    ):  # fmt: skip
        type_name = {"i": "INT", "u": "UINT", "d": "DINT"}[name[0]]
        lines.append(f"  {name} : {type_name} := {draw(st.integers(low, high))};")
    for name in ("b0", "b1", "b2"):
        lines.append(f"  {name} : BOOL := {draw(st.sampled_from(['TRUE', 'FALSE']))};")
    for name in ("r0", "r1"):
        value = draw(st.integers(-80, 80))
        text = _real_text(abs(value))
        lines.append(f"  {name} : REAL := {'-' if value < 0 else ''}{text};")
    return lines


@st.composite
def programs(draw: st.DrawFn, features: Features | None = None) -> str:
    acc = _Writer(draw, ACC, features or Features())
    main = _Writer(draw, MAIN, features or Features())
    acc_body = acc.block(2, (), most=4)
    main_body = main.block(3, (), most=8)
    return TEMPLATE.format(
        acc_body="\n".join(acc_body),
        main_vars="\n".join(_declarations(draw)),
        main_body="\n".join(main_body),
    )


def program_with(main_body: str, acc_body: str = ";", **initial: str) -> str:
    """A program of the generator's shape with a fixed body (for explicit examples)."""
    defaults = {
        "i0": "INT := 0", "i1": "INT := 0", "i2": "INT := 0", "u0": "UINT := 0",
        "u1": "UINT := 0", "d0": "DINT := 0", "d1": "DINT := 0", "b0": "BOOL := FALSE",
        "b1": "BOOL := FALSE", "b2": "BOOL := FALSE", "r0": "REAL := 0.0", "r1": "REAL := 0.0",
    }  # fmt: skip
    declared = {**defaults, **initial}
    return TEMPLATE.format(
        acc_body=acc_body,
        main_vars="\n".join(f"  {name} : {decl};" for name, decl in declared.items()),
        main_body=main_body,
    )


# ---- running both sides -------------------------------------------------------------------


def _same(a: object, b: object) -> bool:
    """Identical values: the same Python type, and REALs bit for bit (NaN equals NaN)."""
    if type(a) is not type(b):
        return False
    if isinstance(a, float) and isinstance(b, float):
        if math.isnan(a) or math.isnan(b):
            return math.isnan(a) and math.isnan(b)
        return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)
    return a == b


def assert_same_run(program: str, cycles: int = CYCLES) -> None:
    sources = [SourceFile("diff.st", program)]
    result = compile_sources(sources)
    assert result.artifact is not None, "\n".join(str(d) for d in result.diagnostics)
    clock = VirtualClock()
    resource = Resource("R", clock)
    resource.load(result.artifact)
    resource.start()
    walker = TreeWalker(sources)
    for cycle in range(1, cycles + 1):
        resource.cycle()
        walker.run_cycle(clock.now_ns())
        compiled, oracle = resource.variables.values(), walker.values()
        assert compiled.keys() == oracle.keys()
        differences = {
            path: (compiled[path], oracle[path])
            for path in compiled
            if not _same(compiled[path], oracle[path])
        }
        states = {p.name: p.state for p in resource.status().programs}
        assert not differences and states == walker.states(), (
            f"cycle {cycle}: compiled vs tree walker {differences}; "
            f"states {states} vs {walker.states()}\n{program}"
        )
        clock.advance(CYCLE_NS)


SETTINGS = settings(
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


@SETTINGS
@given(programs())
def test_compiled_code_matches_the_tree_walker(program: str) -> None:
    assert_same_run(program)


def test_the_explicit_examples_compile() -> None:
    """The fixed programs below are valid ST: only the compiled values are wrong."""
    for program in (NOT_EXAMPLE, UNWRAPPED_EXAMPLE, DINT_REAL_EXAMPLE, LITERAL_EXAMPLE):
        assert compile_sources([SourceFile("diff.st", program)]).ok
    assert compile_sources([SourceFile("diff.st", OUTPUT_EXAMPLE)]).ok


# ---- former miscompilations, each with the example that showed it ------------------------

NOT_EXAMPLE = program_with("i0 := NOT i0;", i0="INT := 5")


@SETTINGS
@given(programs(Features(signed_not=True)))
@example(NOT_EXAMPLE)
def test_not_of_signed_integers(program: str) -> None:
    assert_same_run(program)


UNWRAPPED_EXAMPLE = program_with("d0 := i0 * i1 + d0;", i0="INT := 300", i1="INT := 300")


@SETTINGS
@given(programs(Features(unwrapped_operands=True)))
@example(UNWRAPPED_EXAMPLE)
def test_narrow_results_in_wider_operations(program: str) -> None:
    assert_same_run(program)


DINT_REAL_EXAMPLE = program_with("r1 := r0 + d0;", r0="REAL := 1.0", d0="DINT := 16777217")


@SETTINGS
@given(programs(Features(dint_in_real=True)))
@example(DINT_REAL_EXAMPLE)
def test_dint_operands_of_real_arithmetic(program: str) -> None:
    assert_same_run(program)


LITERAL_EXAMPLE = program_with("r0 := 0.1;\nb0 := r0 = 0.1;\nb1 := r0 > 0.1;")


@SETTINGS
@given(programs(Features(inexact_real_literals=True)))
@example(LITERAL_EXAMPLE)
def test_inexact_real_literals(program: str) -> None:
    assert_same_run(program)


OUTPUT_EXAMPLE = program_with("acc(inc := 1, total => i0);", acc_body="total := 70000;")


@SETTINGS
@given(programs(Features(narrowing_outputs=True)))
@example(OUTPUT_EXAMPLE)
def test_fb_outputs_into_narrower_variables(program: str) -> None:
    assert_same_run(program)


ALL_FEATURES = Features(
    signed_not=True,
    unwrapped_operands=True,
    dint_in_real=True,
    inexact_real_literals=True,
    narrowing_outputs=True,
)


@settings(SETTINGS, max_examples=30)
@given(programs(ALL_FEATURES))
def test_flagged_generators_write_valid_programs(program: str) -> None:
    """The xfail tests stop at their explicit example; this keeps the generators they
    would use honest: the programs compile (only their values are wrong)."""
    result = compile_sources([SourceFile("diff.st", program)])
    assert result.ok, "\n".join(str(d) for d in result.diagnostics) + "\n" + program
