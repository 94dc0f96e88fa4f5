"""Stage 4, generate: one Python class (PROGRAM, FUNCTION_BLOCK) or function per POU.

The generated source is the compiled code: the runtime executes it with the intrinsics
of `runtime.intrinsics` in scope, and the CRCs are taken over it. Integers are wrapped
to their width only where the result is consumed (a store, a comparison, a division,
an argument), never after each + - *, since wrapping commutes with those.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.infer import Scope
from backend.compiler.resolve import PouSymbols, Resolved, Variable
from backend.compiler.types import (
    ANY_INT,
    ANY_REAL,
    BOOL,
    ElementaryType,
    FbType,
    Type,
)

INDENT = "    "
_COMPARE = {"=": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}


def class_name(pou_name: str) -> str:
    return f"POU_{key(pou_name)}"


def default_value(var_type: Type) -> str:
    if isinstance(var_type, FbType):
        return f"{class_name(var_type.name)}()"
    match var_type.category:
        case "bool":
            return "False"
        case "real":
            return "0.0"
        case "string":
            return "''"
    return "0"


def wrap(code: str, var_type: ElementaryType) -> str:
    """Bring an integer expression back into the range of its type (two's complement)."""
    if var_type.category == "time" or (var_type.is_integer and var_type not in (ANY_INT,)):
        mask = (1 << var_type.bits) - 1
        if var_type.signed:
            half = 1 << (var_type.bits - 1)
            return f"((({code}) + {half} & {mask}) - {half})"
        return f"(({code}) & {mask})"
    return code


@dataclass
class _Value:
    code: str
    type: Type
    unwrapped: bool = False  # an integer result that may lie outside its type's range


@dataclass
class _Emitter:
    scope: Scope
    local: bool  # a FUNCTION: variables are Python locals, not attributes of `s`
    lines: list[str] = field(default_factory=list)
    temp_count: int = 0

    def emit(self, depth: int, line: str) -> None:
        self.lines.append(INDENT * depth + line)

    def temp(self) -> str:
        self.temp_count += 1
        return f"_t{self.temp_count}"

    # ---- expressions
    def var_code(self, variable: Variable) -> str:
        return variable.attr if self.local else f"s.{variable.attr}"

    def exact(self, expr: ast.Expr) -> _Value:
        value = self.expr(expr)
        if value.unwrapped and isinstance(value.type, ElementaryType):
            return _Value(wrap(value.code, value.type), value.type)
        return value

    def expr(self, expr: ast.Expr) -> _Value:
        match expr:
            case ast.IntLiteral(value=v):
                return _Value(repr(v), ANY_INT)
            case ast.RealLiteral(value=v):
                return _Value(repr(v), ANY_REAL)
            case ast.BoolLiteral(value=v):
                return _Value(repr(v), BOOL)
            case ast.TimeLiteral(nanoseconds=ns):
                return _Value(repr(ns), _type(self.scope, expr))
            case ast.StringLiteral(value=v):
                return _Value(repr(v), _type(self.scope, expr))
            case ast.NameRef(name=name):
                variable = self.scope.variable(name)
                assert variable is not None
                return _Value(self.var_code(variable), variable.type)
            case ast.MemberRef(base=base, member=_):
                member = self.scope.member(expr)
                assert member is not None
                return _Value(f"{self.expr(base).code}.{member.attr}", member.type)
            case ast.Unary():
                return self._unary(expr)
            case ast.Binary():
                return self._binary(expr)
            case ast.Call():
                return self._call(expr)
        raise AssertionError(f"unhandled expression {expr!r}")

    def _unary(self, expr: ast.Unary) -> _Value:
        result = _elementary(self.scope, expr)
        operand = self.expr(expr.operand)
        if expr.op == "NOT":
            if result == BOOL:
                return _Value(f"(not {operand.code})", BOOL)
            return _Value(f"({self.exact(expr.operand).code} ^ {(1 << result.bits) - 1})", result)
        return _Value(f"(-{operand.code})", result, result.category in ("int", "bits", "time"))

    def _binary(self, expr: ast.Binary) -> _Value:
        result = _elementary(self.scope, expr)
        op = expr.op
        if op in _COMPARE:
            left, right = self.exact(expr.left), self.exact(expr.right)
            return _Value(f"({left.code} {_COMPARE[op]} {right.code})", BOOL)
        if op in ("AND", "&", "OR", "XOR"):
            left, right = self.exact(expr.left), self.exact(expr.right)
            symbol = {"AND": "&", "&": "&", "OR": "|", "XOR": "^"}[op]
            return _Value(f"({left.code} {symbol} {right.code})", result)
        integral = result.category in ("int", "bits", "time")
        if op in ("+", "-", "*") and not (op == "*" and result.category == "time"):
            left, right = self.expr(expr.left), self.expr(expr.right)
            return _Value(f"({left.code} {op} {right.code})", result, integral)
        left, right = self.exact(expr.left), self.exact(expr.right)
        if op == "*":  # TIME * number
            return _Value(f"int({left.code} * {right.code})", result, True)
        if op == "/":
            if result.category == "real":
                return _Value(f"_fdiv({left.code}, {right.code})", result)
            if result.category == "time":
                return _Value(f"_tdiv({left.code}, {right.code})", result, True)
            return _Value(f"_idiv({left.code}, {right.code})", result, True)
        if op == "MOD":
            return _Value(f"_imod({left.code}, {right.code})", result)
        if op == "**":
            return _Value(f"_pow({left.code}, {right.code})", result)
        raise AssertionError(f"unhandled operator {op}")

    def _call(self, call: ast.Call) -> _Value:
        if key(call.name) == "__CURRENT_TIME":
            return _Value("_SYS.now_ns", _type(self.scope, call))
        raise AssertionError(f"unhandled call {call.name}")

    def converted(self, target: Type, value_expr: ast.Expr) -> str:
        """Code for `value_expr` stored into a variable of type `target`."""
        value = self.exact(value_expr)
        if isinstance(target, ElementaryType) and target.category == "real":
            source = value.type
            if isinstance(source, ElementaryType) and source.category != "real":
                return f"float({value.code})"
            if target.bits == 32 and source != target:
                return f"_f32({value.code})"
        return value.code

    # ---- statements
    def block(self, statements: tuple[ast.Statement, ...], depth: int) -> None:
        start = len(self.lines)
        for statement in statements:
            self.statement(statement, depth)
        if len(self.lines) == start:
            self.emit(depth, "pass")

    def statement(self, statement: ast.Statement, depth: int) -> None:
        match statement:
            case ast.Assign(target=target, value=value):
                target_type = _type(self.scope, target)
                self.emit(depth, f"{self.expr(target).code} = {self.converted(target_type, value)}")
            case ast.CallStatement(call=call):
                self.call_statement(call, depth)
            case ast.If(branches=branches, orelse=orelse):
                for index, (condition, body) in enumerate(branches):
                    keyword = "if" if index == 0 else "elif"
                    self.emit(depth, f"{keyword} {self.exact(condition).code}:")
                    self.block(body, depth + 1)
                if orelse:
                    self.emit(depth, "else:")
                    self.block(orelse, depth + 1)
            case ast.While(condition=condition, body=body):
                self.emit(depth, f"while {self.exact(condition).code}:")
                self.block(body, depth + 1)
            case ast.Repeat(body=body, until=until):
                self.emit(depth, "while True:")
                self.block(body, depth + 1)
                self.emit(depth + 1, f"if {self.exact(until).code}:")
                self.emit(depth + 2, "break")
            case ast.For():
                self.for_loop(statement, depth)
            case ast.Exit():
                self.emit(depth, "break")
            case ast.Return():
                self.emit(depth, "return")

    def for_loop(self, loop: ast.For, depth: int) -> None:
        counter = self.scope.variable(loop.variable)
        assert counter is not None and isinstance(counter.type, ElementaryType)
        ref = self.var_code(counter)
        step_code = self.exact(loop.step).code if loop.step is not None else "1"
        self.emit(depth, f"{ref} = {self.converted(counter.type, loop.start)}")
        stop = self.exact(loop.stop).code
        if loop.step is None or isinstance(loop.step, ast.IntLiteral):
            test = f"{ref} <= {stop}"
        elif isinstance(loop.step, ast.Unary) and isinstance(loop.step.operand, ast.IntLiteral):
            test = f"{ref} >= {stop}"
        else:
            step_var = self.temp()
            self.emit(depth, f"{step_var} = {step_code}")
            step_code = step_var
            test = f"({ref} <= {stop}) if {step_var} >= 0 else ({ref} >= {stop})"
        self.emit(depth, f"while {test}:")
        self.block(loop.body, depth + 1)
        self.emit(depth + 1, f"{ref} = {wrap(f'{ref} + {step_code}', counter.type)}")

    def call_statement(self, call: ast.Call, depth: int) -> None:
        instance = self.scope.variable(call.name)
        if instance is None or not isinstance(instance.type, FbType):
            self.emit(depth, self.exact(call).code)
            return
        fb = self.scope.fb_symbols(instance.type)
        handle = self.temp()
        self.emit(depth, f"{handle} = {self.var_code(instance)}")
        outputs: list[tuple[ast.Expr, Variable]] = []
        for arg in call.args:
            assert arg.name is not None
            param = fb.by_key[key(arg.name)]
            if arg.is_output:
                outputs.append((arg.value, param))
            else:
                self.emit(depth, f"{handle}.{param.attr} = {self.converted(param.type, arg.value)}")
        self.emit(depth, f"{handle}()")
        for target, param in outputs:
            self.emit(depth, f"{self.expr(target).code} = {handle}.{param.attr}")


def _type(scope: Scope, expr: ast.Expr) -> Type:
    result = scope.type_of(expr)
    assert result is not None, f"generate called on unchecked code at {expr.pos}"
    return result


def _elementary(scope: Scope, expr: ast.Expr) -> ElementaryType:
    result = _type(scope, expr)
    assert isinstance(result, ElementaryType)
    return result


def generate_pou(resolved: Resolved, pou: PouSymbols) -> str:
    """The Python source of one POU."""
    scope = Scope(resolved, pou)
    if pou.kind == "FUNCTION":
        raise NotImplementedError("functions are generated from the compiler issue on")
    emitter = _Emitter(scope, local=False)
    emitter.emit(0, f"class {class_name(pou.name)}:")
    emitter.emit(1, f"__slots__ = {tuple(v.attr for v in pou.variables)!r}")
    emitter.emit(0, "")
    emitter.emit(1, "def __init__(s):")
    if not pou.variables:
        emitter.emit(2, "pass")
    for variable in pou.variables:
        if variable.init is not None:
            code = emitter.converted(variable.type, variable.init)
        else:
            code = default_value(variable.type)
        emitter.emit(2, f"s.{variable.attr} = {code}")
    emitter.emit(0, "")
    emitter.emit(1, "def __call__(s):")
    emitter.block(pou.pou.body, 2)
    return "\n".join(emitter.lines) + "\n"
