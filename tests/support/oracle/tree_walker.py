"""A tree-walking interpreter for a subset of ST: the oracle the compiled code is checked by.

It shares only the front end with the compiler (parse, resolve, and `Scope` for the type of
each expression) and none of the code generator: every statement is executed straight from
the AST, and every operation is done the way IEC 61131-3 describes it. An operation works
in the type the typing rules give it: its operands are first converted to that type (an
integer or a literal used in REAL arithmetic becomes a REAL, i.e. is rounded to single
precision), and the result is brought into that type right away (integers wrap in two's
complement, REAL results round to single precision). Division truncates toward zero;
integer division by zero is a program fault, REAL division by zero follows IEEE 754.

The subset: PROGRAMs, FUNCTION_BLOCKs and their instances, variables of the elementary
types BOOL, SINT..LINT, USINT..ULINT, BYTE..LWORD, REAL, LREAL and TIME, assignments,
+ - * / MOD, comparisons, AND/OR/XOR/NOT, IF, CASE, FOR, WHILE, REPEAT, EXIT, CONTINUE,
RETURN, calls of function block instances, and `__CURRENT_TIME()`. TON is executed natively
(with the semantics of `backend/compiler/stdlib/timers.st`); the other standard function
blocks run from their ST source. Anything else raises `Unsupported`, so that the oracle
never silently gives an answer it was not written to give.

Clarity matters more than speed here: values are Python objects in dictionaries, and
every expression is evaluated afresh by recursion over the tree.
"""

from __future__ import annotations

import functools
import math
import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum
from typing import TypeGuard

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.check import check
from backend.compiler.infer import EnumValue, NonFinite, ProgramRef, Scope
from backend.compiler.pipeline import parse_all
from backend.compiler.resolve import PouSymbols, Resolved, Variable, resolve
from backend.compiler.source import Pos, SourceFile, stdlib_sources
from backend.compiler.types import (
    LREAL,
    ElementaryType,
    EnumType,
    FbType,
    Type,
    common_numeric,
    integer_like,
)

Value = bool | int | float


class Unsupported(Exception):
    """The program uses something outside the oracle's subset."""


class ProgramFault(Exception):
    """A run-time error that stops the program (integer division by zero)."""


class _Flow(Enum):
    """How a statement list ended: normally, or by EXIT, CONTINUE or RETURN."""

    NEXT = "next"
    EXIT = "exit"
    CONTINUE = "continue"
    RETURN = "return"


# ---- values of the elementary types ---------------------------------------------------------

_SINGLE = struct.Struct("<f")


def to_single(value: float) -> float:
    """Round a double to the nearest IEEE 754 single (round half to even), as a REAL holds."""
    try:
        single: float = _SINGLE.unpack(_SINGLE.pack(value))[0]
    except OverflowError:
        # struct refuses exactly the values that round beyond the largest single
        return math.copysign(math.inf, value)
    return single


def int_to_single(value: int) -> float:
    """An integer as a REAL: rounded once, to 24 significant bits, halves to even.

    Going through a double first could round twice for integers beyond 2**53."""
    magnitude = abs(value)
    surplus = magnitude.bit_length() - 24
    if surplus > 0:
        kept, dropped = divmod(magnitude, 1 << surplus)
        half = 1 << (surplus - 1)
        if dropped > half or (dropped == half and kept % 2 == 1):
            kept += 1
        magnitude = kept << surplus
    try:
        return to_single(math.copysign(float(magnitude), value))
    except OverflowError:  # beyond the range of a double: far beyond a single's
        return math.copysign(math.inf, value)


def wrap(value: int, t: ElementaryType) -> int:
    """Two's-complement wrap of an integer into the width of `t` (literals have no width)."""
    if t.is_any_literal or t.bits == 0:
        return value
    modulus = 1 << t.bits
    value %= modulus
    if t.signed and value >= modulus // 2:
        value -= modulus
    return value


