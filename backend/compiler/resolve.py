"""Stage 2, resolve: bind every declaration to a type and build the symbol tables.

The result, `Resolved`, is what check and generate work on: POUs with their variables,
user data types (structs, enums, aliases, subranges), and the global variables. Tables
are keyed by the upper-case name; everything a later stage iterates over is sorted or in
declaration order, never in hash order.
"""

from __future__ import annotations

import keyword
from dataclasses import dataclass, field, replace

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.constants import Guarded, fold_int
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.limits import MAX_DATA_DEPTH, MAX_EXPRESSION_DEPTH
from backend.compiler.qualified_enums import EnumMemo, qualify_enum_values
from backend.compiler.qualified_names import QualifyMemo, qualify_names, unknown_qualified
from backend.compiler.source import Pos
from backend.compiler.types import (
    BOOL,
    BYTE,
    DWORD,
    INT,
    LWORD,
    TIME,
    WORD,
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
    elementary,
)
from runtime.contract.system_variables import NAMESPACE, SYSTEM_VARIABLES

PARAMETER_KINDS = ("VAR_INPUT", "VAR_IN_OUT", "VAR_OUTPUT")


@dataclass(frozen=True)
class Variable:
    name: str
    kind: str  # VAR, VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT, VAR_TEMP, VAR_EXTERNAL, VAR_GLOBAL, MEMBER
    # (also STEP, RETURN, and SYSTEM for `SYS.<NAME>`)
    type: Type
    init: ast.Initializer | None
    constant: bool
    retain: bool
    location: str | None
    attr: str  # the Python name in generated code
    pos: Pos
    edge: str | None = None  # R_EDGE / F_EDGE input


@dataclass
class PouSymbols:
    pou: ast.Pou
    variables: list[Variable]
    by_key: dict[str, Variable]
    return_type: Type | None = None
    # a PROGRAM's or FUNCTION_BLOCK's methods by key, the inherited ones among them
    methods: dict[str, PouSymbols] = field(default_factory=dict)
    # a method (kind METHOD): the function block or program it belongs to, whose variables
    # its body sees, and the key of the one that declares it
    outer: PouSymbols | None = None
    method: ast.Method | None = None
    declared_in: str = ""
    base: str | None = None  # the key of the function block this one EXTENDS
    # the keys of the interfaces it implements: its own, its base's, and what they extend
    interfaces: tuple[str, ...] = ()
    # its properties by key, the inherited ones among them
    properties: dict[str, PropertyInfo] = field(default_factory=dict)

    def own_routines(self) -> list[PouSymbols]:
        """The methods and property accessors this block declares itself (not inherited),
        by name: code that runs on its instances."""
        routines = [m for _, m in sorted(self.methods.items())]
        for _, prop in sorted(self.properties.items()):
            routines += [a for a in (prop.getter, prop.setter) if a is not None]
        return [r for r in routines if r.declared_in == key(self.name)]

    @property
    def access(self) -> str:
        """A method's access; IEC 61131-3 makes one without a specifier PROTECTED."""
        return (self.method.access if self.method is not None else None) or "PROTECTED"

    @property
    def name(self) -> str:
        return self.pou.name

    @property
    def kind(self) -> str:
        return self.pou.kind

    @property
    def parameters(self) -> list[Variable]:
        """Inputs, in-outs and outputs in declaration order (the order of positional args)."""
        return [v for v in self.variables if v.kind in PARAMETER_KINDS]


@dataclass
class StructInfo:
    name: str
    members: list[Variable]
    by_key: dict[str, Variable]


@dataclass
class EnumInfo:
    type: EnumType
    values: dict[str, tuple[str, int]]  # key -> (spelling, value), in declaration order


@dataclass(frozen=True)
class PropertyInfo:
    """A PROPERTY: its GET as a method without parameters whose result is the property's
    value, its SET as a method whose one input, named like the property, is the value
    written (either may be missing: read-only, write-only)."""

    name: str
    type: Type
    getter: PouSymbols | None
    setter: PouSymbols | None
    declared_in: str
    pos: Pos

    @property
    def access(self) -> str:
        accessor = self.getter or self.setter
        return accessor.access if accessor is not None else "PROTECTED"


@dataclass
class InterfaceInfo:
    decl: ast.Interface
    # its method prototypes by key, those of the interfaces it extends among them (their
    # `declared_in` the interface's key; always PUBLIC)
    methods: dict[str, PouSymbols] = field(default_factory=dict)
    extends: tuple[str, ...] = ()  # the keys of every interface it extends, transitively
    properties: dict[str, PropertyInfo] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.decl.name


