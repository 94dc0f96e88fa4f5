"""Expression typing, shared by the check stage (which reports) and generate (which trusts).

`Scope` answers what a name means inside one POU; `type_of` gives an expression's type and
records a diagnostic for everything that is wrong with it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.diagnostics import Diagnostic, error
from backend.compiler.resolve import PouSymbols, Resolved, Variable
from backend.compiler.types import (
    ANY_INT,
    ANY_REAL,
    BOOL,
    ELEMENTARY,
    LTIME,
    STRING,
    TIME,
    ElementaryType,
    FbType,
    Type,
    common_numeric,
)

# Functions the runtime provides directly (name -> return type).
BUILTIN_FUNCTIONS: dict[str, ElementaryType] = {
    "__CURRENT_TIME": TIME,
}


@dataclass
class Scope:
    resolved: Resolved
    pou: PouSymbols
    diagnostics: list[Diagnostic] = field(default_factory=list)

    def variable(self, name: str) -> Variable | None:
        return self.pou.by_key.get(key(name))

    def fb_symbols(self, fb: FbType) -> PouSymbols:
        return self.resolved.pous[key(fb.name)]

    def report(self, pos: ast.Pos, message: str) -> None:
        self.diagnostics.append(error(pos, message))

    # ---- typing
    def type_of(self, expr: ast.Expr) -> Type | None:
        match expr:
            case ast.IntLiteral():
                return ANY_INT
            case ast.RealLiteral():
                return ANY_REAL
            case ast.BoolLiteral():
                return BOOL
            case ast.TimeLiteral(long=long):
                return LTIME if long else TIME
            case ast.StringLiteral():
                return STRING
            case ast.NameRef(name=name, pos=pos):
                variable = self.variable(name)
                if variable is None:
                    self.report(pos, f"'{name}' is not declared")
                    return None
                return variable.type
            case ast.MemberRef():
                member = self.member(expr)
                return member.type if member is not None else None
            case ast.Unary():
                return self._unary(expr)
            case ast.Binary():
                return self._binary(expr)
            case ast.Call():
                return self.call_type(expr)
        raise AssertionError(f"unhandled expression {expr!r}")

    def member(self, expr: ast.MemberRef) -> Variable | None:
        base_type = self.type_of(expr.base)
        if base_type is None:
            return None
        if not isinstance(base_type, FbType):
            self.report(expr.pos, f"'{base_type.name}' has no member '{expr.member}'")
            return None
        member = self.fb_symbols(base_type).by_key.get(key(expr.member))
        if member is None or member.kind not in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT"):
            self.report(expr.pos, f"function block '{base_type.name}' has no '{expr.member}'")
            return None
        return member

    def _unary(self, expr: ast.Unary) -> Type | None:
        operand = self.type_of(expr.operand)
        if operand is None:
            return None
        if not isinstance(operand, ElementaryType):
            self.report(expr.pos, f"'{expr.op}' cannot be applied to '{operand.name}'")
            return None
        if expr.op == "NOT" and operand.category in ("bool", "bits"):
            return operand
        if expr.op == "-" and (operand.category in ("int", "real", "time")):
            return operand
        self.report(expr.pos, f"'{expr.op}' cannot be applied to {operand.name}")
        return None

    def _binary(self, expr: ast.Binary) -> Type | None:
        left, right = self.type_of(expr.left), self.type_of(expr.right)
        if left is None or right is None:
            return None
        if not isinstance(left, ElementaryType) or not isinstance(right, ElementaryType):
            self.report(expr.pos, f"'{expr.op}' cannot be applied to {left.name}, {right.name}")
            return None
        op = expr.op
        mismatch = f"'{op}' cannot be applied to {left.name} and {right.name}"
        if op in ("AND", "OR", "XOR", "&"):
            if left == right and left.category in ("bool", "bits"):
                return left
            joined = common_numeric(left, right)
            if joined is not None and joined.category == "bits":
                return joined
            self.report(expr.pos, mismatch)
            return None
        if op in ("=", "<>", "<", ">", "<=", ">="):
            comparable = (
                common_numeric(left, right) is not None
                or (left.category == right.category and left.category in ("time", "string"))
                or (left == right == BOOL)
            )
            if not comparable:
                self.report(expr.pos, mismatch)
            return BOOL
        if left.category == "time" or right.category == "time":
            return self._time_arithmetic(expr, left, right, mismatch)
        joined = common_numeric(left, right)
        if joined is None or joined.category not in ("int", "real", "bits"):
            self.report(expr.pos, mismatch)
            return None
        if op == "**":
            return joined if joined.category == "real" else ELEMENTARY["LREAL"]
        if op == "MOD" and joined.category == "real":
            self.report(expr.pos, mismatch)
            return None
        return joined

    def _time_arithmetic(
        self, expr: ast.Binary, left: ElementaryType, right: ElementaryType, mismatch: str
    ) -> Type | None:
        if expr.op in ("+", "-") and left.category == right.category == "time":
            return LTIME if LTIME in (left, right) else TIME
        if expr.op in ("*", "/") and left.category == "time" and right.is_numeric:
            return left
        if expr.op == "*" and right.category == "time" and left.is_numeric:
            return right
        self.report(expr.pos, mismatch)
        return None

    def call_type(self, call: ast.Call) -> Type | None:
        builtin = BUILTIN_FUNCTIONS.get(key(call.name))
        if builtin is not None:
            for arg in call.args:
                self.type_of(arg.value)
            if call.args:
                self.report(call.pos, f"'{call.name}' takes no arguments")
            return builtin
        variable = self.variable(call.name)
        if variable is not None and isinstance(variable.type, FbType):
            self.report(call.pos, f"function block instance '{call.name}' has no value")
            return None
        self.report(call.pos, f"'{call.name}' is not a function")
        return None