def round_half_away(value: float) -> int:
    """REAL to integer: to the nearest integer, halves away from zero; NaN and infinities
    have no integer value and give 0 (the runtime's documented choice)."""
    if math.isnan(value) or math.isinf(value):
        return 0
    whole = math.floor(abs(value))
    # the fraction is exact; adding 0.5 first could round 0.49999999999999994 up to 1
    if abs(value) - whole >= 0.5:
        whole += 1
    return whole if value >= 0 else -whole


def truncating_division(a: int, b: int) -> int:
    if b == 0:
        raise ProgramFault("integer division by zero")
    quotient = abs(a) // abs(b)
    return quotient if (a < 0) == (b < 0) else -quotient


def ieee_division(a: float, b: float) -> float:
    """REAL division as IEEE 754 defines it, including division by zero."""
    if b == 0:
        if a == 0 or math.isnan(a):
            return math.nan
        # the sign of an infinite quotient is the exclusive or of the operands' signs
        return math.copysign(math.inf, a) * math.copysign(1.0, b)
    return a / b


def elementary_of(t: Type) -> ElementaryType:
    found = integer_like(t) if isinstance(t, EnumType) else t
    if not isinstance(found, ElementaryType):
        raise Unsupported(f"type {t.name}")
    if found.category == "string" or found.category == "date":
        raise Unsupported(f"type {found.name}")
    return found


def convert(value: Value, source: Type, target: Type) -> Value:
    """A value of type `source` as a value of type `target` (assignment semantics)."""
    src, dst = elementary_of(source), elementary_of(target)
    if dst.category == "bool":
        return bool(value)
    if dst.category == "real":
        if src.category == "real":
            as_float = float(value)
            return to_single(as_float) if dst.bits == 32 else as_float
        as_int = int(value)
        return int_to_single(as_int) if dst.bits == 32 else float(as_int)
    # integers, bit strings and durations
    if src.category == "real":
        return wrap(round_half_away(float(value)), dst)
    return wrap(int(value), dst)


def initial_value(t: Type) -> Value:
    elementary = elementary_of(t)
    if elementary.category == "bool":
        return False
    if elementary.category == "real":
        return 0.0
    return 0


# ---- instances --------------------------------------------------------------------------------


@dataclass
class Instance:
    """The variables of one PROGRAM or FUNCTION_BLOCK instance, by upper-case name; a
    variable of function block type holds another Instance."""

    pou: PouSymbols
    slots: dict[str, Value | Instance] = field(default_factory=dict)

    def get(self, name: str) -> Value | Instance:
        return self.slots[key(name)]

    def value(self, name: str) -> Value:
        found = self.slots[key(name)]
        if isinstance(found, Instance):
            raise Unsupported(f"'{name}' is a function block instance, not a value")
        return found


def stored_variables(pou: PouSymbols) -> list[Variable]:
    """The variables an instance keeps between calls (what the runtime shows)."""
    return [v for v in pou.variables if v.kind not in ("VAR_GLOBAL", "VAR_TEMP")]


def _has_implicit_eno(pou: PouSymbols) -> bool:
    """Every function block instance has a BOOL ENO, unless the block declares its own."""
    return pou.kind == "FUNCTION_BLOCK" and "ENO" not in pou.by_key


@dataclass
class _Typing:
    """The types of one POU's expressions, from the compiler's own typing rules, each
    asked for once."""

    scope: Scope
    # by node identity: the nodes live as long as the tree (made-up ones see `made_up`)
    cache: dict[int, Type] = field(default_factory=dict)
    made_up: dict[int, ast.Expr] = field(default_factory=dict)

    def derived(self, origin: object, build: Callable[[], ast.Expr]) -> ast.Expr:
        """A node the walker makes up for `origin` (a FOR counter reference, `AND(a, b)` as
        `a AND b`), made once and kept, so that its identity stays its own."""
        found = self.made_up.get(id(origin))
        if found is None:
            found = self.made_up[id(origin)] = build()
        return found

    def of(self, expr: ast.Expr) -> Type:
        found = self.cache.get(id(expr))
        if found is None:
            typed = self.scope.type_of(expr)
            if typed is None:
                raise Unsupported(f"no type for the expression at {expr.pos}")
            self.cache[id(expr)] = found = typed
        return found