@dataclass
class Resolved:
    pous: dict[str, PouSymbols] = field(default_factory=dict)
    structs: dict[str, StructInfo] = field(default_factory=dict)
    enums: dict[str, EnumInfo] = field(default_factory=dict)
    globals: list[Variable] = field(default_factory=list)
    globals_by_key: dict[str, Variable] = field(default_factory=dict)
    diagnostics: list[Diagnostic] = field(default_factory=list)
    # `SYS.<NAME>` by key; empty when a type, POU or global of the user is named SYS
    system: dict[str, Variable] = field(default_factory=dict)
    interfaces: dict[str, InterfaceInfo] = field(default_factory=dict)

    def conforms(self, block: str, kind: str) -> bool:
        """Whether an instance of block `block` (a key) is also a `kind` (a key): the block
        itself, a base of it, or an interface it implements."""
        current: str | None = block
        while current is not None:
            if current == kind:
                return True
            current = self.pous[current].base if current in self.pous else None
        return block in self.pous and kind in self.pous[block].interfaces

    def sorted_pous(self) -> list[PouSymbols]:
        return [self.pous[k] for k in sorted(self.pous)]

    def enum_values_named(self, name: str) -> list[tuple[EnumInfo, int]]:
        """Every enum that has a value called `name` (unqualified use)."""
        return [
            (info, info.values[key(name)][1])
            for _, info in sorted(self.enums.items())
            if key(name) in info.values
        ]


def python_attr(name: str) -> str:
    """A Python-safe attribute name for an ST identifier (ST allows Python keywords), or for
    a variable named by its address (`%IX1.1` -> `at__IX1_1`: no identifier has `__`)."""
    if name.startswith("%"):
        return "at__" + name[1:].replace(".", "_")
    return f"{name}_" if keyword.iskeyword(name) or name in ("None", "True", "False") else name


def visible(resolved: Resolved, pou: PouSymbols, name: str) -> Variable | None:
    """The variable `name` means inside `pou`: its own, else a global. A direct address
    (`%IX0.1`) means the variable located there, named or not, of the POU or the globals."""
    found = pou.by_key.get(key(name))
    if found is None and pou.outer is not None:  # a method sees its block's variables
        found = pou.outer.by_key.get(key(name))
    if found is None:
        found = resolved.globals_by_key.get(key(name))
    if found is None and name.startswith("%"):
        address = name.upper()
        candidates = (*pou.variables, *resolved.globals)
        found = next((v for v in candidates if v.location == address), None)
    return found


# the type of a direct address by its size letter: %IX0.1 / %I0.1 a bit, %MW10 a word
_ADDRESS_SIZES = {"X": BOOL, "B": BYTE, "W": WORD, "D": DWORD, "L": LWORD}


def _implicit_globals(units: list[ast.SourceUnit], result: Resolved) -> None:
    """An address code names that no declaration locates is a global of its own
    (`%MW10 := 42;` writes the memory word 10), of the type its size letter says."""
    located = {v.location for p in result.pous.values() for v in p.variables if v.location}
    located.update(v.location for v in result.globals if v.location)
    first: dict[str, Pos] = {}
    for unit in units:
        for address, pos in unit.addresses:
            first.setdefault(address, pos)
    for address in sorted(first):
        if address in located:
            continue
        size = address.lstrip("%IQM")[:1]  # the area letter may be missing (`%B6`)
        variable = Variable(
            address, "VAR_GLOBAL", _ADDRESS_SIZES.get(size, BOOL), None, False, False, address,
            python_attr(address), first[address],
        )  # fmt: skip
        result.globals.append(variable)
        result.globals_by_key[key(address)] = variable


