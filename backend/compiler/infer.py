"""Expression typing and name lookup, shared by check and generate (which trusts checked
code).

`Scope` answers what a name means inside one POU and gives every expression its type, or
None when it has none. It reports nothing itself: what is wrong with an expression is for
the rules of the check stage (`backend.compiler.checks`), which check hands to `Scope` to
run on each node as soon as the node is typed.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

from backend.compiler import ast, builtins
from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.constants import Guarded, fold_int
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.resolve import (
    PouSymbols,
    PropertyInfo,
    Resolved,
    StructInfo,
    Variable,
    visible,
)
from backend.compiler.sizes import codesys_layout
from backend.compiler.source import Pos
from backend.compiler.test_functions import TestFunction, test_function
from backend.compiler.types import (
    ANY_INT,
    ANY_REAL,
    BOOL,
    BYTE,
    DWORD,
    ELEMENTARY,
    LTIME,
    NULL_TYPE,
    STRING,
    TIME,
    UDINT,
    UINT,
    ULINT,
    USINT,
    WORD,
    WSTRING,
    ArrayType,
    ElementaryType,
    EnumType,
    FbType,
    InterfaceType,
    OpenArrayType,
    RefType,
    StructType,
    Type,
    VariadicType,
    common_numeric,
    elementary,
    integer_like,
    is_implicit_reference,
    value_type,
)
from runtime.contract.system_variables import NAMESPACE


@dataclass(frozen=True)
class EnumValue:
    type: EnumType
    value: int


@dataclass(frozen=True)
class ProgramRef:
    pou: PouSymbols


@dataclass(frozen=True)
class NonFinite:
    """rusty's INF_REAL, NAN_REAL, INF_LREAL, NAN_LREAL (W0808): IEEE infinity and NaN,
    which IEC 61131-3 cannot write; a declaration of the name hides them."""

    name: str
    type: ElementaryType
    value: float


NON_FINITE = {
    f"{kind}_{type_name}": NonFinite(f"{kind}_{type_name}", ELEMENTARY[type_name], value)
    for kind, value in (("INF", math.inf), ("NAN", math.nan))
    for type_name in ("REAL", "LREAL")
}

Binding = Variable | EnumValue | ProgramRef | NonFinite


@dataclass(frozen=True)
class ActionCall:
    """A call of an ACTION: `act()` inside its POU (`instance` None), `inst.act()` on an
    instance of a function block (`instance` the expression) or `Prog.act()` on a program."""

    owner: PouSymbols
    action: ast.Action
    instance: ast.Expr | ProgramRef | None


@dataclass(frozen=True)
class UserFunction:
    pou: PouSymbols


@dataclass(frozen=True)
class StandardFunction:
    builtin: builtins.Builtin


@dataclass(frozen=True)
class RefOf:
    """REF(x): a reference to the variable x (IEC 61131-3 ed. 3); ADR(x) of CODESYS is the
    same as a `POINTER TO` (`pointer`)."""

    pointer: bool = False


@dataclass(frozen=True)
class IsValidRef:
    """CODESYS __ISVALIDREF(r): whether the REFERENCE TO r is bound (W0806)."""


@dataclass(frozen=True)
class SizeOf:
    """CODESYS SIZEOF(x): the size of x in bytes, a constant (W0802)."""


@dataclass(frozen=True)
class MethodCall:
    """A call of a method: `inst.M()`, `M()` inside its block, `THIS^.M()` (`receiver`
    None for the block the code runs in), or `SUPER^.M()`: the base's method itself
    (`static`), not the one the instance overrides it with."""

    method: PouSymbols
    receiver: ast.Expr | None
    static: PouSymbols | None = None


@dataclass(frozen=True)
class PropertyAccess:
    """A property read or written: `inst.P`, `itf.P`, `P` or `THIS^.P` inside its block
    (`receiver` None), `SUPER^.P` (`static`: the base's accessors themselves)."""

    prop: PropertyInfo
    receiver: ast.Expr | None
    static: PouSymbols | None = None


@dataclass(frozen=True)
class SuperBody:
    """`SUPER^()`: the body of the base function block, run on this instance."""

    base: PouSymbols


@dataclass(frozen=True)
class TestCall:
    """A test function of a test file (`backend.compiler.test_functions`)."""

    function: TestFunction


# What else a call in an expression may name; none of these gives a value.
NoValue = Literal["method", "action", "instance", "program", "external", "unknown", "super"]
Callee = (
    UserFunction | StandardFunction | RefOf | IsValidRef | SizeOf | MethodCall | TestCall | NoValue
)

# THIS and SUPER: references to the instance the code runs on, as itself or as its base
SELF_NAMES = ("THIS", "SUPER")


@dataclass(frozen=True)
class Misfit:
    """Why the arguments of a standard function call give it no type."""

    kind: Literal["no parameter", "too many", "missing", "too few", "types"]
    pos: Pos
    detail: str = ""  # "no parameter": the name used; "types": what the function's typing says


COMPARISONS = ("=", "<>", "<", ">", "<=", ">=")

# The rules of the check stage on one expression node, given the node's type.
ExpressionRules = Callable[["Scope", ast.Expr, "Type | None"], None]


@dataclass
class Scope:
    resolved: Resolved
    pou: PouSymbols
    # run on every node once it is typed; generate sets none, it works on checked code
    rules: ExpressionRules | None = None
    diagnostics: list[Diagnostic] = field(default_factory=list)  # what the rules report
    # by id() of the node; the node is kept alongside so its id cannot be reused
    _types: dict[int, tuple[Type | None, ast.Expr]] = field(default_factory=dict)
    # enum values named without their type, resolved from where they are used
    _enum_hints: dict[int, tuple[EnumValue, ast.Expr]] = field(default_factory=dict)
    # `s.fb(...)`: the member a call on a receiver names, by id() of the call (kept alongside)
    _called_members: dict[int, tuple[ast.MemberRef, ast.Call]] = field(default_factory=dict)
    # the nodes `^` follows (THIS and SUPER need it)
    _dereferenced: set[int] = field(default_factory=set)
    # the nodes written (assignment targets): a property there is set, not read
    written: set[int] = field(default_factory=set)

    def dereferenced(self, expr: ast.Expr) -> bool:
        return id(expr) in self._dereferenced

    # ---- names
    def variable(self, name: str) -> Variable | None:
        found = visible(self.resolved, self.pou, name)
        if found is None and key(name) in SELF_NAMES:
            return self._self_reference(key(name))
        if found is None and key(name) == "ENO":  # a block's body may set its own ENO
            return block_eno(self.pou)
        return found

    def block(self) -> PouSymbols | None:
        """The PROGRAM or FUNCTION_BLOCK whose instance the code runs on (a method's too)."""
        if self.pou.outer is not None:
            return self.pou.outer
        return self.pou if self.pou.kind in ("PROGRAM", "FUNCTION_BLOCK") else None

    def _self_reference(self, name: str) -> Variable | None:
        """THIS (a REF_TO the block) or SUPER (a REF_TO its base), as variables of kind
        THIS and SUPER that only `^` may follow."""
        block = self.block()
        if block is None or (name == "SUPER" and block.base is None):
            return None
        target = block if name == "THIS" else self.resolved.pous[block.base or ""]
        here = self.pou.pou.pos
        return Variable(
            name, name, RefType(FbType(target.name)), None, True, False, None, "s", here
        )

    def self_deref(self, expr: ast.Expr) -> str | None:
        """ "THIS" or "SUPER" for `THIS^` and `SUPER^`, else None."""
        if isinstance(expr, ast.Deref) and isinstance(expr.base, ast.NameRef):
            found = self.variable(expr.base.name)
            if found is not None and found.kind in SELF_NAMES:
                return found.kind
        return None

    def method_call(self, call: ast.Call) -> MethodCall | None:
        """The method `call` calls, if it calls one."""
        receiver = call.receiver
        if call.name == "^":
            return None
        if receiver is None:
            block = self.block()
            if block is None or self.variable(call.name) is not None:
                return None
            found = block.methods.get(key(call.name))
            return MethodCall(found, None) if found is not None else None
        if self.self_deref(receiver) == "SUPER":
            block = self.block()
            assert block is not None and block.base is not None
            base = self.resolved.pous[block.base]
            found = base.methods.get(key(call.name))
            return MethodCall(found, receiver, base) if found is not None else None
        receiver_type = self.type_of(receiver)
        if isinstance(receiver_type, FbType):
            owner = self.fb_symbols(receiver_type)
            found = owner.methods.get(key(call.name))
            return MethodCall(found, receiver) if found is not None else None
        if isinstance(receiver_type, InterfaceType):
            interface = self.resolved.interfaces[key(receiver_type.name)]
            found = interface.methods.get(key(call.name))
            return MethodCall(found, receiver) if found is not None else None
        return None

    def conforms(self, target: Type, source: Type) -> bool:
        """What object orientation adds to `assignable`: an instance (or an interface
        extending it) into an interface variable, a reference to a derived block into a
        reference to its base."""
        if isinstance(target, InterfaceType):
            if isinstance(source, FbType):
                return self.resolved.conforms(key(source.name), key(target.name))
            if isinstance(source, InterfaceType):
                extended = self.resolved.interfaces[key(source.name)].extends
                return key(source.name) == key(target.name) or key(target.name) in extended
            return False
        if isinstance(target, RefType) and isinstance(source, RefType):
            ends = (target.target, source.target)
            if isinstance(ends[0], FbType) and isinstance(ends[1], FbType):
                same_kind = (target.pointer, target.implicit) == (source.pointer, source.implicit)
                return same_kind and self.resolved.conforms(key(ends[1].name), key(ends[0].name))
        return False

    def property_access(self, expr: ast.Expr) -> PropertyAccess | None:
        """The property `expr` names, if it names one (a variable of the name hides it)."""
        if isinstance(expr, ast.NameRef):
            block = self.block()
            if block is None or self.lookup(expr.name) is not None:
                return None
            found = block.properties.get(key(expr.name))
            return PropertyAccess(found, None) if found is not None else None
        if not isinstance(expr, ast.MemberRef) or self.system_namespace(expr.base):
            return None
        if self.self_deref(expr.base) == "SUPER":
            block = self.block()
            assert block is not None and block.base is not None
            base = self.resolved.pous[block.base]
            found = base.properties.get(key(expr.member))
            return PropertyAccess(found, expr.base, base) if found is not None else None
        base_type = self.type_of(expr.base)
        if isinstance(base_type, FbType):
            found = self.fb_symbols(base_type).properties.get(key(expr.member))
        elif isinstance(base_type, InterfaceType):
            found = self.resolved.interfaces[key(base_type.name)].properties.get(key(expr.member))
        else:
            return None
        return PropertyAccess(found, expr.base) if found is not None else None

    def may_call(self, method: PouSymbols) -> bool:
        """Whether the code here may call a method (or a property's accessor): PUBLIC and
        INTERNAL ones from anywhere (a project is one namespace); PRIVATE ones from the
        block that declares them; PROTECTED ones from it and the blocks derived from it."""
        if method.access in ("PUBLIC", "INTERNAL"):
            return True
        block = self.block()
        while block is not None:
            if key(block.name) == method.declared_in:
                return True
            if method.access == "PRIVATE" or block.base is None:
                return False
            block = self.resolved.pous[block.base]
        return False

    def called_instance(self, call: ast.Call) -> PouSymbols | None:
        """The block (or program) whose body a call statement runs: a program, an
        instance, a REFERENCE TO one (`ref(...)`), or the instance a reference refers to
        (`r^(...)`; not SUPER^(), which runs the base's body)."""
        if call.name == "^" and call.receiver is not None:
            if self.self_deref(call.receiver) is not None:
                return None
            target = self.type_of(call.receiver)
            return self.fb_symbols(target) if isinstance(target, FbType) else None
        binding = self.lookup(call.name) if call.receiver is None else None
        if isinstance(binding, ProgramRef):
            return binding.pou
        if isinstance(binding, Variable) and isinstance(value_type(binding.type), FbType):
            instance = value_type(binding.type)
            assert isinstance(instance, FbType)
            return self.fb_symbols(instance)
        return None

    def super_body(self, call: ast.Call) -> SuperBody | None:
        """`SUPER^()` in a derived function block."""
        if call.name != "^" or call.receiver is None or self.self_deref(call.receiver) != "SUPER":
            return None
        block = self.block()
        assert block is not None and block.base is not None
        return SuperBody(self.resolved.pous[block.base])

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
        return NON_FINITE.get(key(name))

    def action_call(self, call: ast.Call) -> ActionCall | None:
        """The action `call` calls, if it calls one (a variable of the name hides it)."""
        receiver = call.receiver
        instance: ast.Expr | ProgramRef | None = None
        if receiver is None:
            if self.variable(call.name) is not None:
                return None
            owner = self.block() or self.pou  # a method calls its block's actions
        elif isinstance(receiver, ast.NameRef) and isinstance(
            program := self.lookup(receiver.name), ProgramRef
        ):
            owner, instance = program.pou, program
        else:
            receiver_type = self.type_of(receiver)
            if not isinstance(receiver_type, FbType):
                return None
            owner, instance = self.fb_symbols(receiver_type), receiver
        actions = owner.pou.sfc.actions if owner.pou.sfc is not None else ()
        found = [a for a in actions if key(a.name) == key(call.name)]
        return ActionCall(owner, found[0], instance) if found else None

    def expression_instance(self, call: ast.Call) -> tuple[ast.Expr, FbType] | None:
        """The function block instance `call` calls when an expression gives it (IEC ed. 3,
        CODESYS): `fbs[1](...)`, `p^(...)`, or `s.fb(...)` on a member that is an instance
        (and no action of the receiver)."""
        instance: ast.Expr
        if call.instance is not None:
            instance = call.instance
        elif call.receiver is not None and self.action_call(call) is None:
            member = ast.MemberRef(call.receiver, call.name, call.pos)
            variable = self.member(member)
            if variable is None or not isinstance(variable.type, FbType):
                return None
            instance = self._called_members.setdefault(id(call), (member, call))[0]
        else:
            return None
        found = self.type_of(instance)
        return (instance, found) if isinstance(found, FbType) else None

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

    def report(self, pos: Pos, code: Code, message: str) -> None:
        self.diagnostics.append(Diagnostic.at(pos, code, message))

    # ---- typing
    def type_of(self, expr: ast.Expr) -> Type | None:
        """The type of `expr`, computed (and the rules run on it) once per node."""
        node = id(expr)
        if node not in self._types:
            found = self._compute_type(expr)
            self._types[node] = (found, expr)
            if self.rules is not None:
                self.rules(self, expr, found)
        return self._types[node][0]

    def _compute_type(self, expr: ast.Expr) -> Type | None:
        match expr:
            case ast.IntLiteral(type_name=type_name):
                return _literal_type(type_name, ANY_INT, ("int", "bits", "real"))
            case ast.RealLiteral(type_name=type_name):
                return _literal_type(type_name, ANY_REAL, ("real",))
            case ast.BoolLiteral(type_name=type_name):
                return _literal_type(type_name, BOOL, ("bool",))
            case ast.TimeLiteral(type_name=type_name):
                return ELEMENTARY.get(type_name, TIME)
            case ast.StringLiteral(wide=wide, type_name=type_name):
                return _literal_type(type_name, WSTRING if wide else STRING, ("string",))
            case ast.EnumLiteral():
                return self._enum_literal(expr)
            case ast.NameRef(name=name):
                binding = self.enum_hint(expr) or self.lookup(name)
                if binding is None:
                    found = self.property_access(expr)
                    return found.prop.type if found is not None else None
                if isinstance(binding, Variable | EnumValue | NonFinite):
                    return value_type(binding.type)
                return FbType(binding.pou.name)
            case ast.MemberRef():
                member = self.member(expr)
                if member is None:
                    found = self.property_access(expr)
                    return found.prop.type if found is not None else None
                return value_type(member.type)
            case ast.IndexRef():
                return self._index(expr)
            case ast.BitRef(base=base, width=width):
                base_type = self.type_of(base)
                if base_type is None or integer_like(base_type) is None:
                    return None
                return {1: BOOL, 8: BYTE, 16: WORD, 32: DWORD}[width]
            case ast.NullLiteral():
                return NULL_TYPE
            case ast.Deref(base=base):
                self._dereferenced.add(id(base))  # the node is kept alive by the Deref's entry
                base_type = self.type_of(base)
                return base_type.target if isinstance(base_type, RefType) else None
            case ast.Unary():
                return self._unary(expr)
            case ast.Binary():
                return self._binary(expr)
            case ast.Call():
                return self.call_type(expr)
        raise AssertionError(f"unhandled expression {expr!r}")

    def _enum_literal(self, expr: ast.EnumLiteral) -> Type | None:
        info = self.resolved.enums.get(key(expr.type_name))
        if info is None or key(expr.value) not in info.values:
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

        checked = Guarded(leaf)
        return fold_int(expr, checked)

    def member(self, expr: ast.MemberRef) -> Variable | None:
        """The variable `expr` names: a system variable, a member of a structure, or a member
        of a function block that is visible from outside."""
        if self.system_namespace(expr.base):
            return self.resolved.system.get(key(expr.member))
        base_type = self.type_of(expr.base)
        if isinstance(base_type, FbType):
            block = self.fb_symbols(base_type)
            member = block.by_key.get(key(expr.member))
            if member is None and key(expr.member) == "ENO":
                return block_eno(block)
            if member is None or member.kind in ("VAR_TEMP", "VAR_GLOBAL"):
                return None
            return member
        if isinstance(base_type, StructType):
            return self.struct(base_type).by_key.get(key(expr.member))
        return None

    def _index(self, expr: ast.IndexRef) -> Type | None:
        base_type = self.type_of(expr.base)
        for index in expr.indices:
            self.type_of(index)
        if isinstance(base_type, ArrayType) and len(expr.indices) == len(base_type.dims):
            return base_type.element
        if isinstance(base_type, OpenArrayType) and len(expr.indices) == base_type.rank:
            return base_type.element
        return None

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
        return None

    def _binary(self, expr: ast.Binary) -> Type | None:
        for known, bare in ((expr.left, expr.right), (expr.right, expr.left)):
            if self._bare_name(bare) and not self._bare_name(known):
                self.expect(bare, self.type_of(known))
        left_type, right_type = self.type_of(expr.left), self.type_of(expr.right)
        if left_type is None or right_type is None:
            return None
        op = expr.op
        if op in ("=", "<>") and isinstance(
            left_type, EnumType | StructType | RefType | InterfaceType
        ):
            return BOOL  # whether the two compare is a rule (checks.operators)
        left, right = integer_like(left_type) or left_type, integer_like(right_type) or right_type
        if not isinstance(left, ElementaryType) or not isinstance(right, ElementaryType):
            return None
        if op in ("AND", "OR", "XOR", "&"):
            if left == right == BOOL:
                return BOOL
            joined = common_numeric(left, right)
            return joined if joined is not None and joined.is_integer else None
        if op in COMPARISONS:
            return BOOL  # whether the two compare is a rule (checks.operators)
        if left.category in ("time", "date") or right.category in ("time", "date"):
            return _time_arithmetic(op, left, right)
        joined = common_numeric(left, right) if left.is_numeric and right.is_numeric else None
        if joined is None:  # no arithmetic on BOOL or STRING
            return None
        if op == "**":
            return (
                joined
                if joined.category == "real" and not joined.is_any_literal
                else ELEMENTARY["LREAL"]
            )
        if op == "MOD" and joined.category == "real":
            return None
        return joined

    # ---- calls
    def call_type(self, call: ast.Call) -> Type | None:
        callee = self.callee(call)
        if isinstance(callee, UserFunction):
            for arg, _ in self.connect_arguments(callee.pou, call):
                if arg.value is not None:
                    self.type_of(arg.value)
            return callee.pou.return_type or ELEMENTARY["DINT"]
        if isinstance(callee, MethodCall):
            for arg, _ in self.connect_arguments(callee.method, call):
                if arg.value is not None:
                    self.type_of(arg.value)
            return callee.method.return_type
        if isinstance(callee, StandardFunction):
            result = self.standard_call(callee.builtin, call)
            return None if isinstance(result, Misfit) else result
        if isinstance(callee, SizeOf):
            size = self.size_of(call)
            return None if size is None else smallest_unsigned(size)
        if isinstance(callee, TestCall):
            for arg in call.args:
                if arg.value is not None:
                    self.type_of(arg.value)
            return callee.function.gives
        if isinstance(callee, IsValidRef):
            referenced = self.referenced(call)
            if referenced is not None:
                self.type_of(referenced)
            return BOOL
        if isinstance(callee, RefOf):
            referenced = self.referenced(call)
            target = self.type_of(referenced) if referenced is not None else None
            return None if target is None else RefType(target, callee.pointer)
        return None

    def referenced(self, call: ast.Call) -> ast.Expr | None:
        """The variable of REF(x): its one unnamed argument."""
        if len(call.args) != 1 or call.args[0].name is not None:
            return None
        return call.args[0].value

    def size_of(self, call: ast.Call) -> int | None:
        """The bytes SIZEOF(x) counts, as CODESYS does (`sizes`); None for a call that is
        not one variable or expression with such a size."""
        if len(call.args) != 1 or call.args[0].name is not None or call.args[0].value is None:
            return None
        argument_type = self.type_of(call.args[0].value)
        if argument_type is None:
            return None
        layout = codesys_layout(self.resolved, argument_type)
        return None if layout is None else layout.size

    def callee(self, call: ast.Call) -> Callee:
        """What a call in an expression calls."""
        if self.action_call(call) is not None:
            return "action"
        method = self.method_call(call)
        if method is not None:
            return method
        if call.name == "^":
            return "super"
        if self.expression_instance(call) is not None:
            return "instance"
        if call.receiver is not None:
            return "method"
        binding = self.lookup(call.name)
        if isinstance(binding, Variable) and isinstance(binding.type, FbType):
            return "instance"
        if isinstance(binding, ProgramRef):
            return "program"
        pou = self.resolved.pous.get(key(call.name))
        if pou is not None and pou.kind == "FUNCTION" and not is_external(pou):
            return UserFunction(pou)
        if key(call.name) == "SIZEOF":
            return SizeOf()
        if key(call.name) in ("REF", "ADR"):
            return RefOf(pointer=key(call.name) == "ADR")
        if key(call.name) == "__ISVALIDREF":
            return IsValidRef()
        test = self.test_call(call)
        if test is not None:
            return TestCall(test)
        builtin = builtins.lookup(call.name)
        if builtin is not None:
            return StandardFunction(builtin)
        if pou is not None and pou.kind == "FUNCTION":
            return "external"
        return "unknown"

    def test_call(self, call: ast.Call) -> TestFunction | None:
        """The test function `call` calls, in a test file."""
        if call.receiver is not None or call.instance is not None:
            return None
        return test_function(call.name, self.pou.pou.pos.file)

    def builtin_arguments(
        self, builtin: builtins.Builtin, call: ast.Call
    ) -> list[ast.Expr] | Misfit:
        """The arguments of a builtin call in parameter order: named ones in their place,
        positional ones filling the remaining places from the left."""
        values = [arg for arg in call.args if arg.value is not None and not is_en_eno(arg)]
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
                return Misfit("no parameter", arg.pos, arg.name)
            ordered[params.index(key(arg.name))] = arg.value
        free = [i for i, value in enumerate(ordered) if value is None]
        unnamed = [arg.value for arg in values if arg.name is None]
        if len(unnamed) > len(free):
            return Misfit("too many", call.pos)
        for index, value in zip(free, unnamed, strict=False):
            ordered[index] = value
        if any(value is None for value in ordered):
            return Misfit("missing", call.pos)
        return [value for value in ordered if value is not None]

    def standard_call(self, builtin: builtins.Builtin, call: ast.Call) -> Type | Misfit | None:
        """The type of a standard function call, or why its arguments do not fit; None when
        an argument has no type of its own."""
        args = self.builtin_arguments(builtin, call)
        if isinstance(args, Misfit):
            return args
        types = [self.type_of(arg) for arg in args]
        if builtin.name in builtins.SHIFTS and types and types[0] == ANY_INT:
            based = isinstance(args[0], ast.IntLiteral) and args[0].based
            types[0] = builtins.shifted_literal_type(self.constant_int(args[0]), based)
        known = [t for t in types if t is not None]
        if len(known) < len(types):
            return None
        if len(args) < builtin.min_args:
            return Misfit("too few", call.pos)
        result = builtin.typing(known)
        return Misfit("types", call.pos, result) if isinstance(result, str) else result

    def connect_arguments(
        self, pou: PouSymbols, call: ast.Call
    ) -> list[tuple[ast.Argument, Variable | None]]:
        """Pair each argument with its parameter: named ones by name (None: the POU has no
        such parameter), positional ones with the parameters not named, in declaration order
        (inputs, in-outs, outputs); positional ones beyond those are left out."""
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
                pairs.append((arg, None))
                continue
            named.add(key(param.name))
            pairs.append((arg, param))
        free = [p for p in params if key(p.name) not in named]
        positional = [arg for arg in call.args if arg.name is None]
        for arg, param in zip(positional, free, strict=False):
            pairs.append((arg, param))
        return pairs


# Every function and function block has EN (run only when TRUE) and ENO (TRUE when it ran).
# A function block's ENO is a variable of each instance too (TRUE until a call with EN
# FALSE), unless the block declares a variable of that name itself.
_NOWHERE = Pos("", 0, 0)
_TRUE = ast.BoolLiteral(True, _NOWHERE)
IMPLICIT_PARAMETERS = {
    "EN": Variable("EN", "VAR_INPUT", BOOL, None, False, False, None, "EN", _NOWHERE),
    "ENO": Variable("ENO", "VAR_OUTPUT", BOOL, _TRUE, False, False, None, "ENO", _NOWHERE),
}


def block_eno(pou: PouSymbols) -> Variable | None:
    """The implicit ENO of a FUNCTION_BLOCK's instances (None: not a block, or it declares
    a variable named ENO, which is then its own)."""
    if pou.kind != "FUNCTION_BLOCK" or "ENO" in pou.by_key:
        return None
    return IMPLICIT_PARAMETERS["ENO"]


def instance_fields(pou: PouSymbols) -> list[Variable]:
    """The variables an instance of a PROGRAM or FUNCTION_BLOCK holds: its own (but the
    globals and temporaries) and a block's implicit ENO, last."""
    own = [v for v in pou.variables if v.kind not in ("VAR_GLOBAL", "VAR_TEMP")]
    eno = block_eno(pou)
    return own if eno is None else [*own, eno]


def is_en_eno(arg: ast.Argument) -> bool:
    """Is `arg` the EN or ENO of a standard function's call (which have no other)?"""
    return arg.name is not None and key(arg.name) in IMPLICIT_PARAMETERS


def smallest_unsigned(value: int) -> ElementaryType:
    """The type CODESYS gives SIZEOF: the smallest unsigned integer that holds the size."""
    return next(t for t in (USINT, UINT, UDINT) if value <= t.max) if value <= UDINT.max else ULINT


def is_implicit(param: Variable) -> bool:
    return any(param is implicit for implicit in IMPLICIT_PARAMETERS.values())


def binds_reference(param: Variable, arg: ast.Argument) -> bool:
    """Is `arg` the binding of a REFERENCE TO input (CODESYS: `inst(r := x)` binds r to x,
    as `r REF= x` would, instead of copying x's value)?"""
    return param.kind == "VAR_INPUT" and not arg.is_output and is_implicit_reference(param.type)


def enable_argument(call: ast.Call, callee: PouSymbols | None) -> ast.Expr | None:
    """The expression connected to the implicit EN, unless it is missing or the literal TRUE
    (a POU that declares its own `EN` input gets that input instead; `callee` None: a
    standard function)."""
    if callee is not None and "EN" in callee.by_key:
        return None
    for arg in call.args:
        if arg.name is not None and key(arg.name) == "EN" and arg.value is not None:
            if isinstance(arg.value, ast.BoolLiteral) and arg.value.value:
                return None
            return arg.value
    return None


def _time_arithmetic(op: str, left: ElementaryType, right: ElementaryType) -> Type | None:
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
    return None


def _literal_type(type_name: str | None, default: Type, kinds: tuple[str, ...]) -> Type | None:
    """The type of a literal; `INT#5` takes the named type if the literal is of a kind that
    type holds (no INT#1.5, no INT#TRUE)."""
    if type_name is None:
        return default
    found = elementary(type_name)
    return found if found is not None and found.category in kinds else None


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