@dataclass
class _Frame:
    """What one running POU body sees: its own instance and its typing."""

    instance: Instance
    typing: _Typing

    @property
    def scope(self) -> Scope:
        return self.typing.scope


@dataclass
class _Program:
    name: str
    instance: Instance
    error: str | None = None


_COMPARISONS: dict[str, Callable[[Value, Value], bool]] = {
    "=": lambda a, b: a == b,
    "<>": lambda a, b: a != b,
    "<": lambda a, b: a < b,
    ">": lambda a, b: a > b,
    "<=": lambda a, b: a <= b,
    ">=": lambda a, b: a >= b,
}


class TreeWalker:
    """Runs the PROGRAMs of `sources` cycle by cycle, straight from the syntax tree."""

    def __init__(self, sources: list[SourceFile]) -> None:
        self.resolved, program_pous = _front_end(sources)
        self.now_ns = 0  # what __CURRENT_TIME() gives: time since the first cycle
        self._first_cycle_ns: int | None = None
        self._typings: dict[str, _Typing] = {}
        self.globals = Instance(_globals_pou(self.resolved))
        for variable in self.resolved.globals:
            self.globals.slots[key(variable.name)] = self._initial(variable, self.globals)
        # every PROGRAM is a user program named after its POU, in source order (as the
        # compiler's default configuration has it)
        self.programs = [
            _Program(name, self.new_instance(self.resolved.pous[key(name)]))
            for name in program_pous
        ]

    # ---- the public interface
    def run_cycle(self, now_ns: int) -> None:
        """One CPU cycle at clock time `now_ns`: every program that is not in ERROR runs
        once. Program time starts at 0 in the first cycle."""
        if self._first_cycle_ns is None:
            self._first_cycle_ns = now_ns
        self.now_ns = now_ns - self._first_cycle_ns
        for program in self.programs:
            if program.error is not None:
                continue
            try:
                self.invoke(program.instance)
            except ProgramFault as fault:
                program.error = str(fault)

    def values(self) -> dict[str, object]:
        """Every elementary variable as "Program.var" / "Program.fb.var"."""
        found: dict[str, object] = {}
        for program in self.programs:
            _collect(program.instance, program.name, found)
        return found

    def states(self) -> dict[str, str]:
        return {p.name: "ERROR" if p.error is not None else "RUN" for p in self.programs}

    # ---- instances
    def new_instance(self, pou: PouSymbols) -> Instance:
        instance = Instance(pou)
        for variable in stored_variables(pou):
            instance.slots[key(variable.name)] = self._initial(variable, instance)
        if _has_implicit_eno(pou):
            instance.slots["ENO"] = True
        return instance

    def _initial(self, variable: Variable, owner: Instance) -> Value | Instance:
        if isinstance(variable.type, FbType):
            if variable.init is not None:
                raise Unsupported("initialised function block instances")
            return self.new_instance(self.resolved.pous[key(variable.type.name)])
        if variable.init is None:
            return initial_value(variable.type)
        if not _is_expr(variable.init):
            raise Unsupported("array and structure initializers")
        frame = _Frame(owner, self._typing(owner.pou))
        return convert(
            self.eval(frame, variable.init), frame.typing.of(variable.init), variable.type
        )

    def _typing(self, pou: PouSymbols) -> _Typing:
        found = self._typings.get(key(pou.name))
        if found is None:
            found = self._typings[key(pou.name)] = _Typing(Scope(self.resolved, pou))
        return found

    def invoke(self, instance: Instance) -> None:
        """One call of a function block (or one cycle of a program)."""
        pou = instance.pou
        if _has_implicit_eno(pou):  # IEC: a block that runs sets ENO TRUE
            instance.slots["ENO"] = True
        if key(pou.name) == "TON" and pou.pou.pos.file.startswith("stdlib/"):
            self._ton(instance)
            return
        for variable in pou.variables:
            if variable.kind == "VAR_TEMP":
                instance.slots[key(variable.name)] = self._initial(variable, instance)
        self.block(_Frame(instance, self._typing(pou)), pou.pou.body)

    def _ton(self, timer: Instance) -> None:
        """TON, on-delay: Q follows IN after IN has been TRUE for PT; ET counts up to PT;
        once Q is TRUE, Q and ET hold until IN falls (whatever PT does then)."""
        pou = timer.pou
        time_of = {key(v.name): v.type for v in pou.variables}

        def store(name: str, value: Value) -> None:
            timer.slots[key(name)] = convert(value, time_of[key(name)], time_of[key(name)])

        if timer.value("IN"):
            if not timer.value("running"):
                store("running", True)
                store("start", self.now_ns)
            if not timer.value("Q"):
                store("ET", int(self.now_ns) - int(timer.value("start")))
                if int(timer.value("ET")) >= int(timer.value("PT")):
                    store("ET", timer.value("PT"))
                    store("Q", True)
        else:
            store("running", False)
            store("Q", False)
            store("ET", 0)

    # ---- statements
    def block(self, frame: _Frame, statements: tuple[ast.Statement, ...]) -> _Flow:
        for statement in statements:
            flow = self.statement(frame, statement)
            if flow is not _Flow.NEXT:
                return flow
        return _Flow.NEXT

    def statement(self, frame: _Frame, statement: ast.Statement) -> _Flow:
        match statement:
            case ast.Assign(target=target, value=value):
                if not _is_expr(value):
                    raise Unsupported("array and structure initializers in assignments")
                result = self.eval(frame, value)
                target_type = frame.typing.of(target)
                self.store(frame, target, convert(result, frame.typing.of(value), target_type))
            case ast.CallStatement(call=call):
                self.call_statement(frame, call)
            case ast.ExprStatement(expr=expr):
                self.eval(frame, expr)  # CODESYS: evaluated, the value dropped
            case ast.If(branches=branches, orelse=orelse):
                for condition, body in branches:
                    if self.eval(frame, condition):
                        return self.block(frame, body)
                return self.block(frame, orelse)
            case ast.Case():
                return self.case(frame, statement)
            case ast.For():
                return self.for_loop(frame, statement)
            case ast.While(condition=condition, body=body):
                while self.eval(frame, condition):
                    flow = self.block(frame, body)
                    if flow is _Flow.EXIT:
                        break
                    if flow is _Flow.RETURN:
                        return flow
            case ast.Repeat(body=body, until=until):
                while True:
                    flow = self.block(frame, body)
                    if flow is _Flow.EXIT:
                        break
                    if flow is _Flow.RETURN:
                        return flow
                    if self.eval(frame, until):
                        break
            case ast.Exit():
                return _Flow.EXIT
            case ast.Continue():
                return _Flow.CONTINUE
            case ast.Return():
                return _Flow.RETURN
        return _Flow.NEXT

    def case(self, frame: _Frame, case: ast.Case) -> _Flow:
        selector = self.eval(frame, case.selector)  # evaluated once
        for labels, body in case.branches:
            for label in labels:
                if isinstance(label, ast.CaseRange):
                    low, high = self.eval(frame, label.low), self.eval(frame, label.high)
                    matched = low <= selector <= high
                else:
                    matched = selector == self.eval(frame, label)
                if matched:
                    return self.block(frame, body)
        return self.block(frame, case.orelse)

    def for_loop(self, frame: _Frame, loop: ast.For) -> _Flow:
        """FOR: the end and the step are evaluated before every test of the counter; the
        loop ends when the counter passes the end, or when the next value would not fit the
        counter's type (instead of wrapping around and running forever)."""
        counter_ref = frame.typing.derived(loop, lambda: ast.NameRef(loop.variable, loop.pos))
        counter_type = elementary_of(frame.typing.of(counter_ref))
        start = self.eval(frame, loop.start)
        self.store(frame, counter_ref, convert(start, frame.typing.of(loop.start), counter_type))
        step: Value = 1
        first = True
        while True:
            if not first:
                following = int(self.eval(frame, counter_ref)) + int(step)
                if wrap(following, counter_type) != following:
                    self.store(frame, counter_ref, wrap(following, counter_type))
                    break
                self.store(frame, counter_ref, following)
            first = False
            if loop.step is not None:
                step = self.eval(frame, loop.step)
            counter = self.eval(frame, counter_ref)
            stop = self.eval(frame, loop.stop)
            if not (counter <= stop if step >= 0 else counter >= stop):
                break
            flow = self.block(frame, loop.body)
            if flow is _Flow.EXIT:
                break
            if flow is _Flow.RETURN:
                return flow
        return _Flow.NEXT

    def call_statement(self, frame: _Frame, call: ast.Call) -> None:
        binding = frame.scope.lookup(call.name) if call.receiver is None else None
        if not (isinstance(binding, Variable) and isinstance(binding.type, FbType)):
            self.eval(frame, call)  # a function called for its effect
            return
        instance = self._read(frame, binding)
        assert isinstance(instance, Instance)
        outputs: list[tuple[ast.Argument, Variable]] = []
        # inputs are evaluated and set one by one, in the order the call names them
        for arg, param in frame.scope.connect_arguments(instance.pou, call):
            if arg.value is None or param is None:
                continue
            if key(param.name) in ("EN", "ENO"):
                raise Unsupported("EN/ENO")
            if arg.is_output or param.kind == "VAR_OUTPUT":
                outputs.append((arg, param))
                continue
            if param.kind == "VAR_IN_OUT":
                raise Unsupported("VAR_IN_OUT")
            value = self.eval(frame, arg.value)
            instance.slots[key(param.name)] = convert(value, frame.typing.of(arg.value), param.type)
        self.invoke(instance)
        # an output connected with => is assigned to its variable like any other value
        for arg, param in outputs:
            assert arg.value is not None
            result = instance.value(param.name)
            if arg.negated:
                result = not result
            target_type = frame.typing.of(arg.value)
            self.store(frame, arg.value, convert(result, param.type, target_type))

    # ---- variables
    def _read(self, frame: _Frame, variable: Variable) -> Value | Instance:
        owner = self.globals if variable.kind == "VAR_GLOBAL" else frame.instance
        return owner.get(variable.name)

    def store(self, frame: _Frame, target: ast.Expr, value: Value) -> None:
        """Store an already converted value."""
        match target:
            case ast.NameRef(name=name):
                variable = frame.scope.variable(name)
                if variable is None:
                    raise Unsupported(f"assignment to '{name}'")
                owner = self.globals if variable.kind == "VAR_GLOBAL" else frame.instance
                owner.slots[key(name)] = value
            case ast.MemberRef(base=base, member=member):
                instance = self.eval_instance(frame, base)
                instance.slots[key(member)] = value
            case _:
                raise Unsupported(f"assignment to {type(target).__name__}")

    def eval_instance(self, frame: _Frame, expr: ast.Expr) -> Instance:
        match expr:
            case ast.NameRef(name=name):
                variable = frame.scope.variable(name)
                if variable is not None:
                    found = self._read(frame, variable)
                    if isinstance(found, Instance):
                        return found
            case ast.MemberRef(base=base, member=member):
                found = self.eval_instance(frame, base).get(member)
                if isinstance(found, Instance):
                    return found
        raise Unsupported(f"not a function block instance at {expr.pos}")

    # ---- expressions
    def eval(self, frame: _Frame, expr: ast.Expr) -> Value:
        match expr:
            case ast.IntLiteral(value=value):
                # an untyped literal keeps its exact value until an operation or a store
                # gives it a type; a typed one (INT#5) is a value of its type
                return convert(value, frame.typing.of(expr), frame.typing.of(expr))
            case ast.RealLiteral(value=value):
                literal_type = elementary_of(frame.typing.of(expr))
                if literal_type.category != "real":
                    raise Unsupported("typed REAL literal of a non-REAL type")
                return to_single(value) if literal_type.name == "REAL" else value
            case ast.BoolLiteral(value=value):
                return value
            case ast.TimeLiteral(nanoseconds=nanoseconds, type_name=type_name):
                if type_name not in ("TIME", "LTIME"):
                    raise Unsupported(type_name)
                return nanoseconds
            case ast.NameRef(name=name):
                binding = frame.scope.lookup(name)
                if isinstance(binding, EnumValue | NonFinite):
                    return binding.value
                if binding is None or isinstance(binding, ProgramRef):
                    raise Unsupported(f"'{name}' as a value")
                found = self._read(frame, binding)
                if isinstance(found, Instance):
                    raise Unsupported(f"'{name}' as a value")
                return found
            case ast.MemberRef(base=base, member=member):
                return self.eval_instance(frame, base).value(member)
            case ast.Unary():
                return self.unary(frame, expr)
            case ast.Binary():
                return self.binary(frame, expr)
            case ast.Call(name=name) if key(name) == "__CURRENT_TIME" and not expr.args:
                return self.now_ns
            case ast.Call(name=name) if key(name) in _OPERATOR_CALLS:
                return self.operator_call(frame, expr)
        raise Unsupported(f"{type(expr).__name__} at {expr.pos}")

    def operator_call(self, frame: _Frame, call: ast.Call) -> Value:
        """`NOT(x)`, `AND(a, b, ...)`, `MOD(a, b)`: the operators written as functions."""
        args = [arg.value for arg in call.args]
        if any(arg.name is not None for arg in call.args) or None in args:
            raise Unsupported(f"named arguments of {call.name}")
        operands = [arg for arg in args if arg is not None]
        name = key(call.name)
        if name == "NOT" and len(operands) == 1:
            return self.eval(
                frame, frame.typing.derived(call, lambda: ast.Unary(name, operands[0], call.pos))
            )
        if len(operands) < 2 or (name == "MOD" and len(operands) != 2):
            raise Unsupported(f"{call.name} with {len(operands)} arguments")

        def folded() -> ast.Expr:  # AND(a, b, c) is (a AND b) AND c
            result = operands[0]
            for operand in operands[1:]:
                result = ast.Binary(name, result, operand, call.pos)
            return result

        return self.eval(frame, frame.typing.derived(call, folded))

    def unary(self, frame: _Frame, expr: ast.Unary) -> Value:
        result_type = elementary_of(frame.typing.of(expr))
        operand = self.eval(frame, expr.operand)
        if expr.op == "+":
            return operand
        if expr.op == "NOT":
            if result_type.category == "bool":
                return not operand
            return wrap(~int(operand), result_type)
        if result_type.category == "real":
            return -float(operand)
        return wrap(-int(operand), result_type)

    def binary(self, frame: _Frame, expr: ast.Binary) -> Value:
        op = expr.op
        left_type, right_type = frame.typing.of(expr.left), frame.typing.of(expr.right)
        # both operands are always evaluated, left first (ST has no short circuit)
        left, right = self.eval(frame, expr.left), self.eval(frame, expr.right)
        if op in _COMPARISONS:
            return _compare(op, left, right, left_type, right_type)
        result_type = elementary_of(frame.typing.of(expr))
        a = convert(left, left_type, result_type)
        b = convert(right, right_type, result_type)
        if op in ("AND", "&", "OR", "XOR"):
            return _logic(op, a, b, result_type)
        if result_type.category == "real":
            return _real_arithmetic(op, float(a), float(b), result_type)
        if result_type.category == "time" and op in ("*", "/"):
            raise Unsupported("TIME scaled by a number")
        if result_type.category == "time" and not (
            elementary_of(left_type).category == elementary_of(right_type).category == "time"
        ):
            raise Unsupported("TIME combined with a number")
        return wrap(_integer_arithmetic(op, int(a), int(b)), result_type)