class _TypeResolver:
    """Turns type references into types, resolving named types on first use."""

    def __init__(self, units: list[ast.SourceUnit], result: Resolved) -> None:
        self.result = result
        self.pou_kinds: dict[str, ast.Pou] = {}
        self.interfaces: dict[str, ast.Interface] = {}
        self.decls: dict[str, ast.TypeDecl] = {}
        self.named: dict[str, Type | None] = {}
        self.in_progress: set[str] = set()
        self.global_constants: dict[str, ast.Initializer | None] = {}
        # every enum value by key, as the first enum declared with it has it
        self.enum_values: dict[str, int] = {}
        for unit in units:
            for pou in unit.pous:
                self.pou_kinds.setdefault(key(pou.name), pou)
            for interface in unit.interfaces:
                self.interfaces.setdefault(key(interface.name), interface)
            for decl in unit.types:
                if key(decl.name) in self.decls:
                    first = self.decls[key(decl.name)]
                    self.report(
                        decl.pos,
                        Code.DUPLICATE_TYPE,
                        f"type '{decl.name}' is already declared at {first.pos}",
                    )
                    continue
                self.decls[key(decl.name)] = decl
            for block in unit.globals:
                if "CONSTANT" in block.qualifiers:
                    for var in block.decls:
                        self.global_constants[key(var.name)] = var.init

    def report(self, pos: Pos, code: Code, message: str) -> None:
        self.result.diagnostics.append(Diagnostic.at(pos, code, message))

    def const_int(
        self, expr: ast.Expr, local_constants: dict[str, ast.Initializer | None]
    ) -> int | None:
        """Evaluate a constant integer expression (array bounds, string lengths, enum values)."""

        def leaf(node: ast.NameRef | ast.EnumLiteral) -> int | None:
            if isinstance(node, ast.EnumLiteral):
                info = self.result.enums.get(key(node.type_name))
                found = info.values.get(key(node.value)) if info is not None else None
                return found[1] if found is not None else None
            name = key(node.name)
            if name in local_constants or name in self.global_constants:
                init = local_constants.get(name, self.global_constants.get(name))
                return fold_int(init, checked) if isinstance(init, ast.Expr) else None
            return self.enum_values.get(name)

        checked = Guarded(leaf)
        value = fold_int(expr, checked)
        if checked.cut_short:
            message = f"a constant defined through more than {MAX_EXPRESSION_DEPTH} others"
            self.report(expr.pos, Code.EXPRESSION_DEPTH, message)
        return value

    def default_init(self, spec: ast.TypeRef) -> ast.Initializer | None:
        """The initializer a named type carries (`TYPE T : INT := 5;`), through aliases."""
        seen: set[str] = set()
        while isinstance(spec, ast.NamedType) and key(spec.name) not in seen:
            seen.add(key(spec.name))
            decl = self.decls.get(key(spec.name))
            if decl is None:
                return None
            if decl.init is not None:
                return decl.init
            spec = decl.spec
        return None

    def resolve_named(self, name: str, pos: Pos) -> Type | None:
        found = elementary(name)
        if found is not None:
            return found
        name_key = key(name)
        if name_key in self.named:
            return self.named[name_key]
        decl = self.decls.get(name_key)
        if decl is not None:
            if name_key in self.in_progress:
                self.report(
                    pos, Code.RECURSIVE_TYPE, f"type '{name}' is defined in terms of itself"
                )
                return None
            if len(self.in_progress) >= MAX_DATA_DEPTH:  # resolving recurses through them
                message = f"types defined through one another more than {MAX_DATA_DEPTH} deep"
                self.report(pos, Code.DATA_DEPTH, message)
                return None
            self.in_progress.add(name_key)
            resolved = self.resolve_spec(decl.spec, {}, type_name=decl.name)
            self.in_progress.discard(name_key)
            self.named[name_key] = resolved
            return resolved
        pou = self.pou_kinds.get(name_key)
        if pou is not None and pou.kind in ("FUNCTION_BLOCK", "PROGRAM"):
            return FbType(pou.name)
        if name_key in self.interfaces:
            return InterfaceType(self.interfaces[name_key].name)
        why = f": {unknown_qualified(name, 'type')}" if "." in name else ""
        self.report(pos, Code.UNKNOWN_TYPE, f"unknown type '{name}'{why}")
        self.named[name_key] = None
        return None

    def resolve_spec(
        self,
        spec: ast.TypeRef,
        local_constants: dict[str, ast.Initializer | None],
        type_name: str | None = None,
    ) -> Type | None:
        match spec:
            case ast.NamedType(name=name, pos=pos):
                return self.resolve_named(name, pos)
            case ast.StringType(wide=wide, length=length, pos=pos):
                size = 0
                if length is not None:
                    size = self.const_int(length, local_constants) or 0
                    if size <= 0:
                        self.report(
                            pos, Code.STRING_LENGTH, "string length must be a positive constant"
                        )
                return ElementaryType("WSTRING" if wide else "STRING", "string", length=size)
            case ast.ArrayType():
                return self._array(spec, local_constants)
            case ast.VariadicType():
                return VariadicType()
            case ast.RefType(target=target, pointer=pointer, implicit=implicit, pos=pos):
                if pointer:
                    message = "POINTER TO is CODESYS/TwinCAT; IEC 61131-3 writes REF_TO"
                    self.report(pos, Code.POINTER, message)
                if implicit:
                    message = "REFERENCE TO is CODESYS/TwinCAT; IEC 61131-3 writes REF_TO and ^"
                    self.report(pos, Code.IMPLICIT_REFERENCE, message)
                inner = self.resolve_spec(target, local_constants)
                return None if inner is None else RefType(inner, pointer, implicit)
            case ast.SubrangeSpec():
                return self._subrange(spec, local_constants)
            case ast.EnumSpec():
                return self._enum(spec, type_name or f"enum@{spec.pos.line}:{spec.pos.col}")
            case ast.StructSpec():
                return self._struct(spec, type_name or f"struct@{spec.pos.line}:{spec.pos.col}")
        raise AssertionError(f"unhandled type spec {spec!r}")

    def _subrange(
        self, spec: ast.SubrangeSpec, local_constants: dict[str, ast.Initializer | None]
    ) -> Type | None:
        """A subrange is its base type (the range is checked here, not represented): an
        integer type, and bounds that are constant integers of it, the lower first."""
        base = self.resolve_named(spec.base, spec.pos)
        if base is None:
            return None
        if not (isinstance(base, ElementaryType) and base.is_integer):
            message = f"a subrange needs an integer base type, not '{base.name}'"
            self.report(spec.pos, Code.SUBRANGE_BASE, message)
            return base
        bounds = []
        for bound in (spec.low, spec.high):
            value = self.const_int(bound, local_constants)
            if value is None:
                message = f"subrange bounds must be constant integers of {base.name}"
                self.report(bound.pos, Code.SUBRANGE_BOUNDS, message)
                return base
            if not base.min <= value <= base.max:
                message = f"subrange bound {value} is outside {base.name}"
                self.report(bound.pos, Code.SUBRANGE_BOUNDS, message)
                return base
            bounds.append(value)
        low, high = bounds
        if high < low:
            self.report(spec.low.pos, Code.EMPTY_SUBRANGE, f"subrange {low}..{high} is empty")
        return base

    def _array(
        self, spec: ast.ArrayType, local_constants: dict[str, ast.Initializer | None]
    ) -> Type | None:
        element = self.resolve_spec(spec.element, local_constants)
        if isinstance(element, OpenArrayType):
            message = "an array of variable-length arrays cannot be stored; give its bounds"
            self.report(spec.element.pos, Code.VARIABLE_LENGTH_ARRAY, message)
            return None
        open_ranges = sum(1 for bounds in spec.ranges if bounds is None)
        if open_ranges == len(spec.ranges):
            return None if element is None else OpenArrayType(element, open_ranges)
        dims: list[tuple[int, int]] = []
        for bounds in spec.ranges:
            if bounds is None:
                message = "an array has either all its ranges open (*) or none"
                self.report(spec.pos, Code.VARIABLE_LENGTH_ARRAY, message)
                return None
            low = self.const_int(bounds[0], local_constants)
            high = self.const_int(bounds[1], local_constants)
            if low is None or high is None:
                self.report(
                    bounds[0].pos, Code.ARRAY_BOUNDS, "array bounds must be constant integers"
                )
                return None
            if high < low:
                self.report(
                    bounds[0].pos, Code.EMPTY_ARRAY_RANGE, f"array range {low}..{high} is empty"
                )
                return None
            dims.append((low, high))
        if element is None:
            return None
        return ArrayType(element, tuple(dims))

    def _enum(self, spec: ast.EnumSpec, name: str) -> Type | None:
        base: ElementaryType = INT
        if spec.base is not None:
            found = elementary(spec.base)
            if found is None or not found.is_integer:
                self.report(
                    spec.pos,
                    Code.ENUM_BASE,
                    f"enum base type must be an integer type, not '{spec.base}'",
                )
            else:
                base = found
        enum_type = EnumType(name, base)
        info = EnumInfo(enum_type, {})
        next_value = 0
        for value_name, value_expr, pos in spec.values:
            value = next_value
            if value_expr is not None:
                evaluated = self.const_int(value_expr, {})
                if evaluated is None:
                    self.report(
                        pos, Code.ENUM_VALUE, f"value of '{value_name}' must be a constant integer"
                    )
                else:
                    value = evaluated
            if key(value_name) in info.values:
                self.report(
                    pos, Code.DUPLICATE_ENUM_VALUE, f"'{value_name}' appears twice in enum '{name}'"
                )
            info.values[key(value_name)] = (value_name, value)
            next_value = value + 1
        self.result.enums[key(name)] = info
        for value_key, (_, value) in info.values.items():
            self.enum_values.setdefault(value_key, value)
        return enum_type

    def _struct(self, spec: ast.StructSpec, name: str) -> Type | None:
        info = StructInfo(name, [], {})
        self.result.structs[key(name)] = info
        for decl in spec.members:
            member_type = self.resolve_spec(decl.type, {})
            if member_type is None:
                continue
            if key(decl.name) in info.by_key:
                self.report(
                    decl.pos,
                    Code.DUPLICATE_MEMBER,
                    f"member '{decl.name}' appears twice in '{name}'",
                )
                continue
            init = decl.init if decl.init is not None else self.default_init(decl.type)
            variable = Variable(
                decl.name, "MEMBER", member_type, init, False, False, None,
                python_attr(decl.name), decl.pos,
            )  # fmt: skip
            info.members.append(variable)
            info.by_key[key(decl.name)] = variable
        return StructType(name)


