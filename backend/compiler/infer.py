"""Expression typing and name lookup, shared by check (which reports) and generate (which
trusts checked code).

`Scope` answers what a name means inside one POU and gives every expression its type,
recording a diagnostic for everything that is wrong with it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from backend.compiler import ast, builtins
from backend.compiler.ast import key
from backend.compiler.constants import fold_int, guarded
from backend.compiler.diagnostics import Diagnostic, error, warning
from backend.compiler.resolve import PouSymbols, Resolved, StructInfo, Variable
from backend.compiler.source import Pos
from backend.compiler.types import (
    ANY_INT,
    ANY_REAL,
    BOOL,
    BYTE,
    DWORD,
    ELEMENTARY,
    LTIME,
    STRING,
    TIME,
    WORD,
    WSTRING,
    ArrayType,
    ElementaryType,
    EnumType,
    FbType,
    StructType,
    Type,
    VariadicType,
    assignable,
    common_numeric,
    elementary,
    integer_like,
)
from runtime.contract.system_variables import NAMESPACE


@dataclass(frozen=True)
class EnumValue:
    type: EnumType
    value: int


@dataclass(frozen=True)
class ProgramRef:
    pou: PouSymbols


Binding = Variable | EnumValue | ProgramRef


@dataclass
class Scope:
    resolved: Resolved
    pou: PouSymbols
    diagnostics: list[Diagnostic] = field(default_factory=list)
    # by id() of the node; the node is kept alongside so its id cannot be reused
    _types: dict[int, tuple[Type | None, ast.Expr]] = field(default_factory=dict)
    # enum values named without their type, resolved from where they are used
    _enum_hints: dict[int, tuple[EnumValue, ast.Expr]] = field(default_factory=dict)

    # ---- names
    def variable(self, name: str) -> Variable | None:
        found = self.pou.by_key.get(key(name))
        if found is not None:
            return found
        return self.resolved.globals_by_key.get(key(name))

    def lookup(self, name: str) -> Binding | None:
        found = self.variable(name)
        if found is not None:
            return found
        matches = self.resolved.enum_values_named(name)
        if matches:
            info, value = matches[0]
            return EnumValue(info.type, value)
        pou = self.resolved.pous.get(key(name))
        if pou is not None and pou.kind == "PROGRAM":
            return ProgramRef(pou)
        return None

    def system_namespace(self, expr: ast.Expr) -> bool:
        """`expr` is the name SYS of the system variables (`SYS.COLDSTART`): no declaration
        of the user hides it (a variable, enum value or program here; a type, POU or global
        in resolve, which then leaves `resolved.system` empty)."""
        return (
            isinstance(expr, ast.NameRef)
            and key(expr.name) == NAMESPACE
            and bool(self.resolved.system)
            and self.lookup(expr.name) is None
        )

    def refuse_system_write(self, target: ast.Expr) -> bool:
        """Report a write to a read-only system variable (assignment, output, in-out);
        True when `target` is one."""
        while isinstance(target, ast.BitRef | ast.IndexRef):
            target = target.base
        if not isinstance(target, ast.MemberRef) or not self.system_namespace(target.base):
            return False
        self.type_of(target)  # reports an unknown name, once
        variable = self.resolved.system.get(key(target.member))
        if variable is None or not variable.constant:
            return False
        self.report(target.pos, f"{NAMESPACE}.{variable.name} is a read-only system variable")
        return True

    def expect(self, expr: ast.Initializer, target: Type | None) -> None:
        """`expr` is used where a value of `target` is wanted: an unqualified enum value
        that several enums define means the one of `target` (`c := XXXX`)."""
        if not isinstance(expr, ast.NameRef) or not isinstance(target, EnumType):
            return
        if self.variable(expr.name) is not None or id(expr) in self._types:
            return
        info = self.resolved.enums.get(key(target.name))
        if info is not None and key(expr.name) in info.values:
            self._enum_hints[id(expr)] = (
                EnumValue(info.type, info.values[key(expr.name)][1]),
                expr,
            )

    def _bare_name(self, expr: ast.Expr) -> bool:
        """A name that is no variable: it may be an enum value to resolve from context."""
        return isinstance(expr, ast.NameRef) and self.variable(expr.name) is None

    def enum_hint(self, expr: ast.Expr) -> EnumValue | None:
        hint = self._enum_hints.get(id(expr))
        return hint[0] if hint is not None else None

    def fb_symbols(self, fb: FbType) -> PouSymbols:
        return self.resolved.pous[key(fb.name)]

    def struct(self, struct: StructType) -> StructInfo:
        return self.resolved.structs[key(struct.name)]

    def report(self, pos: Pos, message: str) -> None:
        self.diagnostics.append(error(pos, message))

    def warn(self, pos: Pos, message: str) -> None:
        self.diagnostics.append(warning(pos, message))

    # ---- typing
    def type_of(self, expr: ast.Expr) -> Type | None:
        """The type of `expr`; computed (and its problems reported) once per node."""
        node = id(expr)
        if node not in self._types:
            self._types[node] = (self._compute_type(expr), expr)
        return self._types[node][0]

    def _compute_type(self, expr: ast.Expr) -> Type | None:
        match expr:
            case ast.IntLiteral(type_name=type_name):
                return self._literal_type(type_name, ANY_INT, expr.pos, ("int", "bits", "real"))
            case ast.RealLiteral(type_name=type_name):
                return self._literal_type(type_name, ANY_REAL, expr.pos, ("real",))
            case ast.BoolLiteral(type_name=type_name):
                return self._literal_type(type_name, BOOL, expr.pos, ("bool",))
            case ast.TimeLiteral(type_name=type_name):
                return ELEMENTARY.get(type_name, TIME)
            case ast.StringLiteral(wide=wide, type_name=type_name):
                if type_name is not None:
                    return self._literal_type(type_name, STRING, expr.pos, ("string",))
                return WSTRING if wide else STRING
            case ast.EnumLiteral():
                return self._enum_literal(expr)
            case ast.NameRef(name=name, pos=pos):
                binding = self.enum_hint(expr) or self.lookup(name)
                if binding is None and self.system_namespace(expr):
                    self.report(
                        pos, f"{name} holds the system variables; name one, as in {name}.COLDSTART"
                    )
                    return None
                if binding is None:
                    self.report(pos, f"'{name}' is not declared")
                    return None
                if isinstance(binding, Variable):
                    return binding.type
                if isinstance(binding, EnumValue):
                    return binding.type
                return FbType(binding.pou.name)
            case ast.MemberRef():
                member = self.member(expr)
                return member.type if member is not None else None
            case ast.IndexRef():
                return self._index(expr)
            case ast.BitRef(base=base, bit=bit, pos=pos, width=width):
                base_type = self.type_of(base)
                if base_type is None:
                    return None
                integer = integer_like(base_type)
                if integer is None:
                    self.report(
                        pos, f"bit access needs an integer or bit string, not {base_type.name}"
                    )
                    return None
                if (bit + 1) * width > integer.bits:
                    self.report(pos, f"part {bit} is out of range for {integer.name}")
                return {1: BOOL, 8: BYTE, 16: WORD, 32: DWORD}[width]
            case ast.DirectRef(pos=pos):
                self.report(
                    pos, "direct addresses in code are not supported; declare a located variable"
                )
                return None
            case ast.Deref(pos=pos):
                self.report(pos, "pointers are not supported")
                return None
            case ast.Unary():
                return self._unary(expr)
            case ast.Binary():
                return self._binary(expr)
            case ast.Call():
                return self.call_type(expr)
        raise AssertionError(f"unhandled expression {expr!r}")

    def _literal_type(
        self, type_name: str | None, default: Type, pos: Pos, kinds: tuple[str, ...]
    ) -> Type | None:
        """The type of a literal; `INT#5` takes the named type if the literal is of a kind
        that type holds (no INT#1.5, no INT#TRUE)."""
        if type_name is None:
            return default
        found = elementary(type_name)
        if found is None:
            self.report(pos, f"unknown type '{type_name}' in typed literal")
            return None
        if found.category not in kinds:
            self.report(pos, f"{type_name}# cannot be given this literal")
            return None
        return found

    def _enum_literal(self, expr: ast.EnumLiteral) -> Type | None:
        info = self.resolved.enums.get(key(expr.type_name))
        if info is None:
            self.report(expr.pos, f"'{expr.type_name}' is not an enum type")
            return None
        if key(expr.value) not in info.values:
            self.report(expr.pos, f"enum '{expr.type_name}' has no value '{expr.value}'")
            return None
        return info.type

    def enum_literal_value(self, expr: ast.EnumLiteral) -> int:
        return self.resolved.enums[key(expr.type_name)].values[key(expr.value)][1]

    def constant_int(self, expr: ast.Expr | None) -> int | None:
        """The value of a constant integer expression (literals, enum values, constants)."""

        def leaf(node: ast.NameRef | ast.EnumLiteral) -> int | None:
            if isinstance(node, ast.EnumLiteral):
                info = self.resolved.enums.get(key(node.type_name))
                found = info.values.get(key(node.value)) if info is not None else None
                return found[1] if found is not None else None
            binding = self.enum_hint(node) or self.lookup(node.name)
            if isinstance(binding, EnumValue):
                return binding.value
            if isinstance(binding, Variable) and binding.constant:
                init = binding.init
                return fold_int(init, checked) if isinstance(init, ast.Expr) else None
            return None

        checked = guarded(leaf)
        return fold_int(expr, checked)

    def member(self, expr: ast.MemberRef) -> Variable | None:
        if self.system_namespace(expr.base):
            found = self.resolved.system.get(key(expr.member))
            if found is None:
                self.report(expr.pos, f"{NAMESPACE} has no system variable '{expr.member}'")
            return found
        base_type = self.type_of(expr.base)
        if base_type is None:
            return None
        if isinstance(base_type, FbType):
            symbols = self.fb_symbols(base_type)
            member = symbols.by_key.get(key(expr.member))
            if member is None or member.kind in ("VAR_TEMP", "VAR_GLOBAL"):
                self.report(expr.pos, f"'{base_type.name}' has no member '{expr.member}'")
                return None
            return member
        if isinstance(base_type, StructType):
            member = self.struct(base_type).by_key.get(key(expr.member))
            if member is None:
                self.report(expr.pos, f"'{base_type.name}' has no member '{expr.member}'")
            return member
        self.report(expr.pos, f"{base_type.name} has no member '{expr.member}'")
        return None

    def _index(self, expr: ast.IndexRef) -> Type | None:
        base_type = self.type_of(expr.base)
        for index in expr.indices:
            index_type = self.type_of(index)
            if index_type is not None and integer_like(index_type) is None:
                self.report(index.pos, f"array index must be an integer, not {index_type.name}")
        if base_type is None:
            return None
        if not isinstance(base_type, ArrayType):
            self.report(expr.pos, f"{base_type.name} is not an array")
            return None
        if len(expr.indices) != len(base_type.dims):
            self.report(expr.pos, f"{base_type.name} needs {len(base_type.dims)} indices")
            return None
        for index, (low, high) in zip(expr.indices, base_type.dims, strict=True):
            constant = self.constant_int(index)
            if constant is not None and not low <= constant <= high:
                self.report(index.pos, f"index {constant} is outside the bounds {low}..{high}")
        return base_type.element

    def _unary(self, expr: ast.Unary) -> Type | None:
        operand = self.type_of(expr.operand)
        if operand is None:
            return None
        integer = integer_like(operand)
        if expr.op == "NOT" and (operand == BOOL or integer is not None):
            return operand if operand == BOOL else integer
        if (
            expr.op in ("-", "+")
            and isinstance(operand, ElementaryType)
            and operand.category in ("int", "bits", "real", "time")
        ):
            return operand
        self.report(expr.pos, f"'{expr.op}' cannot be applied to {operand.name}")
        return None

    def _binary(self, expr: ast.Binary) -> Type | None:
        for known, bare in ((expr.left, expr.right), (expr.right, expr.left)):
            if self._bare_name(bare) and not self._bare_name(known):
                self.expect(bare, self.type_of(known))
        left_type, right_type = self.type_of(expr.left), self.type_of(expr.right)
        if left_type is None or right_type is None:
            return None
        op = expr.op
        mismatch = f"'{op}' cannot be applied to {left_type.name} and {right_type.name}"
        if op in ("=", "<>") and isinstance(left_type, EnumType | StructType):
            if left_type != right_type and not (
                isinstance(left_type, EnumType) and integer_like(right_type) is not None
            ):
                self.report(expr.pos, mismatch)
            return BOOL
        left, right = integer_like(left_type) or left_type, integer_like(right_type) or right_type
        if not isinstance(left, ElementaryType) or not isinstance(right, ElementaryType):
            self.report(expr.pos, mismatch)
            return None
        if op in ("AND", "OR", "XOR", "&"):
            if left == right == BOOL:
                return BOOL
            joined = common_numeric(left, right)
            if joined is not None and joined.is_integer:
                return joined
            self.report(expr.pos, mismatch)
            return None
        if op in ("=", "<>", "<", ">", "<=", ">="):
            comparable = (
                common_numeric(left, right) is not None
                or left.category == right.category
                or (left == BOOL and right.is_integer)
                or (right == BOOL and left.is_integer)
            )
            if not comparable:
                self.report(expr.pos, mismatch)
            return BOOL
        if left.category in ("time", "date") or right.category in ("time", "date"):
            return self._time_arithmetic(expr, left, right, mismatch)
        joined = common_numeric(left, right) if left.is_numeric and right.is_numeric else None
        if joined is None:  # no arithmetic on BOOL or STRING
            self.report(expr.pos, mismatch)
            return None
        if op == "**":
            return (
                joined
                if joined.category == "real" and not joined.is_any_literal
                else ELEMENTARY["LREAL"]
            )
        if op == "MOD" and joined.category == "real":
            self.report(expr.pos, mismatch)
            return None
        return joined

    def _time_arithmetic(
        self, expr: ast.Binary, left: ElementaryType, right: ElementaryType, mismatch: str
    ) -> Type | None:
        op = expr.op
        if op in ("+", "-") and left.category == right.category == "time":
            return LTIME if LTIME in (left, right) else TIME
        if op in ("+", "-") and left.category == "date" and right.category == "time":
            return left  # DT + TIME, TOD - TIME
        if op == "+" and left.category == "time" and right.category == "date":
            return right
        if op == "-" and left.category == right.category == "date":
            return TIME  # DT - DT, DATE - DATE, TOD - TOD
        if op in ("*", "/") and left.category == "time" and right.is_numeric:
            return left
        if op in ("+", "-") and left.category in ("time", "date") and right.is_integer:
            return left  # an integer added to a time counts nanoseconds
        if op == "*" and right.category == "time" and left.is_numeric:
            return right
        self.report(expr.pos, mismatch)
        return None

    # ---- calls
    def call_type(self, call: ast.Call) -> Type | None:
        if call.receiver is not None:
            self.report(call.pos, "methods are not supported")
            return None
        binding = self.lookup(call.name)
        if isinstance(binding, Variable) and isinstance(binding.type, FbType):
            self.report(call.pos, f"function block instance '{call.name}' has no value")
            return None
        if isinstance(binding, ProgramRef):
            self.report(call.pos, f"program '{call.name}' has no value; call it as a statement")
            return None
        pou = self.resolved.pous.get(key(call.name))
        if pou is not None and pou.kind == "FUNCTION" and not is_external(pou):
            self.check_user_call(pou, call)
            return pou.return_type or ELEMENTARY["DINT"]
        builtin = builtins.lookup(call.name)
        if builtin is not None:
            return self._builtin_type(builtin, call)
        if pou is not None and pou.kind == "FUNCTION":
            self.report(call.pos, f"external function '{call.name}' is not available")
            return None
        if key(call.name) in ("REF", "ADR"):
            self.report(call.pos, "pointers are not supported (REF and ADR only inside printf)")
            return None
        self.report(call.pos, f"'{call.name}' is not a function")
        return None

    def builtin_arguments(self, builtin: builtins.Builtin, call: ast.Call) -> list[ast.Expr] | None:
        """The arguments of a builtin call in parameter order: named ones in their place,
        positional ones filling the remaining places from the left."""
        values = [arg for arg in call.args if arg.value is not None]
        if builtin.name == "PRINTF":  # the test helper prints through pointers: unwrap them
            return [_unwrap_pointer(arg.value) for arg in values if arg.value is not None]
        if all(arg.name is None for arg in values):
            return [arg.value for arg in values if arg.value is not None]
        if builtin.params is None:
            # IN1, IN2, ... (or K, IN0, IN1 of MUX): selectors first, then inputs by number
            def order(arg: ast.Argument) -> tuple[int, int]:
                name = key(arg.name or "")
                if name.startswith("IN") and name[2:].isdigit():
                    return (1, int(name[2:]))
                return (0, 0)

            named = sorted((arg for arg in values if arg.name is not None), key=order)
            rest = [arg for arg in values if arg.name is None]
            return [arg.value for arg in (*named, *rest) if arg.value is not None]
        params = [key(p) for p in builtin.params]
        ordered: list[ast.Expr | None] = [None] * len(params)
        for arg in values:
            if arg.name is None:
                continue
            if key(arg.name) not in params:
                self.report(arg.pos, f"'{call.name}' has no parameter '{arg.name}'")
                return None
            ordered[params.index(key(arg.name))] = arg.value
        free = [i for i, value in enumerate(ordered) if value is None]
        unnamed = [arg.value for arg in values if arg.name is None]
        if len(unnamed) > len(free):
            self.report(call.pos, f"'{call.name}' takes {len(params)} arguments")
            return None
        for index, value in zip(free, unnamed, strict=False):
            ordered[index] = value
        if any(value is None for value in ordered):
            self.report(call.pos, f"'{call.name}' needs {', '.join(builtin.params)}")
            return None
        return [value for value in ordered if value is not None]

    def _builtin_type(self, builtin: builtins.Builtin, call: ast.Call) -> Type | None:
        args = self.builtin_arguments(builtin, call)
        if args is None:
            return None
        types = [self.type_of(arg) for arg in args]
        if any(t is None for t in types):
            return None
        if len(args) < builtin.min_args:
            self.report(call.pos, f"'{call.name}' needs at least {builtin.min_args} arguments")
            return None
        result = builtin.typing([t for t in types if t is not None])
        if isinstance(result, str):
            self.report(call.pos, f"'{call.name}' {result}")
            return None
        return result

    def check_user_call(self, pou: PouSymbols, call: ast.Call) -> None:
        for arg, param in self.connect_arguments(pou, call):
            if param is None:
                if arg.value is not None:
                    self.type_of(arg.value)
                continue
            self._check_argument(arg, param)

    def connect_arguments(
        self, pou: PouSymbols, call: ast.Call
    ) -> list[tuple[ast.Argument, Variable | None]]:
        """Pair each argument with its parameter: named ones by name, positional ones with
        the parameters not named, in declaration order (inputs, in-outs, outputs)."""
        params = pou.parameters
        pairs: list[tuple[ast.Argument, Variable | None]] = []
        named: set[str] = set()
        for arg in call.args:
            if arg.name is None:
                continue
            if key(arg.name) in IMPLICIT_PARAMETERS and key(arg.name) not in pou.by_key:
                pairs.append((arg, IMPLICIT_PARAMETERS[key(arg.name)]))
                continue
            param = pou.by_key.get(key(arg.name))
            if param is None or param.kind not in ("VAR_INPUT", "VAR_IN_OUT", "VAR_OUTPUT"):
                self.report(arg.pos, f"'{pou.name}' has no parameter '{arg.name}'")
                pairs.append((arg, None))
                continue
            named.add(key(param.name))
            pairs.append((arg, param))
        free = [p for p in params if key(p.name) not in named]
        positional = [arg for arg in call.args if arg.name is None]
        if len(positional) > len(free):
            self.report(
                call.pos, f"'{pou.name}' takes {len(params)} arguments, not {len(call.args)}"
            )
        for arg, param in zip(positional, free, strict=False):
            pairs.append((arg, param))
        return pairs

    def _check_argument(self, arg: ast.Argument, param: Variable) -> None:
        if arg.value is None:
            return
        if param.kind in ("VAR_OUTPUT", "VAR_IN_OUT") or arg.is_output:
            self.refuse_system_write(arg.value)
        value_type = self.type_of(arg.value)
        if value_type is None:
            return
        if param.kind == "VAR_OUTPUT" or arg.is_output:
            if not assignable(value_type, param.type):
                self.report(
                    arg.value.pos, f"cannot store {param.type.name} output in {value_type.name}"
                )
            return
        if not assignable(param.type, value_type):
            self.report(
                arg.value.pos, f"type mismatch: cannot pass {value_type.name} as {param.type.name}"
            )


# Every function and function block has EN (run only when TRUE) and ENO (TRUE when it ran).
IMPLICIT_PARAMETERS = {
    "EN": Variable("EN", "VAR_INPUT", BOOL, None, False, False, None, "EN", Pos("", 0, 0)),
    "ENO": Variable("ENO", "VAR_OUTPUT", BOOL, None, False, False, None, "ENO", Pos("", 0, 0)),
}


def is_implicit(param: Variable) -> bool:
    return any(param is implicit for implicit in IMPLICIT_PARAMETERS.values())


def enable_argument(call: ast.Call, callee: PouSymbols) -> ast.Expr | None:
    """The expression connected to the implicit EN, unless it is missing or the literal TRUE
    (a POU that declares its own `EN` input gets that input instead)."""
    if "EN" in callee.by_key:
        return None
    for arg in call.args:
        if arg.name is not None and key(arg.name) == "EN" and arg.value is not None:
            if isinstance(arg.value, ast.BoolLiteral) and arg.value.value:
                return None
            return arg.value
    return None


def _unwrap_pointer(expr: ast.Expr) -> ast.Expr:
    if isinstance(expr, ast.Call) and key(expr.name) in ("REF", "ADR") and len(expr.args) == 1:
        inner = expr.args[0].value
        if inner is not None:
            return inner
    return expr


def is_external(pou: PouSymbols) -> bool:
    """A FUNCTION declared only to announce one the environment provides (e.g. printf)."""
    variadic = any(isinstance(v.type, VariadicType) for v in pou.variables)
    return pou.kind == "FUNCTION" and variadic and not pou.pou.body