_OPERATOR_CALLS = ("NOT", "AND", "OR", "XOR", "MOD")


def _logic(op: str, a: Value, b: Value, result_type: ElementaryType) -> Value:
    """AND, OR, XOR: on BOOLs, or bit by bit on integers and bit strings."""
    if result_type.category == "bool":
        if op == "OR":
            return bool(a) or bool(b)
        if op == "XOR":
            return bool(a) != bool(b)
        return bool(a) and bool(b)
    if op == "OR":
        return wrap(int(a) | int(b), result_type)
    if op == "XOR":
        return wrap(int(a) ^ int(b), result_type)
    return wrap(int(a) & int(b), result_type)


def _compare(op: str, left: Value, right: Value, left_type: Type, right_type: Type) -> bool:
    """Comparison in the common type of the operands: an integer compared with a REAL is
    first converted to REAL; integers (and BOOLs, durations) are compared by value."""
    a_type, b_type = elementary_of(left_type), elementary_of(right_type)
    common = common_numeric(a_type, b_type)
    if common is not None and common.category == "real":
        concrete = LREAL if common.is_any_literal else common
        left, right = convert(left, a_type, concrete), convert(right, b_type, concrete)
    return _COMPARISONS[op](left, right)


def _real_arithmetic(op: str, a: float, b: float, result_type: ElementaryType) -> float:
    # a double holds the exact sum, difference or product of two singles, and rounds their
    # quotient so closely that rounding it once more to single is the correctly rounded
    # single result: so computing in double and rounding once gives IEC REAL arithmetic
    if op == "+":
        result = a + b
    elif op == "-":
        result = a - b
    elif op == "*":
        result = a * b
    elif op == "/":
        result = ieee_division(a, b)
    else:
        raise Unsupported(f"REAL operator {op}")
    return to_single(result) if result_type.bits == 32 else result