@dataclass
class ResolveMemo:
    """What the last run of `resolve` on the same project qualified, for the next one (the
    language services resolve after each keystroke)."""

    names: QualifyMemo = field(default_factory=QualifyMemo)
    enum_values: EnumMemo = field(default_factory=EnumMemo)


def resolve(units: list[ast.SourceUnit], memo: ResolveMemo | None = None) -> Resolved:
    memo = memo or ResolveMemo()
    units, notes = qualify_names(units, memo.names)  # CODESYS `Tc2_Standard.TON` is `TON`
    units = qualify_enum_values(units, memo.enum_values)  # CODESYS `Color.Red` is `Color#Red`
    result = Resolved()
    result.diagnostics.extend(notes)
    types = _TypeResolver(units, result)
    for name in sorted(types.decls):  # every declared type, used or not, is checked
        types.resolve_named(types.decls[name].name, types.decls[name].pos)

    for unit in units:
        for block in unit.globals:
            for variable in _block_variables(block, types, {}):
                if key(variable.name) in result.globals_by_key:
                    first = result.globals_by_key[key(variable.name)]
                    result.diagnostics.append(
                        Diagnostic.at(
                            variable.pos,
                            Code.DUPLICATE_GLOBAL,
                            f"global '{variable.name}' is already declared at {first.pos}",
                        )
                    )
                    continue
                result.globals.append(variable)
                result.globals_by_key[key(variable.name)] = variable

    seen: dict[str, ast.Pou] = {}
    for unit in units:
        for pou in unit.pous:
            previous = seen.get(key(pou.name))
            if previous is not None:
                result.diagnostics.append(
                    Diagnostic.at(
                        pou.pos,
                        Code.DUPLICATE_POU,
                        f"'{pou.name}' is already declared at {previous.pos}",
                    )
                )
                continue
            seen[key(pou.name)] = pou
    for name in sorted(seen):
        result.pous[name] = _resolve_pou(seen[name], types, result)
    _resolve_interfaces(units, types, result)
    _resolve_methods(types, result)
    _resolve_properties(types, result)
    _inherit(result)
    _implemented(result)
    _implicit_globals(units, result)
    user_names = (types.decls, result.pous, result.globals_by_key)
    if not any(key(NAMESPACE) in names for names in user_names):  # the user's SYS wins
        result.system = system_variables()
    return result