def _integer_arithmetic(op: str, a: int, b: int) -> int:
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if op == "/":
        return truncating_division(a, b)
    if op == "MOD":
        # the remainder has the sign of the dividend: a = (a / b) * b + a MOD b
        return a - b * truncating_division(a, b)
    raise Unsupported(f"integer operator {op}")


def _is_expr(init: ast.Initializer) -> TypeGuard[ast.Expr]:
    return not isinstance(init, ast.ArrayInit | ast.StructInit)


def _collect(instance: Instance, prefix: str, out: dict[str, object]) -> None:
    for variable in stored_variables(instance.pou):
        found = instance.get(variable.name)
        path = f"{prefix}.{variable.name}"
        if isinstance(found, Instance):
            _collect(found, path, out)
        else:
            out[path] = found
    if _has_implicit_eno(instance.pou):
        out[f"{prefix}.ENO"] = instance.get("ENO")


def _front_end(sources: list[SourceFile]) -> tuple[Resolved, list[str]]:
    """Parse, resolve and check as the compiler does (the standard library included; a user
    POU of the same name replaces a standard one); refuse a program with errors. Also gives
    the names of the user's PROGRAMs in source order."""
    units, diagnostics = parse_all(sources)
    if any(unit.configurations for unit in units):
        raise Unsupported("CONFIGURATION (the walker runs every PROGRAM once per cycle)")
    programs = [p.name for unit in units for p in unit.pous if p.kind == "PROGRAM"]
    user_pous = {key(p.name) for unit in units for p in unit.pous}
    for unit in _standard_library():
        kept = tuple(p for p in unit.pous if key(p.name) not in user_pous)
        units.append(ast.SourceUnit(unit.file, kept, unit.globals, unit.types))
    resolved = resolve(units)
    diagnostics.extend(resolved.diagnostics)
    diagnostics.extend(check(resolved))
    errors = [str(d) for d in diagnostics if d.severity == "error"]
    if errors:
        raise ValueError("the program has errors:\n" + "\n".join(errors))
    return resolved, programs


@functools.cache
def _standard_library() -> tuple[ast.SourceUnit, ...]:
    """The standard library parsed once per process, as the compiler parses it once: its
    syntax tree is immutable, and each walker takes what it needs of it (parsed afresh for
    each walker, it cost a random program's walker more than the rest of its front end)."""
    library, _ = parse_all(stdlib_sources())
    return tuple(library)


def _globals_pou(resolved: Resolved) -> PouSymbols:
    """A stand-in POU whose variables are the globals (so that globals are an Instance)."""
    pou = ast.Pou("GLOBALS", "GLOBALS", None, (), (), Pos("", 1, 1))
    return PouSymbols(pou, list(resolved.globals), {key(v.name): v for v in resolved.globals})