def system_variables() -> dict[str, Variable]:
    """The system variables (`SYS.COLDSTART`) as variables of kind SYSTEM; the read-only
    ones are `constant` (only the runtime sets them). Generated code names them
    `_SYS.<NAME>`."""
    here = Pos("<system>", 1, 1)
    table: dict[str, Variable] = {}
    for entry in SYSTEM_VARIABLES:
        var_type = elementary(entry.type)
        assert var_type is not None, entry
        table[key(entry.name)] = Variable(
            entry.name, "SYSTEM", var_type, None, not entry.writable, False, None,
            entry.name, here,
        )  # fmt: skip
    return table


def _block_variables(
    block: ast.VarBlock, types: _TypeResolver, local_constants: dict[str, ast.Initializer | None]
) -> list[Variable]:
    variables = []
    for decl in block.decls:
        var_type = types.resolve_spec(decl.type, local_constants)
        if var_type is None:
            continue
        init = decl.init if decl.init is not None else types.default_init(decl.type)
        variables.append(
            Variable(
                name=decl.name,
                kind=block.kind,
                type=var_type,
                init=init,
                constant="CONSTANT" in block.qualifiers,
                retain="RETAIN" in block.qualifiers or "PERSISTENT" in block.qualifiers,
                location=decl.location,
                attr=python_attr(decl.name),
                pos=decl.pos,
                edge=decl.edge,
            )
        )
    return variables


STEP_STRUCT = "SFC_STEP"


def _step_struct(result: Resolved) -> StructType:
    """The type of an SFC step as ST sees it: `Step.X` (active) and `Step.T` (elapsed)."""
    if key(STEP_STRUCT) not in result.structs:
        here = Pos("<sfc>", 1, 1)
        members = [
            Variable("X", "MEMBER", BOOL, None, True, False, None, "X", here),
            Variable("T", "MEMBER", TIME, None, True, False, None, "T", here),
        ]
        result.structs[key(STEP_STRUCT)] = StructInfo(
            STEP_STRUCT, members, {key(m.name): m for m in members}
        )
    return StructType(STEP_STRUCT)


def _resolve_pou(pou: ast.Pou, types: _TypeResolver, result: Resolved) -> PouSymbols:
    symbols = PouSymbols(pou, [], {})
    if pou.return_type is not None:
        symbols.return_type = types.resolve_spec(pou.return_type, {})
        if symbols.return_type is not None:
            # inside a function its name is the variable that holds the result
            result_var = Variable(
                pou.name, "RETURN", symbols.return_type, None, False, False, None,
                python_attr(pou.name), pou.pos,
            )  # fmt: skip
            symbols.by_key[key(pou.name)] = result_var
    local_constants = {
        key(decl.name): decl.init
        for block in pou.var_blocks
        if "CONSTANT" in block.qualifiers
        for decl in block.decls
    }
    for block in pou.var_blocks:
        for variable in _block_variables(block, types, local_constants):
            if key(variable.name) in symbols.by_key:
                first = symbols.by_key[key(variable.name)]
                result.diagnostics.append(
                    Diagnostic.at(
                        variable.pos,
                        Code.DUPLICATE_VARIABLE,
                        f"'{variable.name}' is already declared at {first.pos}",
                    )
                )
                continue
            if variable.kind == "VAR_EXTERNAL":
                declared = result.globals_by_key.get(key(variable.name))
                if declared is None:
                    result.diagnostics.append(
                        Diagnostic.at(
                            variable.pos,
                            Code.EXTERNAL_WITHOUT_GLOBAL,
                            f"VAR_EXTERNAL '{variable.name}' has no VAR_GLOBAL",
                        )
                    )
                    continue
                variable = declared  # the same storage as the global
            symbols.variables.append(variable)
            symbols.by_key[key(variable.name)] = variable
    if pou.sfc is not None:
        step_type = _step_struct(result)
        for step in pou.sfc.steps:
            if key(step.name) in symbols.by_key:
                first = symbols.by_key[key(step.name)]
                result.diagnostics.append(
                    Diagnostic.at(
                        step.pos,
                        Code.STEP_NAME,
                        f"step '{step.name}': the name is already used at {first.pos}",
                    )
                )
                continue
            variable = Variable(
                step.name, "STEP", step_type, None, True, False, None,
                python_attr(step.name), step.pos,
            )  # fmt: skip
            symbols.variables.append(variable)
            symbols.by_key[key(step.name)] = variable
        for number, transition in enumerate(pou.sfc.transitions):
            _add_transition_value(symbols, number, transition, result)
    return symbols


TRANSITION_VARIABLE = "_TMP_TRANSITION"


def transition_variable(number: int) -> str:
    """The hidden BOOL in which a chart keeps the last value its transition `number`
    (0-based, in text order) took, for a live chart to show (it is evaluated only while
    the transition is enabled): `_TMP_TRANSITION1` for the first."""
    return f"{TRANSITION_VARIABLE}{number + 1}"


def _add_transition_value(
    symbols: PouSymbols, number: int, transition: ast.Transition, result: Resolved
) -> None:
    name = transition_variable(number)
    if key(name) in symbols.by_key:
        message = f"'{name}' is the name of the hidden value of transition {number + 1}"
        first = symbols.by_key[key(name)]
        result.diagnostics.append(Diagnostic.at(first.pos, Code.DUPLICATE_VARIABLE, message))
        return
    variable = Variable(name, "VAR", BOOL, None, False, False, None, name, transition.pos)
    symbols.variables.append(variable)
    symbols.by_key[key(name)] = variable


def _resolve_method(
    method: ast.Method,
    owner: PouSymbols | None,
    types: _TypeResolver,
    result: Resolved,
    declared_in: str = "",
) -> PouSymbols:
    """A method as a POU of kind METHOD: its parameters and locals, all temporary (Python
    locals named `x__`, which no name of the user or of the generated code is), and its
    result under its name."""
    pseudo = ast.Pou(
        "METHOD", method.name, method.return_type, method.var_blocks, method.body, method.pos
    )
    symbols = _resolve_pou(pseudo, types, result)
    apart = {
        id(v): replace(v, attr=f"{v.attr}__")
        for v in [*symbols.variables, *symbols.by_key.values()]
        if v.kind not in ("VAR_GLOBAL", "STEP")
    }
    symbols.variables = [apart.get(id(v), v) for v in symbols.variables]
    symbols.by_key = {k: apart.get(id(v), v) for k, v in symbols.by_key.items()}
    symbols.outer, symbols.method = owner, method
    symbols.declared_in = key(owner.name) if owner is not None else declared_in
    return symbols


def _resolve_methods(types: _TypeResolver, result: Resolved) -> None:
    """The methods each PROGRAM and FUNCTION_BLOCK declares itself."""
    for _, pou in sorted(result.pous.items()):
        for method in pou.pou.methods:
            name = key(method.name)
            clash = pou.methods[name].pou.pos if name in pou.methods else None
            variable = pou.by_key.get(name)
            if variable is not None and variable.kind != "RETURN":
                clash = variable.pos
            if clash is not None:
                message = f"method '{method.name}': the name is already used at {clash}"
                result.diagnostics.append(Diagnostic.at(method.pos, Code.METHOD_NAME, message))
                continue
            pou.methods[name] = _resolve_method(method, pou, types, result)


def _inherit(result: Resolved) -> None:
    """EXTENDS: a derived function block has its base's variables first (ordinary members
    of its instances) and its base's methods, which its own replace (OVERRIDE). A base that
    is unknown, no function block, or the block itself through its bases is refused."""
    done: set[str] = set()

    def settle(name: str, chain: tuple[str, ...]) -> None:
        pou = result.pous[name]
        if name in done or not pou.pou.extends:
            done.add(name)
            return
        done.add(name)
        if pou.kind != "FUNCTION_BLOCK" or len(pou.pou.extends) > 1:
            message = "only a FUNCTION_BLOCK extends, and one function block at most"
            result.diagnostics.append(Diagnostic.at(pou.pou.pos, Code.EXTENDS, message))
            return
        base_name = pou.pou.extends[0]
        base = result.pous.get(key(base_name))
        if base is None or base.kind != "FUNCTION_BLOCK":
            message = f"'{pou.name}' extends '{base_name}', which is no function block"
            result.diagnostics.append(Diagnostic.at(pou.pou.pos, Code.EXTENDS, message))
            return
        if key(base_name) in (*chain, name):
            message = f"'{pou.name}' extends itself through '{base_name}'"
            result.diagnostics.append(Diagnostic.at(pou.pou.pos, Code.CYCLIC_EXTENDS, message))
            return
        settle(key(base_name), (*chain, name))
        pou.base = key(base_name)
        inherited = [  # a chart is the block's own: not its steps, nor its transitions
            v
            for v in base.variables
            if v.kind != "STEP" and not v.name.startswith(TRANSITION_VARIABLE)
        ]
        for variable in inherited:
            own = pou.by_key.get(key(variable.name))
            if own is not None:
                message = (
                    f"'{own.name}' is already a variable of '{base.name}' (declared at "
                    f"{variable.pos}); a derived block cannot declare it again"
                )
                result.diagnostics.append(Diagnostic.at(own.pos, Code.DUPLICATE_VARIABLE, message))
                pou.variables.remove(own)
        pou.variables[:0] = inherited
        for variable in inherited:
            pou.by_key[key(variable.name)] = variable
        _name_clashes(pou, base, result)
        pou.methods = {**base.methods, **pou.methods}
        pou.properties = {**base.properties, **pou.properties}

    for name in sorted(result.pous):
        settle(name, ())


def _name_clashes(pou: PouSymbols, base: PouSymbols, result: Resolved) -> None:
    """A derived block's own method or property named like a variable of its base, or its
    own variable named like a method or property of its base."""
    members = {**base.methods, **base.properties}
    own = {k: m.pou.pos for k, m in pou.methods.items()}
    own.update({k: p.pos for k, p in pou.properties.items()})
    for name in sorted(own):
        variable = base.by_key.get(name)
        if variable is not None and variable.kind != "RETURN":
            message = (
                f"'{variable.name}' is a variable of '{base.name}' (declared at {variable.pos})"
            )
            result.diagnostics.append(Diagnostic.at(own[name], Code.METHOD_NAME, message))
    for variable in pou.variables:
        name = key(variable.name)
        if name in members and name not in base.by_key:
            message = f"'{variable.name}' is a method or property of '{base.name}'"
            result.diagnostics.append(Diagnostic.at(variable.pos, Code.METHOD_NAME, message))


def _resolve_interfaces(
    units: list[ast.SourceUnit], types: _TypeResolver, result: Resolved
) -> None:
    """Every INTERFACE: its method prototypes (PUBLIC), with those of the interfaces it
    extends; an interface named like another, a type or a POU is refused."""
    for unit in units:
        for interface in unit.interfaces:
            name = key(interface.name)
            if name in result.interfaces or name in types.decls or name in types.pou_kinds:
                message = f"'{interface.name}' is already declared"
                result.diagnostics.append(
                    Diagnostic.at(interface.pos, Code.DUPLICATE_TYPE, message)
                )
                continue
            info = InterfaceInfo(interface)
            for method in interface.methods:
                public = replace(method, access="PUBLIC")
                prototype = _resolve_method(public, None, types, result, declared_in=name)
                if key(method.name) in info.methods:
                    message = f"method '{method.name}' is declared twice in '{interface.name}'"
                    result.diagnostics.append(Diagnostic.at(method.pos, Code.METHOD_NAME, message))
                info.methods[key(method.name)] = prototype
            for prop in interface.properties:
                public_property = replace(prop, access="PUBLIC")
                found = resolve_property(public_property, None, types, result, name)
                if found is not None:
                    info.properties[key(prop.name)] = found
            result.interfaces[name] = info
    done: set[str] = set()

    def settle(name: str, chain: tuple[str, ...]) -> None:
        info = result.interfaces[name]
        if name in done:
            return
        done.add(name)
        closure: list[str] = []
        for base_name in info.decl.extends:
            base = key(base_name)
            if base not in result.interfaces:
                message = f"'{info.name}' extends '{base_name}', which is no interface"
                result.diagnostics.append(Diagnostic.at(info.decl.pos, Code.INTERFACE, message))
                continue
            if base in (*chain, name):
                message = f"'{info.name}' extends itself through '{base_name}'"
                result.diagnostics.append(
                    Diagnostic.at(info.decl.pos, Code.CYCLIC_EXTENDS, message)
                )
                continue
            settle(base, (*chain, name))
            closure += [base, *result.interfaces[base].extends]
            info.methods = {**result.interfaces[base].methods, **info.methods}
            info.properties = {**result.interfaces[base].properties, **info.properties}
        info.extends = tuple(sorted(set(closure)))

    for name in sorted(result.interfaces):
        settle(name, ())


def _implemented(result: Resolved) -> None:
    """The interfaces each block implements: named by IMPLEMENTS, its base's, and the ones
    these extend (an unknown name is refused)."""
    for name in sorted(result.pous, key=lambda n: _depth(result, n)):
        pou = result.pous[name]
        found: list[str] = list(result.pous[pou.base].interfaces) if pou.base else []
        for interface in pou.pou.implements:
            info = result.interfaces.get(key(interface))
            if info is None or pou.kind != "FUNCTION_BLOCK":
                message = f"'{pou.name}' implements '{interface}', which is no interface"
                if pou.kind != "FUNCTION_BLOCK":
                    message = "only a FUNCTION_BLOCK implements interfaces"
                result.diagnostics.append(Diagnostic.at(pou.pou.pos, Code.INTERFACE, message))
                continue
            found += [key(interface), *info.extends]
        pou.interfaces = tuple(sorted(set(found)))


def _depth(result: Resolved, name: str) -> tuple[int, str]:
    """How many bases a block has (bases first), then its name."""
    depth, current = 0, result.pous[name].base
    while current is not None and depth <= len(result.pous):
        depth, current = depth + 1, result.pous[current].base
    return depth, name


def _accessor(prop: ast.Property, accessor: ast.Accessor, prop_type: ast.TypeRef) -> ast.Method:
    """A GET or SET as the method it is: GET gives the property's value (its result named
    like the property), SET takes it (an input named like the property)."""
    blocks = accessor.var_blocks
    if accessor.kind == "SET":
        value = ast.VarDecl(prop.name, prop_type, None, None, prop.pos)
        blocks = (ast.VarBlock("VAR_INPUT", (), (value,), accessor.pos), *blocks)
    return_type = prop_type if accessor.kind == "GET" else None
    return ast.Method(
        prop.name, prop.access, prop.modifiers, return_type, blocks, accessor.body, accessor.pos
    )


def resolve_property(
    prop: ast.Property,
    owner: PouSymbols | None,
    types: _TypeResolver,
    result: Resolved,
    declared_in: str,
) -> PropertyInfo | None:
    """A property of a block (`owner`) or an interface (`declared_in`)."""
    prop_type = types.resolve_spec(prop.type, {})
    if prop_type is None:
        return None
    accessors: dict[str, PouSymbols] = {}
    for accessor in prop.accessors:
        if accessor.kind in accessors:
            message = f"property '{prop.name}' has two {accessor.kind}s"
            result.diagnostics.append(Diagnostic.at(accessor.pos, Code.METHOD_NAME, message))
            continue
        method = _accessor(prop, accessor, prop.type)
        accessors[accessor.kind] = _resolve_method(method, owner, types, result, declared_in)
    return PropertyInfo(
        prop.name, prop_type, accessors.get("GET"), accessors.get("SET"), declared_in, prop.pos
    )


def _resolve_properties(types: _TypeResolver, result: Resolved) -> None:
    """The properties each PROGRAM and FUNCTION_BLOCK declares itself."""
    for _, pou in sorted(result.pous.items()):
        for prop in pou.pou.properties:
            name = key(prop.name)
            variable = pou.by_key.get(name)
            clash = variable.pos if variable is not None and variable.kind != "RETURN" else None
            if name in pou.methods:
                clash = pou.methods[name].pou.pos
            if name in pou.properties:
                clash = pou.properties[name].pos
            if clash is not None:
                message = f"property '{prop.name}': the name is already used at {clash}"
                result.diagnostics.append(Diagnostic.at(prop.pos, Code.METHOD_NAME, message))
                continue
            info = resolve_property(prop, pou, types, result, key(pou.name))
            if info is not None:
                pou.properties[name] = info
