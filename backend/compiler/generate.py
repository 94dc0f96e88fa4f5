"""Stage 4, generate: every POU and user data type as the typed form of the contract
(runtime/contract/code/: expressions and statements as data, with their types and ST
lines), printed as the Python the runtime loads.

PROGRAMs and FUNCTION_BLOCKs become classes (`POU_<NAME>`: variables as slots, `__call__`
runs one cycle or call); FUNCTIONs become plain functions (`FN_<NAME>`) whose variables are
Python locals; STRUCTs become small classes (`STRUCT_<NAME>`). Globals live on `_G`, program
instances on `_P`. Integers are wrapped to their width only where a value is consumed (a
store, a comparison, a division, an argument), never after each + - *, since wrapping
commutes with those.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, fields, is_dataclass

from backend.compiler import ast, builtins
from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.constants import is_zero_literal
from backend.compiler.conversions import converted, intrinsic, literal_in, wrap_constant, wrapped
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.infer import (
    ActionCall,
    EnumValue,
    IsValidRef,
    MethodCall,
    Misfit,
    NonFinite,
    ProgramRef,
    PropertyAccess,
    RefOf,
    Scope,
    SizeOf,
    binds_reference,
    block_eno,
    enable_argument,
    instance_fields,
    is_external,
    is_implicit,
)
from backend.compiler.limits import MAX_INDENT, MAX_UNIT_CODE, MiB
from backend.compiler.resolve import (
    STEP_STRUCT,
    PouSymbols,
    Resolved,
    StructInfo,
    Variable,
    transition_variable,
)
from backend.compiler.source import Pos
from backend.compiler.test_functions import TEST_CYCLES_CALL, test_call_statements
from backend.compiler.types import (
    ANY_INT,
    ANY_REAL,
    BOOL,
    NULL_TYPE,
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
    artifact_type_text,
    common_numeric,
    integer_like,
    is_implicit_reference,
    value_type,
)
from runtime.contract.code.python_text import python_text, unit_lines
from runtime.contract.code.statements import (
    Assign,
    Break,
    Continue,
    Elif,
    Evaluate,
    ForEach,
    If,
    Pass,
    Return,
    Stmt,
    While,
)
from runtime.contract.code.typed_form import (
    Assigned,
    Binary,
    BinaryOp,
    Call,
    Chain,
    Choice,
    Const,
    Expr,
    Index,
    Logic,
    Member,
    Members,
    Named,
    Repeated,
    Sequence,
    Slice,
    This,
    Unary,
    Var,
)
from runtime.contract.code.units import Alias, Class, Function, Inherited, Param, Slot, Unit
from runtime.contract.values import to_real32

_COMPARE: dict[str, BinaryOp] = {"=": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}
_BITWISE: dict[str, BinaryOp] = {"AND": "&", "&": "&", "OR": "|", "XOR": "^"}
LOCAL_KINDS = ("VAR_TEMP", "RETURN")  # Python locals even in a class's __call__


def is_python_local(variable: Variable, in_function: bool) -> bool:
    """Whether a variable of a POU (not a global) is a Python local in its generated code."""
    return in_function or variable.kind in LOCAL_KINDS


def python_locals(pou: PouSymbols) -> list[Variable]:
    """The variables of a POU that its generated code holds in Python locals (a function's
    result among them)."""
    result = pou.by_key.get(key(pou.name))
    declared = [
        *pou.variables,
        *([result] if result is not None and result.kind == "RETURN" else []),
    ]
    return [
        v
        for v in declared
        if v.kind not in ("SYSTEM", "VAR_GLOBAL") and is_python_local(v, pou.kind == "FUNCTION")
    ]


def class_members(pou: PouSymbols) -> set[str]:
    """The names the class of a PROGRAM or FUNCTION_BLOCK has besides its variables: its
    methods, and the slots of edge memories and action control blocks."""
    sfc = pou.pou.sfc
    chart = _Chart(sfc).slots() if sfc is not None else []
    actions = [_action_method(action.name) for action in sfc.actions] if sfc is not None else []
    edges = [_edge_memory(v) for v in instance_fields(pou) if v.edge is not None]
    methods = [method_attr(m.name) for m in pou.methods.values()]
    methods += [f(p.name) for p in pou.properties.values() for f in (getter_attr, setter_attr)]
    return {"__slots__", "KIND__", "__init__", "__call__", *chart, *actions, *edges, *methods}


def method_attr(name: str) -> str:
    """A method of the class of a FUNCTION_BLOCK or PROGRAM (no variable has `__`)."""
    return f"M__{_ident(name)}"


def getter_attr(name: str) -> str:
    """The GET of a property, a method of the block's class."""
    return f"GET__{_ident(name)}"


def setter_attr(name: str) -> str:
    return f"SET__{_ident(name)}"


def _edge_memory(variable: Variable) -> str:
    """The slot that remembers an R_EDGE or F_EDGE input's last value."""
    return f"_edge_{variable.attr}"


def _ident(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]", "_", key(name))


def class_name(pou_name: str) -> str:
    return f"POU_{_ident(pou_name)}"


def function_name(pou_name: str) -> str:
    return f"FN_{_ident(pou_name)}"


def struct_class(struct_name: str) -> str:
    return f"STRUCT_{_ident(struct_name)}"


def is_aggregate(t: Type) -> bool:
    return isinstance(t, ArrayType | OpenArrayType | StructType | FbType)


def returns_tuple(pou: PouSymbols) -> bool:
    """Functions with outputs or in-outs return (result, outputs..., in-outs...)."""
    return any(v.kind in ("VAR_OUTPUT", "VAR_IN_OUT") for v in pou.variables)


def tuple_members(pou: PouSymbols) -> list[Variable]:
    outputs = [v for v in pou.variables if v.kind == "VAR_OUTPUT"]
    return outputs + [v for v in pou.variables if v.kind == "VAR_IN_OUT"]


class GenerationError(Exception):
    """Code a resource could not load (too large, too deep) or that would not work (a name
    of the user hiding one of its own): generation stops, with what was wrong."""

    def __init__(self, diagnostics: list[Diagnostic]) -> None:
        super().__init__("\n".join(str(d) for d in diagnostics))
        self.diagnostics = diagnostics


@dataclass
class _Value:
    node: Expr
    type: Type
    unwrapped: bool = False  # an integer result that may lie outside its type's range
    # an unwrapped `head + n` (n a literal): its wrap adds n to the wrap's own constant
    constant_tail: tuple[Expr, int] | None = None


@dataclass
class _Emitter:
    scope: Scope
    local: bool  # a FUNCTION: its variables are Python locals
    at: Pos  # what is being generated (a statement, a declaration), where a limit is met
    pre: list[Stmt] = field(default_factory=list)  # hoisted statements for the next one
    body: list[Stmt] = field(default_factory=list)  # the block being generated
    depth: int = 0  # the indentation of that block's lines
    temp_count: int = 0
    in_globals: bool = False  # initialising GLOBALS itself: other globals are on `s`
    # the width the + - * expression being generated is wrapped to where it is stored
    modulus_bits: int | None = None
    st_line: int = 0  # the ST line of the statement being generated (0: none)
    size: int = 0  # characters printed so far
    max_size: int = MAX_UNIT_CODE
    # FOR counters held in a Python local while their loop runs: (kind, attr) -> local
    counters: dict[tuple[str, str], str] = field(default_factory=dict)
    # the values such a local takes when nothing but the loop can change it: an index of
    # it needs no bounds check when they all lie within the array's
    counter_ranges: dict[str, tuple[int, int]] = field(default_factory=dict)
    # generating a method: its own variables (by id), Python locals of its function
    method_locals: frozenset[int] = frozenset()
    # the temporary holding the EN of each call generated with one, by id() of the call
    enables: dict[int, str] = field(default_factory=dict)

    def body_of(self, depth: int, fill: Callable[[], object]) -> tuple[Stmt, ...]:
        """The statements `fill` generates, as the block of a function at `depth`."""
        self.depth, self.body = depth, []
        fill()
        self.add()  # what the last expression hoisted
        statements, self.body = self.body, []
        return tuple(statements)

    def make_room(self, size: int) -> None:
        """Refuse `size` more characters beyond the unit's limit, before a long line is
        even built."""
        if self.size + size > self.max_size:
            message = f"the generated code of this unit exceeds {self.max_size // MiB} MiB"
            raise GenerationError([Diagnostic.at(self.at, Code.CODE_SIZE, message)])

    def temp(self) -> str:
        self.temp_count += 1
        return f"__t{self.temp_count}"

    # ---- storage
    def var_node(self, variable: Variable) -> Var:
        type_text = artifact_type_text(variable.type)
        counter = self.counters.get((variable.kind, variable.attr))
        if counter is not None:
            return Var(counter, "local", type_text)
        if variable.kind == "SYSTEM":  # SYS.COLDSTART
            return Var(variable.attr, "system", type_text)
        if variable.kind == "VAR_GLOBAL":
            return Var(variable.attr, "instance" if self.in_globals else "globals", type_text)
        if id(variable) in self.method_locals or is_python_local(variable, self.local):
            return Var(variable.attr, "local", type_text)
        return Var(variable.attr, "instance", type_text)

    # ---- expressions
    def exact(self, expr: ast.Expr) -> _Value:
        return _exact(self.expr(expr))

    def exact_node(self, expr: ast.Expr) -> Expr:
        return self.exact(expr).node

    def type_of(self, expr: ast.Expr) -> Type:
        return _type(self.scope, expr)

    def expr(self, expr: ast.Expr) -> _Value:
        ring = (isinstance(expr, ast.Binary) and expr.op in ("+", "-", "*")) or (
            isinstance(expr, ast.Unary) and expr.op == "-"
        )
        if ring:
            return self._expr(expr)
        saved, self.modulus_bits = self.modulus_bits, None  # the value itself counts here
        try:
            return self._expr(expr)
        finally:
            self.modulus_bits = saved

    def _expr(self, expr: ast.Expr) -> _Value:
        match expr:
            case ast.IntLiteral(value=v):
                literal_type = _type(self.scope, expr)
                if isinstance(literal_type, ElementaryType) and literal_type.category == "real":
                    number = float(v)  # REAL#5
                    value = to_real32(number) if literal_type.bits == 32 else number
                    return _constant(value, literal_type)
                if isinstance(literal_type, ElementaryType) and not literal_type.is_any_literal:
                    v = wrap_constant(v, literal_type)
                return _constant(v, literal_type)
            case ast.RealLiteral(value=v):
                literal_type = _type(self.scope, expr)
                if isinstance(literal_type, ElementaryType) and literal_type.bits == 32:
                    v = to_real32(v)  # REAL#7.3 is the single nearest 7.3, as a REAL holds it
                return _constant(v, literal_type)
            case ast.BoolLiteral(value=v):
                return _constant(v, BOOL)
            case ast.TimeLiteral(nanoseconds=ns):
                return _constant(ns, _type(self.scope, expr))
            case ast.StringLiteral(value=v):
                return _constant(v, _type(self.scope, expr))
            case ast.EnumLiteral():
                return _constant(self.scope.enum_literal_value(expr), _type(self.scope, expr))
            case ast.NameRef(name=name):
                binding = self.scope.enum_hint(expr) or self.scope.lookup(name)
                if isinstance(binding, EnumValue):
                    return _constant(binding.value, binding.type)
                if isinstance(binding, NonFinite):  # float('inf'), float('nan')
                    return _constant(float(binding.value), binding.type)
                if isinstance(binding, ProgramRef):
                    program = FbType(binding.pou.name)
                    return _Value(
                        Var(class_name(binding.pou.name), "programs", _t(program)), program
                    )
                if binding is None:  # a property of the block
                    return self._property_get(expr)
                if binding.kind == "THIS":  # a reference to the instance the code runs on
                    return _Value(_reference_call(This(""), (), Const("", "STRING")), binding.type)
                return _implicit(self.var_node(binding), binding.type)
            case ast.MemberRef(base=base):
                member = self.scope.member(expr)
                if member is None:
                    return self._property_get(expr)
                if member.kind == "SYSTEM":
                    return _Value(self.var_node(member), member.type)
                owner = self.expr(base).node
                return _implicit(Member(owner, member.attr, _t(member.type)), member.type)
            case ast.IndexRef():
                return self._index(expr)
            case ast.NullLiteral():
                return _Value(Const(None, NULL_TYPE.name), NULL_TYPE)
            case ast.Deref() if self.scope.self_deref(expr) is not None:
                return _Value(This(""), _type(self.scope, expr))  # THIS^, SUPER^: the instance
            case ast.Deref(base=base):  # NULL is a program fault (`_deref`)
                result = _type(self.scope, expr)
                return _Value(intrinsic("_deref", _t(result), self.expr(base).node), result)
            case ast.BitRef(base=base, bit=bit, width=width):
                whole = self.exact(base)
                shifted = Binary(">>", whole.node, _int(bit * width), _t(whole.type))
                if width == 1:
                    low = Binary("&", shifted, _int(1), "BOOL")
                    return _Value(Binary("==", low, _int(1), "BOOL"), BOOL)
                result = _type(self.scope, expr)
                return _Value(Binary("&", shifted, _int((1 << width) - 1), _t(result)), result)
            case ast.Unary():
                return self._unary(expr)
            case ast.Binary():
                return self._binary(expr)
            case ast.Call():
                return self.call(expr)
        raise AssertionError(f"unhandled expression {expr!r}")

    def _index(self, expr: ast.IndexRef) -> _Value:
        base = self.expr(expr.base)
        array = base.type
        if isinstance(array, OpenArrayType):
            return self._open_index(base.node, array, expr.indices)
        assert isinstance(array, ArrayType)
        offset = self._flat_offset(expr, array)
        return _Value(Index(base.node, offset, _t(array.element)), array.element)

    def _flat_offset(self, expr: ast.IndexRef, array: ArrayType) -> Expr:
        """The list offset of an element, each index checked against its bounds."""
        offsets: list[Expr] = []
        # the last index first, as its code has always been generated (temporaries in order)
        for index_expr, (low, high) in reversed(list(zip(expr.indices, array.dims, strict=True))):
            constant = self.scope.constant_int(index_expr)
            if constant is not None and low <= constant <= high:
                offsets.append(_int(constant - low))
            else:
                offsets.append(self._checked_offset(self.exact_node(index_expr), low, high))
        return _flat(offsets[::-1], array.dims)

    def reference(self, expr: ast.Expr) -> Expr:
        """REF(expr): `_ref(root, steps, label)`, the object that holds the variable, the
        accessors below it (a list offset computed now) and its ST path below the root
        (the runtime puts the root's path before it)."""
        held = self.held_reference(expr)
        if held is not None:  # REF of a REFERENCE TO: the reference it holds
            return held
        root, steps, label, whole = self._place(expr)
        return _reference_call(root, tuple(steps), label, whole)

    def _place(self, expr: ast.Expr) -> tuple[Expr, list[Expr], Expr, bool]:
        """(root, accessors, label, whether the label is a whole path)."""
        match expr:
            case ast.NameRef(name=name):
                binding = self.scope.lookup(name)
                if isinstance(binding, ProgramRef):
                    program = Var(class_name(binding.pou.name), "programs", binding.pou.name)
                    return program, [], _text(name), False
                assert isinstance(binding, Variable)
                variable = self.var_node(binding)
                assert variable.where != "local", "REF of a local is refused before this"
                return _ROOTS[variable.where], [_text(variable.name)], _text(binding.name), False
            case ast.MemberRef(base=base, member=member_name):
                member = self.scope.member(expr)
                assert member is not None
                root, steps, label, whole = self._place(base)
                if label == _text(""):
                    named: Expr = _text(member_name)
                else:
                    named = Binary("+", label, _text("." + member_name), "STRING")
                return root, [*steps, _text(member.attr)], named, whole
            case ast.IndexRef(base=base, indices=indices):
                array = _type(self.scope, base)
                assert isinstance(array, ArrayType)
                held = [self.temp() for _ in indices]  # each index evaluated once
                for temp, index in zip(held, indices, strict=True):
                    self.pre.append(
                        Assign(Var(temp, "local", "DINT"), self.exact_node(index), self.st_line)
                    )
                offset = self._offset_of_held(array, held)
                root, steps, label, whole = self._place(base)
                shown = Binary("+", label, _text("["), "STRING")
                for number, temp in enumerate(held):
                    if number:
                        shown = Binary("+", shown, _text(", "), "STRING")
                    index_text = intrinsic("str", "STRING", Var(temp, "local", "DINT"))
                    shown = Binary("+", shown, index_text, "STRING")
                return root, [*steps, offset], Binary("+", shown, _text("]"), "STRING"), whole
            case ast.Deref() if self.scope.self_deref(expr) is not None:
                return This(""), [], _text(""), False  # THIS^: the instance, by its own path
            case ast.Deref(base=base):  # REF(r^.x): below what r refers to, named by r
                reference = self.expr(base).node
                named = Binary("+", intrinsic("str", "STRING", reference), _text("^"), "STRING")
                return intrinsic("_deref", "", reference), [], named, True
        raise AssertionError(f"no place for {expr!r}")

    def _offset_of_held(self, array: ArrayType, held: list[str]) -> Expr:
        """The list offset of an element whose indices are held in `held`."""
        offsets = [
            self._checked_offset(Var(index, "local", "DINT"), low, high)
            for index, (low, high) in zip(held, array.dims, strict=True)
        ]
        return _flat(offsets, array.dims)

    def _open_index(
        self, base: Expr, array: OpenArrayType, indices: tuple[ast.Expr, ...]
    ) -> _Value:
        """An element of a variable-length array, `[items, bounds]` at run time: its offset
        in the items from the bounds of the array passed, each index checked by `_ix`."""
        offset: Expr = _int(0)
        bounds = Index(base, _int(1), "")
        for dim, index_expr in enumerate(indices):
            low, high = (Index(Index(bounds, _int(dim), ""), _int(end), "DINT") for end in (0, 1))
            checked = intrinsic("_ix", "DINT", self.exact_node(index_expr), low, high)
            if dim == 0:
                offset = checked
                continue
            length = Binary("+", Binary("-", high, low, "DINT"), _int(1), "DINT")
            offset = Binary("+", Binary("*", offset, length, "DINT"), checked, "DINT")
        items = Index(base, _int(0), "")
        return _Value(Index(items, offset, _t(array.element)), array.element)

    def open_array_argument(self, param: Variable, value_expr: ast.Expr) -> Expr:
        """What a variable-length array parameter is bound to: the items of the array passed
        (the caller's own for an in-out, a copy for an input) and its bounds, in lists, which
        a saved context holds (the items as an alias of the caller's array)."""
        passed = self.expr(value_expr)
        bound_type = _t(param.type)
        if isinstance(passed.type, OpenArrayType):  # passed on: its items and bounds
            items: Expr = Index(passed.node, _int(0), "")
            bounds: Expr = Index(passed.node, _int(1), "")
        else:
            assert isinstance(passed.type, ArrayType)
            items = passed.node
            dims = tuple(Sequence((_int(low), _int(high)), "") for low, high in passed.type.dims)
            bounds = Sequence(dims, "")
        if param.kind != "VAR_INPUT":  # an in-out, or a function's output: the caller's
            if isinstance(passed.type, OpenArrayType):
                return passed.node
            return Sequence((items, bounds), bound_type)
        return Sequence((intrinsic("_copy", "", items), bounds), bound_type)

    def _checked_offset(self, index: Expr, low: int, high: int) -> Expr:
        """The list offset of an array index, checked against the bounds inline (the
        index evaluated once); `_ix` is called only to raise the fault outside them."""
        local = index.name if isinstance(index, Var) and index.where == "local" else None
        known = self.counter_ranges.get(local) if local is not None else None
        if known is not None and low <= known[0] and known[1] <= high:
            return Binary("-", index, _int(low), "DINT") if low else index
        if local is not None:  # a Python local: read it twice
            value, bound = index, index
        else:
            held = self.temp()
            value, bound = Var(held, "local", "DINT"), Assigned(held, index, "DINT")
        within = Chain("<=", (_int(low), bound, _int(high)))
        fault = intrinsic("_ix", "DINT", value, _int(low), _int(high))
        return Choice(within, Binary("-", value, _int(low), "DINT"), fault, "DINT")

    def _unary(self, expr: ast.Unary) -> _Value:
        result = _type(self.scope, expr)
        operand = self.expr(expr.operand)  # generated once: it may hoist calls
        if expr.op == "NOT":
            if result == BOOL:
                return _Value(Unary("not", operand.node, "BOOL"), BOOL)
            assert isinstance(result, ElementaryType)
            exact = _exact(operand).node
            if result.signed:  # two's complement: NOT x = -x - 1
                return _Value(Unary("~", exact, _t(result)), result)
            return _Value(Binary("^", exact, _int((1 << result.bits) - 1), _t(result)), result)
        if expr.op == "+":
            return operand
        integral = isinstance(result, ElementaryType) and result.category != "real"
        return _Value(Unary("-", operand.node, _t(result)), result, integral)

    def _binary(self, expr: ast.Binary) -> _Value:
        result = _type(self.scope, expr)
        op = expr.op
        if op in _COMPARE and isinstance(_type(self.scope, expr.left), RefType | InterfaceType):
            # CODESYS 0
            right = _NULL if is_zero_literal(expr.right) else self.exact_node(expr.right)
            return _Value(Binary(_COMPARE[op], self.exact_node(expr.left), right, "BOOL"), BOOL)
        if op in _COMPARE and isinstance(_type(self.scope, expr.right), RefType | InterfaceType):
            left = _NULL if is_zero_literal(expr.left) else self.exact_node(expr.left)
            return _Value(Binary(_COMPARE[op], left, self.exact_node(expr.right), "BOOL"), BOOL)
        if op in _COMPARE:
            common = _comparison_type(self.scope, expr)
            left, right = self.operand(expr.left, common), self.operand(expr.right, common)
            return _Value(Binary(_COMPARE[op], left, right, "BOOL"), BOOL)
        if op in _BITWISE:
            left, right = self.exact_node(expr.left), self.exact_node(expr.right)
            return _Value(Binary(_BITWISE[op], left, right, _t(result)), result)
        assert isinstance(result, ElementaryType)
        if result.category in ("time", "date"):
            return self._time_binary(expr, result)
        integral = result.category in ("int", "bits")
        name = _t(result)
        if op in ("+", "-", "*"):
            # + - * commute with wrapping: operands of the result's type stay unwrapped
            left = self.operand(expr.left, result, ring=True)
            right = self.operand(expr.right, result, ring=True)
            ring_op: BinaryOp = "+" if op == "+" else "-" if op == "-" else "*"
            value = Binary(ring_op, left, right, name)
            if result.category == "real":
                return _Value(
                    intrinsic("_f32", result, value) if result.bits == 32 else value, result
                )
            tail = None
            if integral and op != "*" and _is_int_constant(right):
                assert isinstance(right, Const) and isinstance(right.value, int)
                tail = (left, right.value if op == "+" else -right.value)
            return _Value(value, result, integral, tail)
        left, right = self.operand(expr.left, result), self.operand(expr.right, result)
        if op == "/":
            if result.category == "real":
                quotient = intrinsic("_fdiv", result, left, right)
                return _Value(
                    intrinsic("_f32", result, quotient) if result.bits == 32 else quotient, result
                )
            return _Value(intrinsic("_idiv", result, left, right), result, True)
        if op == "MOD":
            return _Value(intrinsic("_imod", result, left, right), result)
        if op == "**":
            return _Value(intrinsic("_pow", result, left, right), result)
        raise AssertionError(f"unhandled operator {op}")

    def _time_binary(self, expr: ast.Binary, result: ElementaryType) -> _Value:
        """TIME/date arithmetic: nanosecond counts, scaled by numbers for * and /."""
        right_type = integer_like(_type(self.scope, expr.right)) or _type(self.scope, expr.right)
        left, right = self.exact_node(expr.left), self.exact_node(expr.right)
        op, name = expr.op, _t(result)
        if op in ("+", "-"):
            return _Value(Binary("+" if op == "+" else "-", left, right, name), result, True)
        if op == "*":
            return _Value(
                intrinsic("_round", result, Binary("*", left, right, "LREAL")), result, True
            )
        if isinstance(right_type, ElementaryType) and right_type.category == "real":
            return _Value(intrinsic("_tdiv", result, left, right), result, True)
        return _Value(intrinsic("_idiv", result, left, right), result, True)

    def operand(self, expr: ast.Expr, target: Type, ring: bool = False) -> Expr:
        """`expr` as an operand of an operation computed in `target` (IEC: the operands
        are converted to the operation's type first). With `ring`, an operand of the
        target's own integer type may stay unwrapped (+ - * commute with wrapping)."""
        value = self.expr(expr)
        source = integer_like(value.type) or value.type
        if not isinstance(target, ElementaryType) or not isinstance(source, ElementaryType):
            return _exact(value).node
        if target.category == "real":
            number = _literal_number(expr) if source.is_any_literal else None
            if number is not None:  # a literal takes the type of the operation: REAL#0.1
                return Const(to_real32(number) if target.bits == 32 else number, _t(target))
            if source.category == "real":
                return value.node
            exact = _exact(value).node  # an integer: made a REAL before the operation
            return intrinsic("_f32" if target.bits == 32 else "float", target, exact)
        if ring and value.unwrapped and source == target:
            return value.node
        if ring and value.unwrapped and self.modulus_bits and source.bits >= self.modulus_bits:
            # the whole + - * expression is wrapped to fewer bits at its store: an inner wrap
            # to as many bits or more cannot change the stored result
            return value.node
        return _exact(value).node

    # ---- calls
    def call(self, call: ast.Call) -> _Value:
        callee = self.scope.callee(call)
        if isinstance(callee, MethodCall):
            return self._method_call(callee, call)
        pou = self.scope.resolved.pous.get(key(call.name))
        if pou is not None and pou.kind == "FUNCTION" and not is_external(pou):
            return self._user_call(pou, call, function_name(pou.name))
        if isinstance(callee, SizeOf):  # a constant: its argument never runs
            return _constant(self.scope.size_of(call), _type(self.scope, call))
        if isinstance(callee, RefOf):
            referenced = self.scope.referenced(call)
            assert referenced is not None
            return _Value(self.reference(referenced), _type(self.scope, call))
        if isinstance(callee, IsValidRef):  # the REFERENCE TO holds a reference, not NULL
            referenced = self.scope.referenced(call)
            held = self.held_reference(referenced) if referenced is not None else None
            assert held is not None
            return _Value(Binary("is not", held, _NULL, "BOOL"), BOOL)
        if self.scope.test_call(call) is not None:  # TEST_CYCLES(), the one with a value
            return _Value(TEST_CYCLES_CALL, _type(self.scope, call))
        builtin = builtins.lookup(call.name)
        assert builtin is not None, call.name
        args = self.scope.builtin_arguments(builtin, call)
        assert not isinstance(args, Misfit)
        enable = self._function_enable(call, None)
        values = [self.exact(arg) for arg in args]
        result = _type(self.scope, call)
        node = builtin.emit([v.node for v in values], [v.type for v in values], result)
        if enable is not None:  # EN FALSE: the function does not run and gives its default
            node = Choice(_enabled(enable), node, self.initial(result, None), _t(result))
        return _Value(node, result)

    def _accessor_owner(self, access: PropertyAccess) -> tuple[Expr, Expr | None]:
        """(the object or class whose accessor runs, the instance a static call passes)."""
        if access.static is not None:
            return Named(class_name(access.static.name)), This("")
        if access.receiver is None:
            return This(""), None
        receiver = self.expr(access.receiver).node
        if isinstance(_type(self.scope, access.receiver), InterfaceType):
            receiver = intrinsic("_deref", "", receiver)
        return receiver, None

    def _property_get(self, expr: ast.Expr) -> _Value:
        access = self.scope.property_access(expr)
        assert access is not None
        owner, first = self._accessor_owner(access)
        getter = Member(owner, getter_attr(access.prop.name), "")
        arguments = () if first is None else (first,)
        return _Value(Call(getter, arguments, _t(access.prop.type)), access.prop.type)

    def _property_set(self, target: ast.Expr, value: Expr) -> Stmt | None:
        """The statement that writes `value` through a property's SET (None: no property)."""
        access = self.scope.property_access(target)
        if access is None:
            return None
        owner, first = self._accessor_owner(access)
        setter = Member(owner, setter_attr(access.prop.name), "")
        arguments = (value,) if first is None else (first, value)
        return Evaluate(Call(setter, arguments, ""), self.st_line)

    def _method_call(self, target: MethodCall, call: ast.Call) -> _Value:
        """`inst.M(...)`: the method the instance's class has (an override, dispatched by
        Python); `SUPER^.M(...)`: the base's own, called on this instance."""
        method = method_attr(target.method.name)
        if target.static is not None:
            static = Member(Named(class_name(target.static.name)), method, "")
            return self._user_call(target.method, call, static, This(""))
        receiver = This("") if target.receiver is None else self.expr(target.receiver).node
        if target.receiver is not None and isinstance(
            _type(self.scope, target.receiver), InterfaceType
        ):  # the instance it refers to; none is a program fault, as NULL^ is
            receiver = intrinsic("_deref", "", receiver)
        return self._user_call(target.method, call, Member(receiver, method, ""))

    def _user_call(
        self, pou: PouSymbols, call: ast.Call, callee: str | Expr, first: Expr | None = None
    ) -> _Value:
        """A call of a function (or a method: `first` the instance a static call passes)."""
        pairs = self.scope.connect_arguments(pou, call)
        assigned = {
            key(param.name): arg
            for arg, param in pairs
            if param is not None and not is_implicit(param)
        }
        keywords: list[tuple[str, Expr]] = []
        for param in pou.parameters:
            arg = assigned.get(key(param.name))
            if arg is not None and arg.value is not None and isinstance(param.type, OpenArrayType):
                keywords.append((param.attr, self.open_array_argument(param, arg.value)))
                continue
            if (arg is None or arg.value is None) and param.kind == "VAR_INPUT":
                if is_aggregate(param.type):
                    # an input left out takes its initial value at each call: a fresh one,
                    # where the function's default is one object every call would share
                    # (and keep what the function wrote into it)
                    keywords.append((param.attr, self.initial(param.type, param.init)))
                continue
            if arg is None or arg.value is None or param.kind == "VAR_OUTPUT" or arg.is_output:
                continue
            if binds_reference(param, arg):
                keywords.append((param.attr, self.reference(arg.value)))
                continue
            if param.kind == "VAR_IN_OUT" and isinstance(param.type, FbType):
                # the instance itself, as a block's call passes it: a copy stored back would
                # leave whatever else refers to the instance (another block's in-out) on
                # the old one
                keywords.append((param.attr, self.expr(arg.value).node))
                continue
            keywords.append((param.attr, self.converted(param.type, arg.value)))
        result = pou.return_type or BOOL
        tupled = returns_tuple(pou)
        positional = () if first is None else (first,)
        node: Expr = Call(callee, positional, "" if tupled else _t(result), tuple(keywords))
        enable = self._function_enable(call, pou)
        if enable is not None:  # EN FALSE: the function does not run and gives its default
            default = self.initial(result, None)
            if tupled:
                nothing = [Const(None, "")] * len(tuple_members(pou))
                default = Sequence((default, *nothing), "", as_tuple=True)
            node = Choice(_enabled(enable), node, default, "" if tupled else _t(result))
        if not tupled:
            return _Value(node, result)
        returned = Var(self.temp(), "local", "")
        self.pre.append(Assign(returned, node, self.st_line))
        slots = {key(member.name): index for index, member in enumerate(tuple_members(pou), 1)}
        # outputs are stored in the order the call names them (as CODESYS does)
        for arg, connected in pairs:
            if connected is None or arg.value is None or key(connected.name) not in slots:
                continue
            if isinstance(connected.type, OpenArrayType):  # its items were changed in place
                continue
            if not _is_lvalue(arg.value):
                continue
            slot = _int(slots[key(connected.name)])
            output = _Value(Index(returned, slot, _t(connected.type)), connected.type)
            store = self.store(arg.value, convert_value(output, _type(self.scope, arg.value)))
            self.pre.append(
                store if enable is None else If(_enabled(enable), (store,), (), self.st_line)
            )
        return _Value(Index(returned, _int(0), _t(result)), result)

    def _enable(self, call: ast.Call, callee: PouSymbols | None) -> str | None:
        """EN of a call (`callee` None: of a standard function), evaluated once into a
        temporary; None when the call always runs."""
        enable_expr = enable_argument(call, callee)
        if enable_expr is None:
            return None
        enable = self.temp()
        self.pre.append(Assign(_enabled(enable), self.exact_node(enable_expr), self.st_line))
        self.enables[id(call)] = enable
        return enable

    def _function_enable(self, call: ast.Call, callee: PouSymbols | None) -> str | None:
        """`_enable`, and the ENO outputs stored from it right away: a function that runs
        always succeeds."""
        enable = self._enable(call, callee)
        for target in _eno_targets(call, callee):
            ran = _enabled(enable) if enable is not None else Const(True, "BOOL")
            self.pre.append(self._eno_store(target, ran))
        return enable

    def _eno_store(self, target: ast.Argument, value: Expr) -> Stmt:
        """`ENO => ok` (`NOT ENO => failed`) with ENO's value in `value`."""
        assert target.value is not None
        return self.store(target.value, Unary("not", value, "BOOL") if target.negated else value)

    def converted(self, target: Type, value_expr: ast.Expr) -> Expr:
        """`value_expr` as stored into a variable of type `target`."""
        self.scope.expect(value_expr, target)
        if isinstance(target, InterfaceType) and isinstance(_type(self.scope, value_expr), FbType):
            return self.reference(value_expr)  # an interface refers to the instance
        integer = integer_like(target)
        if integer is not None and _type(self.scope, value_expr) == ANY_INT:
            constant = self.scope.constant_int(value_expr)
            if constant is not None:
                return Const(wrap_constant(constant, integer), _t(target))
        self.modulus_bits = integer.bits if integer is not None else None
        try:
            raw = self.expr(value_expr)  # generated once: it may hoist calls
        finally:
            self.modulus_bits = None
        if is_aggregate(target):
            return intrinsic("_copy", target, raw.node) if _is_lvalue(value_expr) else raw.node
        short_literal = isinstance(value_expr, ast.StringLiteral) and not _longer_than(
            value_expr.value, target
        )
        return convert_value(raw, target, already_fits=short_literal)

    def initial(self, var_type: Type, init: ast.Initializer | None) -> Expr:
        """The initial value of a variable."""
        if isinstance(init, ast.ArrayInit):
            assert isinstance(var_type, ArrayType)
            return self._array_initial(var_type, init)
        if isinstance(init, ast.StructInit):
            members = tuple(
                (
                    self._member_attr(var_type, name),
                    self.initial(self._member_type(var_type, name), value),
                )
                for name, value in init.members
            )
            whole = self.initial(var_type, None)
            return intrinsic("_init", var_type, whole, Members(members))
        if init is not None:
            return self.converted(var_type, init)
        name = _t(var_type)
        match var_type:
            case FbType(name=block):
                return Call(class_name(block), (), name)
            case StructType(name=struct):
                return Call(struct_class(struct), (), name)
            case EnumType():
                info = self.scope.resolved.enums[key(var_type.name)]
                first = next(iter(info.values.values()), ("", 0))
                return Const(first[1], name)
            case ArrayType(element=element):
                return Repeated(
                    self.initial(element, None), var_type.size, is_aggregate(element), name
                )
            case ElementaryType(category=category):
                return Const(_ZERO.get(category, 0), name)
            case VariadicType():
                return Sequence((), name, as_tuple=True)
            case OpenArrayType():  # bound to an array at each call
                return Const(None, name)
            case RefType() | InterfaceType():
                return Const(None, name)  # NULL
        raise AssertionError(f"no initial value for {var_type!r}")

    def _array_initial(self, array: ArrayType, init: ast.ArrayInit) -> Expr:
        element = array.element
        items: list[Expr] = []
        for repeat, value in init.items:
            times = repeat.value if isinstance(repeat, ast.IntLiteral) else 1
            if isinstance(value, ast.ArrayInit) and not isinstance(element, ArrayType):
                group = [self.initial(element, v) for _, v in value.items]
                items.extend(group * times)
            else:
                items.extend([self.initial(element, value)] * times)
        missing = array.size - len(items)
        unique = {id(item): item for item in items}
        sizes = {number: len(python_text(item)) + 2 for number, item in unique.items()}
        self.make_room(sum(sizes[id(item)] for item in items))  # `n(...)` is written n times
        name = _t(array)
        body = Sequence(tuple(items), name)
        if missing > 0:
            if is_aggregate(element):
                filler: Expr = Slice(self.initial(array, None), len(items), None, name)
            else:
                filler = Repeated(self.initial(element, None), missing, False, name)
            return Binary("+", body, filler, name)
        return body

    def _member_type(self, owner: Type, name: str) -> Type:
        return self._member(owner, name).type

    def _member_attr(self, owner: Type, name: str) -> str:
        return self._member(owner, name).attr

    def _member(self, owner: Type, name: str) -> Variable:
        if isinstance(owner, StructType):
            return self.scope.struct(owner).by_key[key(name)]
        assert isinstance(owner, FbType)
        return self.scope.fb_symbols(owner).by_key[key(name)]

    # ---- statements
    def add(self, *statements: Stmt) -> None:
        """Statements at the end of the block being generated, after those hoisted out of
        their expressions."""
        self.body.extend(self.pre)
        self.pre.clear()
        self.body.extend(statements)

    def take_hoisted(self) -> list[Stmt]:
        """The statements hoisted so far, to place before a block's header rather than
        inside the block."""
        hoisted, self.pre = self.pre, []
        return hoisted

    def refuse_deeper_than_allowed(self, depth: int) -> None:
        """Code this deep is more than a resource loads (limits.py)."""
        if depth > MAX_INDENT:
            message = f"statements nested {depth} blocks deep in the generated code"
            raise GenerationError([Diagnostic.at(self.at, Code.STATEMENT_DEPTH, message)])

    def nested(self, fill: Callable[[], object], deeper: bool = True) -> tuple[Stmt, ...]:
        """The statements `fill` generates, as a block one level deeper (`deeper` False:
        to be spliced into the block being generated)."""
        assert not self.pre, "hoisted statements belong before the block's header"
        step = 1 if deeper else 0
        self.refuse_deeper_than_allowed(self.depth + step)
        outer, self.body = self.body, []
        self.depth += step
        try:
            fill()
            self.add()  # what the last expression hoisted
        finally:
            inner, self.body = self.body, outer
            self.depth -= step
        return tuple(inner)

    def block(self, statements: tuple[ast.Statement, ...], deeper: bool = True) -> tuple[Stmt, ...]:
        """The code of ST statements as a block (`pass` for none); `deeper` False: to be
        spliced into the block being generated (a loop's body after its tick)."""

        def fill() -> None:
            for statement in statements:
                self.statement(statement)

        return self.nested(fill, deeper) or (Pass(self.st_line),)

    def loop(
        self, test: Expr, fill: Callable[[], object], after_tick: tuple[Stmt, ...] = ()
    ) -> None:
        """A loop. Each pass starts with a tick where a program with a time slice may be
        suspended until the next CPU cycle (see runtime/slicing.py). `_tick` is None
        while no slice is metered: read once before the loop, a pass then costs a test of
        a local instead of a call (the resource watchdog needs no tick)."""
        tick = Var(self.temp(), "local", "")
        self.add(Assign(tick, Named("_tick"), self.st_line))

        def body() -> None:
            ticked = (Evaluate(Call(tick, (), ""), self.st_line), *after_tick)
            self.add(If(Binary("is not", tick, _NULL, "BOOL"), ticked, (), self.st_line))
            fill()

        self.add(While(test, self.nested(body), self.st_line))

    def tested_loop(self, condition: Expr, fill: Callable[[], object]) -> None:
        """A loop testing `condition` before every pass. Statements hoisted out of the
        condition (a call with outputs) belong inside the loop, before the test, so that
        they run for every test, not once before the loop."""
        if not self.pre:
            self.loop(condition, fill)
            return
        hoisted = self.take_hoisted()

        def body() -> None:
            line = self.st_line
            self.add(*hoisted, If(Unary("not", condition, "BOOL"), (Break(line),), (), line))
            fill()

        self.loop(Const(True, "BOOL"), body)

    def statement(self, statement: ast.Statement) -> None:
        outer, self.st_line, self.at = (self.st_line, self.at), statement.pos.line, statement.pos
        self._statement(statement)
        self.st_line, self.at = outer

    def _statement(self, statement: ast.Statement) -> None:
        line = self.st_line
        match statement:
            case ast.Assign(target=target, value=value, bind=bind, attempt=attempt):
                self.assign(target, value, bind, attempt)
            case ast.CallStatement(call=call):
                self.call_statement(call)
            case ast.ExprStatement(expr=expr):  # for its calls; the value is dropped
                self.add(Evaluate(self.exact_node(expr), line))
            case ast.If(branches=branches, orelse=orelse):
                self.add(*self.if_statement(branches, orelse))
            case ast.Case():
                self.case(statement)
            case ast.While(condition=condition, body=body):
                self.tested_loop(
                    self.exact_node(condition), lambda: self.add(*self.block(body, deeper=False))
                )
            case ast.Repeat(body=body, until=until):
                self.repeat(body, until)
            case ast.For():
                self.for_loop(statement)
            case ast.Exit():
                self.add(Break(line))
            case ast.Continue():
                self.add(Continue(line))
            case ast.Return():
                self.add(self.return_statement())

    def return_statement(self) -> Return:
        pou = self.scope.pou
        if pou.kind not in ("FUNCTION", "METHOD"):
            return Return(None, self.st_line)
        result = pou.by_key.get(key(pou.name))
        result_node: Expr = _NULL
        if result is not None and result.kind == "RETURN":
            result_node = Var(result.attr, "local", _t(result.type))
        if returns_tuple(pou):
            members = [Var(v.attr, "local", _t(v.type)) for v in tuple_members(pou)]
            return Return(Sequence((result_node, *members), "", as_tuple=True), self.st_line)
        return Return(result_node, self.st_line)

    def assign(self, target: ast.Expr, value: ast.Initializer, bind: bool, attempt: bool) -> None:
        if attempt:
            assert isinstance(value, ast.Expr)
            self.add(self.store(target, self.attempt(_type(self.scope, target), value)))
            return
        if bind:  # `r REF= x`: the REFERENCE TO itself now holds REF(x) (`REF= 0`: NULL)
            held = self.held_reference(target)
            assert held is not None and isinstance(value, ast.Call | ast.NullLiteral)
            self.add(Assign(held, self.expr(value).node, self.st_line))
            return
        target_type = _type(self.scope, target)
        if isinstance(value, ast.ArrayInit | ast.StructInit):
            node = self.initial(target_type, value)
        else:
            node = self.converted(target_type, value)
        enable = self.enables.get(id(value))
        stored = self.store(target, node)
        if enable is not None:  # `x := F(EN := FALSE, ...)` leaves x as it was (as Beremiz)
            self.add(If(_enabled(enable), (stored,), (), self.st_line))
            return
        self.add(stored)

    def attempt(self, target: Type, value: ast.Expr) -> Expr:
        """`t ?= x`: a reference to the instance x is or refers to where that instance is
        a `target` (its block, a base of it, an interface it implements), else NULL. The
        test reads the instance's class: its name, and `KIND__` (what it conforms to) of
        a block that extends or implements anything."""
        wanted = target.target if isinstance(target, RefType) else target
        assert isinstance(wanted, FbType | InterfaceType)
        source = _type(self.scope, value)
        reference = self.reference(value) if isinstance(source, FbType) else self.expr(value).node
        held = self.temp()
        found = Var(held, "local", _t(target))
        # generated code has no type() nor getattr(): the class, and what it conforms to
        kind = Member(intrinsic("_deref", "", found), "__class__", "")
        named = Binary("==", Member(kind, "__name__", ""), _text(class_name(wanted.name)), "BOOL")
        nothing = Sequence((), "", as_tuple=True)
        kinds = Member(Member(kind, "__dict__", ""), "get", "")
        conforms = Call(kinds, (_text("KIND__"), nothing), "")
        fits = Logic("or", (named, Binary("in", _text(key(wanted.name)), conforms, "BOOL")))
        bound = Binary("is not", Assigned(held, reference, _t(target)), _NULL, "BOOL")
        return Choice(Logic("and", (bound, fits)), found, _NULL, _t(target))

    def store(self, target: ast.Expr, value: Expr) -> Stmt:
        """The statement that stores `value` (already converted) into `target`."""
        target_type = _type(self.scope, target)
        length = target_type.max_length if isinstance(target_type, ElementaryType) else 0
        if length and not (isinstance(value, Slice) and value.stop == length):
            value = Slice(value, None, length, _t(target_type))  # only strings have a length
        if isinstance(target, ast.BitRef):
            base = self.expr(target.base)
            shift, width = target.bit * target.width, target.width
            updated = intrinsic("_setbits", base.type, base.node, _int(shift), _int(width), value)
            integer = integer_like(base.type)
            return self._assignment(target.base, wrapped(updated, integer) if integer else updated)
        return self._assignment(target, value)

    def _assignment(self, target: ast.Expr, value: Expr) -> Stmt:
        """`target := value`; through a reference (`r^ := v`, a REFERENCE TO r) the place it
        refers to."""
        line = self.st_line
        if isinstance(target, ast.Deref):
            return Evaluate(intrinsic("_deref_set", "", self.expr(target.base).node, value), line)
        through_setter = self._property_set(target, value)
        if through_setter is not None:
            return through_setter
        held = self.held_reference(target)
        if held is not None:
            return Evaluate(intrinsic("_deref_set", "", held, value), line)
        node = self.expr(target).node
        if isinstance(_type(self.scope, target), ArrayType | StructType) and not (
            isinstance(node, Var) and node.where == "local"
        ):
            # an array or structure of an instance, the globals or an element, written
            # whole: its values into the object there, which a block's in-out may hold (the
            # caller's very variable); a Python local of a FUNCTION or method is a value
            # of its own, which the assignment may replace
            if isinstance(value, Call) and value.callee == "_copy":
                value = value.args[0]  # `_fill` copies the values
            return Evaluate(intrinsic("_fill", "", node, value), line)
        return Assign(node, value, line)

    def held_reference(self, expr: ast.Expr) -> Expr | None:
        """The slot of a REFERENCE TO variable `expr` names (None: it names no such
        variable), the reference itself rather than what it refers to."""
        if isinstance(expr, ast.NameRef):
            binding = self.scope.lookup(expr.name)
            if isinstance(binding, Variable) and is_implicit_reference(binding.type):
                return self.var_node(binding)
        if isinstance(expr, ast.MemberRef):
            member = self.scope.member(expr)
            if member is not None and is_implicit_reference(member.type):
                return Member(self.expr(expr.base).node, member.attr, _t(member.type))
        return None

    def if_statement(
        self, branches: tuple[tuple[ast.Expr, tuple[ast.Statement, ...]], ...],
        orelse: tuple[ast.Statement, ...],
    ) -> list[Stmt]:  # fmt: skip
        """IF ... ELSIF ... ELSE, after what its first condition hoists."""
        test = self.exact_node(branches[0][0])
        hoisted = self.take_hoisted()
        return [*hoisted, self._branches(test, branches, orelse)]

    def _branches(
        self, test: Expr, branches: tuple[tuple[ast.Expr, tuple[ast.Statement, ...]], ...],
        orelse: tuple[ast.Statement, ...],
    ) -> If:  # fmt: skip
        """The IF of the first branch (its condition `test`), the others as its ELIFs, up
        to one whose condition hoists statements (which must run only when that condition
        is reached): that one and those after it in an ELSE of its own, one level deeper."""
        line = self.st_line
        then = self.block(branches[0][1])
        elifs: list[Elif] = []
        for index in range(1, len(branches)):
            following = self.exact_node(branches[index][0])
            hoisted = self.take_hoisted()
            if hoisted:
                self.refuse_deeper_than_allowed(self.depth + 1)
                self.depth += 1
                try:
                    rest = self._branches(following, branches[index:], orelse)
                finally:
                    self.depth -= 1
                return If(test, then, (*hoisted, rest), line, tuple(elifs))
            elifs.append(Elif(following, self.block(branches[index][1]), line))
        return If(test, then, self.block(orelse) if orelse else (), line, tuple(elifs))

    def case(self, case: ast.Case) -> None:
        line = self.st_line
        selector = Var(self.temp(), "local", "")
        selector_value = self.exact(case.selector)
        for labels, _ in case.branches:
            for label in labels:
                for bound in (
                    (label.low, label.high) if isinstance(label, ast.CaseRange) else (label,)
                ):
                    self.scope.expect(bound, selector_value.type)
        self.add(Assign(selector, selector_value.node, line))
        chosen: list[tuple[Expr, tuple[Stmt, ...]]] = []
        for labels, body in case.branches:
            tests: list[Expr] = []
            for label in labels:
                if isinstance(label, ast.CaseRange):
                    low, high = self.exact_node(label.low), self.exact_node(label.high)
                    tests.append(Chain("<=", (low, selector, high)))
                else:
                    tests.append(Binary("==", selector, self.exact_node(label), "BOOL"))
            test = tests[0] if len(tests) == 1 else Logic("or", tuple(tests))
            chosen.append((test, self.block(body)))
        otherwise = self.block(case.orelse) if case.orelse else ()
        if not chosen:
            if otherwise:
                self.add(If(Const(True, "BOOL"), otherwise, (), line))
            return
        (test, chosen_body), others = chosen[0], chosen[1:]
        elifs = tuple(Elif(other, body, line) for other, body in others)
        self.add(If(test, chosen_body, otherwise, line, elifs))

    def repeat(self, body: tuple[ast.Statement, ...], until: ast.Expr) -> None:
        line = self.st_line
        first = Var(self.temp(), "local", "BOOL")
        until_node = self.exact_node(until)  # generated before the body, used after it
        hoisted = self.take_hoisted()
        if hoisted:  # the condition needs statements: test at the end, no CONTINUE support

            def at_the_end() -> None:
                self.add(*self.block(body, deeper=False))
                self.add(*hoisted, If(until_node, (Break(line),), (), line))

            self.loop(Const(True, "BOOL"), at_the_end)
            return
        self.add(Assign(first, Const(True, "BOOL"), line))
        again = Logic("or", (first, Unary("not", until_node, "BOOL")))

        def passes() -> None:
            self.add(Assign(first, Const(False, "BOOL"), line))
            self.add(*self.block(body, deeper=False))

        self.loop(again, passes)

    def for_loop(self, loop: ast.For) -> None:
        """IEC FOR: the end and step are evaluated for every test of the loop condition; a
        counter that would wrap past the end of its type ends the loop instead of running
        forever."""
        line = self.st_line
        counter = self.scope.variable(loop.variable)
        assert counter is not None and isinstance(counter.type, ElementaryType)
        ref = self.var_node(counter)
        self.add(Assign(ref, self.converted(counter.type, loop.start), line))
        step_constant = self.scope.constant_int(loop.step) if loop.step is not None else 1
        stop_constant = self.scope.constant_int(loop.stop)
        if (
            step_constant is not None
            and stop_constant is not None
            and not _has_continue(loop.body)
            and self._counter_private(counter, loop.body)
        ):
            if _plain_body(loop.body):
                self.range_loop(loop, counter, ref, step_constant, stop_constant)
                return
            stop = self.exact_node(loop.stop)  # a constant: the same at every test
            self.counted_loop(loop, counter, ref, step_constant, stop)
            return
        step: Expr = Const(step_constant, _t(counter.type))
        if step_constant is None:  # evaluated for every test of the loop condition
            step = Var(self.temp(), "local", _t(counter.type))
        following = Var(self.temp(), "local", "LINT")
        increment = (
            Assign(following, Binary("+", ref, step, "LINT"), line),
            Assign(ref, wrapped(following, counter.type), line),
            If(Binary("!=", ref, following, "BOOL"), (Break(line),), (), line),
        )
        if step_constant is not None and not _has_continue(loop.body):
            stop = self.exact_node(loop.stop)
            test = Binary("<=" if step_constant >= 0 else ">=", ref, stop, "BOOL")
            self.tested_loop(
                test, lambda: self.add(*self.block(loop.body, deeper=False), *increment)
            )
            return
        started = Var(self.temp(), "local", "BOOL")
        self.add(Assign(started, Const(False, "BOOL"), line))

        def passes() -> None:
            self.add(If(started, increment, (), line))
            self.add(Assign(started, Const(True, "BOOL"), line))
            stop = self.exact_node(loop.stop)
            if step_constant is None:
                assert loop.step is not None
                self.add(Assign(step, self.exact_node(loop.step), line))
                rising = Binary(">=", step, Const(0, "DINT"), "BOOL")
                up, down = (Binary(op, ref, stop, "BOOL") for op in ("<=", ">="))
                test: Expr = Choice(rising, up, down, "BOOL")
            else:
                test = Binary("<=" if step_constant >= 0 else ">=", ref, stop, "BOOL")
            self.add(If(Unary("not", test, "BOOL"), (Break(line),), (), line))
            self.add(*self.block(loop.body, deeper=False))

        self.loop(Const(True, "BOOL"), passes)

    def counted_loop(
        self, loop: ast.For, counter: Variable, ref: Var, step: int, stop: Expr
    ) -> None:
        """A FOR whose end and step are constants and whose counter nothing but the loop
        writes: the counter lives in a Python local (stored back after every step), the
        end needs no evaluation, and a step past the end of the type is a comparison. A
        write from outside while a sliced program was suspended at the tick (an online
        write, a force) is taken over, as the plain loop would."""
        counter_type = counter.type
        assert isinstance(counter_type, ElementaryType)
        line = self.st_line
        local = Var(self.temp(), "local", "LINT")
        self.add(Assign(local, ref, line))
        key_ = (counter.kind, counter.attr)

        def passes() -> None:
            self.counters[key_] = local.name
            try:
                self.add(*self.block(loop.body, deeper=False))
            finally:
                del self.counters[key_]
            self.add(Assign(local, Const(step, "LINT"), line, augmented="+"))
            past = Binary(">", local, Const(counter_type.max, "LINT"), "BOOL")
            if step < 0:
                past = Binary("<", local, Const(counter_type.min, "LINT"), "BOOL")
            wrapped_back = (Assign(ref, wrapped(local, counter_type), line), Break(line))
            self.add(If(past, wrapped_back, (), line), Assign(ref, local, line))

        test = Binary("<=" if step >= 0 else ">=", local, stop, "BOOL")
        self.loop(test, passes, (Assign(local, ref, line),))

    def range_loop(self, loop: ast.For, counter: Variable, ref: Var, step: int, stop: int) -> None:
        """A counted loop whose body holds no loop and no RETURN: while no time slice is
        metered (no tick to call, so nothing can write the counter between passes) it is a
        Python `for` over a range, the counter stored at the start of each pass (what a
        fault leaves); with a constant start, an array indexed by the counter within its
        bounds is not checked. Otherwise the counted loop (the body's code twice, not its
        loops: nesting would multiply it)."""
        counter_type = counter.type
        assert isinstance(counter_type, ElementaryType)
        line = self.st_line
        local = Var(self.temp(), "local", "LINT")
        numbers = Var(self.temp(), "local", "")
        start = self.scope.constant_int(loop.start)
        key_ = (counter.kind, counter.attr)
        end = Const(stop + (1 if step >= 0 else -1), "LINT")

        def unsliced() -> None:
            self.add(Assign(numbers, intrinsic("range", "", ref, end, Const(step, "LINT")), line))

            def passes() -> None:
                self.add(Assign(ref, local, line))  # what a fault in the pass leaves
                self.counters[key_] = local.name
                if start is not None:
                    self.counter_ranges[local.name] = (min(start, stop), max(start, stop))
                try:
                    self.add(*self.block(loop.body, deeper=False))
                finally:
                    del self.counters[key_]
                    self.counter_ranges.pop(local.name, None)

            body = self.nested(passes)
            # not left by EXIT: one step past the last pass
            past = Binary("*", intrinsic("len", "", numbers), Const(step, "LINT"), "LINT")
            after = Binary("+", Member(numbers, "start", "LINT"), past, "LINT")
            self.add(ForEach(local.name, numbers, body, (Assign(local, after, line),), line))
            self.add(Assign(ref, wrapped(local, counter_type), line))

        fast = self.nested(unsliced)
        metered = self.nested(
            lambda: self.counted_loop(loop, counter, ref, step, Const(stop, "LINT"))
        )
        self.add(If(Binary("is", Named("_tick"), _NULL, "BOOL"), fast, metered, line))

    def _counter_private(self, counter: Variable, body: tuple[ast.Statement, ...]) -> bool:
        """Nothing but the loop itself writes the counter while the body runs: the body
        assigns it nowhere, passes it to no call, and when it is a slot of the instance
        (which another POU may reach, `Prog.var`), calls no POU at all."""
        if counter.kind in ("VAR_GLOBAL", "VAR_EXTERNAL", "SYSTEM"):
            return False
        slot = not is_python_local(counter, self.local)
        name = key(counter.name)
        for node in _nodes(body):
            match node:
                case ast.Assign(target=target) if key_of_root(target) == name:
                    return False
                case ast.For(variable=variable) if key(variable) == name:
                    return False
                case ast.Call(name=called, args=args, receiver=receiver, instance=instance):
                    if any(
                        isinstance(a.value, ast.NameRef) and key(a.value.name) == name for a in args
                    ):
                        return False
                    if slot and (
                        receiver is not None
                        or instance is not None
                        or self.scope.action_call(node) is not None
                        or self.scope.method_call(node) is not None
                        or key(called) in self.scope.resolved.pous
                        or self.scope.lookup(called) is not None
                    ):
                        return False
        return True

    def call_statement(self, call: ast.Call) -> None:
        line = self.st_line
        method = self.scope.method_call(call)
        if method is not None:
            self.add(Evaluate(self._method_call(method, call).node, line))
            return
        test = self.scope.test_call(call)
        if test is not None:
            self.add(*test_call_statements(self, call, test, line))
            return
        base = self.scope.super_body(call)
        if base is not None:  # SUPER^(): the base's body on this instance
            body = Member(Named(class_name(base.base.name)), "__call__", "")
            self.add(Evaluate(Call(body, (This(""),), ""), line))
            return
        action = self.scope.action_call(call)
        if action is not None:
            method_node = Member(self._action_instance(action), _action_method(call.name), "")
            self.add(Evaluate(Call(method_node, (), ""), line))
            return
        callee = self.scope.called_instance(call)
        instance: Expr | None = None
        if callee is None:  # `fbs[i](...)`, `s.fb(...)`: an instance given by an expression
            called = self.scope.expression_instance(call)
            if called is not None:
                callee, instance = self.scope.fb_symbols(called[1]), self.expr(called[0]).node
        if callee is None:
            self.add(Evaluate(self.exact_node(call), line))
            return
        if instance is not None:
            pass
        elif call.name == "^":  # `r^(...)`: the instance r refers to
            assert call.receiver is not None
            instance = self.expr(call.receiver).node
        else:  # a program, an instance, what a REFERENCE TO refers to
            instance = self.expr(ast.NameRef(call.name, call.pos)).node
        enable = self._enable(call, callee)
        eno = block_eno(callee)
        eno_targets = _eno_targets(call, callee)
        if eno is None:  # a program: ENO TRUE when it runs
            ran = _enabled(enable) if enable is not None else Const(True, "BOOL")
            for target in eno_targets:
                self.pre.append(self._eno_store(target, ran))
        block = Var(self.temp(), "local", _t(FbType(callee.name)))
        self.add(Assign(block, instance, line))

        def run() -> None:
            self._block_call(call, callee, block, eno is not None, eno_targets)

        if enable is None:
            run()
            return
        ran_body = self.nested(run)
        skipped: tuple[Stmt, ...] = ()
        if eno is not None:  # EN FALSE: the body does not run, ENO is FALSE
            not_run = Const(False, "BOOL")
            skipped = (
                Assign(Member(block, "ENO", "BOOL"), not_run, line),
                *(self._eno_store(target, not_run) for target in eno_targets),
            )
        self.add(If(_enabled(enable), ran_body, skipped, line))

    def _block_call(
        self, call: ast.Call, callee: PouSymbols, block: Var, eno: bool,
        eno_targets: list[ast.Argument],
    ) -> None:  # fmt: skip
        """A block's call on `block`: its inputs set, its body run, its outputs stored."""
        line = self.st_line
        outputs: list[tuple[ast.Argument, Variable]] = []
        for arg, param in self.scope.connect_arguments(callee, call):
            if arg.value is None or param is None or is_implicit(param):
                continue
            if arg.is_output or param.kind == "VAR_OUTPUT":
                outputs.append((arg, param))
                continue
            slot = Member(block, param.attr, _t(param.type))
            if isinstance(param.type, OpenArrayType):
                self.add(Assign(slot, self.open_array_argument(param, arg.value), line))
                continue
            if binds_reference(param, arg):  # the input now refers to the variable passed
                self.add(Assign(slot, self.reference(arg.value), line))
                continue
            if param.kind == "VAR_IN_OUT":
                self.add(Assign(slot, self.expr(arg.value).node, line))
                if not is_aggregate(param.type):
                    outputs.append((arg, param))
                continue
            self.add(Assign(slot, self.converted(param.type, arg.value), line))
        # the method itself, not the instance called: CPython 3.11 calls an instance
        # through its type's __call__ slot at twice the cost (51 ns against 27)
        self.add(Evaluate(Call(Member(block, "__call__", ""), (), ""), line))
        for param in callee.parameters:
            # bound for the call only (each call binds one): no caller's array is kept in
            # the instance, for a saved context or a reload to carry
            if isinstance(param.type, OpenArrayType):
                self.add(Assign(Member(block, param.attr, ""), Const(None, ""), line))
        for arg, param in outputs:
            assert arg.value is not None
            output: Expr = Member(block, param.attr, _t(param.type))
            if arg.negated:
                output = Unary("not", output, "BOOL")
            target_type = _type(self.scope, arg.value)
            stored = convert_value(_Value(output, param.type), target_type)
            self.add(self.store(arg.value, stored))
        if eno:
            for target in eno_targets:  # what the block's body left in ENO
                self.add(self._eno_store(target, Member(block, "ENO", "BOOL")))

    def _action_instance(self, action: ActionCall) -> Expr:
        """The object whose action is called: this POU's own, a program's, an instance's."""
        match action.instance:
            case None:
                return This("")
            case ProgramRef(pou=pou):
                return Var(class_name(pou.name), "programs", pou.name)
            case receiver:
                return self.expr(receiver).node


def _eno_targets(call: ast.Call, callee: PouSymbols | None) -> list[ast.Argument]:
    """The arguments that store a call's implicit ENO (`ENO => ok`): none when the POU
    declares a variable named ENO, which is then an output like any other."""
    if callee is not None and "ENO" in callee.by_key:
        return []
    return [
        arg
        for arg in call.args
        if arg.name is not None and key(arg.name) == "ENO" and arg.value is not None
    ]


def convert_value(raw: _Value, target: Type, already_fits: bool = False) -> Expr:
    """An elementary value as stored in a variable of `target`: wrapped to its width,
    converted between types, strings cut to their length."""
    target_int = integer_like(target)
    raw_int = integer_like(raw.type)
    if raw.unwrapped and target_int and raw_int and target_int.bits <= raw_int.bits:
        # wrapping to the narrower target alone gives the same bits as wrapping twice
        return _wrapped(raw, target_int)
    value = _exact(raw)
    if not isinstance(target, ElementaryType | EnumType):
        return value.node
    target_elem = target.base if isinstance(target, EnumType) else target
    source = value.type.base if isinstance(value.type, EnumType) else value.type
    node = value.node
    if isinstance(source, ElementaryType) and source != target_elem:
        if source == ANY_INT and target_elem.is_integer:
            # an expression of literals (`-79 MOD 100`) may lie outside the target's range
            node = literal_in(node, target_elem)
        elif not (source == ANY_REAL and target_elem == ANY_REAL):
            node = converted(node, source, target_elem)
    length = target_elem.max_length
    if length and not already_fits:
        node = Slice(node, None, length, _t(target_elem))
    return node


def _longer_than(text: str, target: Type) -> bool:
    length = target.max_length if isinstance(target, ElementaryType) else 0
    return bool(length) and len(text) > length


def _literal_number(expr: ast.Expr) -> float | None:
    """The value of a number literal, also when negated (`-0.1`)."""
    if isinstance(expr, ast.RealLiteral | ast.IntLiteral):
        return float(expr.value)
    if isinstance(expr, ast.Unary) and expr.op in ("-", "+"):
        inner = _literal_number(expr.operand)
        if inner is not None:
            return -inner if expr.op == "-" else inner
    return None


def _comparison_type(scope: Scope, expr: ast.Binary) -> Type:
    """The type both sides of a comparison are converted to."""
    left = integer_like(_type(scope, expr.left)) or _type(scope, expr.left)
    right = integer_like(_type(scope, expr.right)) or _type(scope, expr.right)
    if isinstance(left, ElementaryType) and isinstance(right, ElementaryType):
        joined = common_numeric(left, right)
        if joined is not None and joined.category == "real":
            return joined
    return left


def _exact(value: _Value) -> _Value:
    if value.unwrapped and isinstance(value.type, ElementaryType):
        return _Value(_wrapped(value, value.type), value.type)
    return value


def _wrapped(value: _Value, t: ElementaryType) -> Expr:
    if value.constant_tail is not None:
        head, n = value.constant_tail
        return wrapped(head, t, n)
    return wrapped(value.node, t)


def _implicit(node: Expr, declared: Type) -> _Value:
    """A variable's value: a REFERENCE TO reads as what it refers to (NULL: a fault)."""
    if is_implicit_reference(declared):
        target = value_type(declared)
        return _Value(intrinsic("_deref", target, node), target)
    return _Value(node, declared)


_t = artifact_type_text
_ZERO: dict[str, bool | float | str] = {"bool": False, "real": 0.0, "string": ""}
_NULL = Const(None, NULL_TYPE.name)
# the object that holds a variable of each place, for a reference to name
_ROOTS: dict[str, Expr] = {
    "instance": This(""), "globals": Named("_G"), "system": Named("_SYS"), "programs": Named("_P"),
}  # fmt: skip


def _int(value: int) -> Const:
    return Const(value, "DINT")


def _text(value: str) -> Const:
    return Const(value, "STRING")


def _constant(value: bool | int | float | str | None, t: Type) -> _Value:
    return _Value(Const(value, _t(t)), t)


def _is_int_constant(node: Expr) -> bool:
    return isinstance(node, Const) and type(node.value) is int


def _enabled(enable: str) -> Var:
    """The temporary that holds a call's EN."""
    return Var(enable, "local", "BOOL")


def _reference_call(
    root: Expr, steps: tuple[Expr, ...], label: Expr, whole: bool | None = None
) -> Call:
    """`_ref(root, steps, label[, whole])`: a reference to what `steps` reach from `root`."""
    arguments: list[Expr] = [root, Sequence(steps, "", as_tuple=True), label]
    if whole is not None:
        arguments.append(Const(whole, "BOOL"))
    return intrinsic("_ref", "", *arguments)


def _flat(offsets: list[Expr], dims: tuple[tuple[int, int], ...]) -> Expr:
    """The list offset of an element of an array of `dims` from its offset in each
    dimension (the last one varying fastest)."""
    total: Expr | None = None
    for number, offset in enumerate(offsets):
        stride = 1
        for low, high in dims[number + 1 :]:
            stride *= high - low + 1
        term = offset if stride == 1 else Binary("*", offset, _int(stride), "DINT")
        total = term if total is None else Binary("+", total, term, "DINT")
    assert total is not None
    return total


def _has_continue(body: tuple[ast.Statement, ...]) -> bool:
    """A CONTINUE that belongs to this loop (not to a nested one)."""
    for statement in body:
        match statement:
            case ast.Continue():
                return True
            case ast.If(branches=branches, orelse=orelse):
                if any(_has_continue(b) for _, b in branches) or _has_continue(orelse):
                    return True
            case ast.Case(branches=branches, orelse=orelse):
                if any(_has_continue(b) for _, b in branches) or _has_continue(orelse):
                    return True
    return False


def _plain_body(body: tuple[ast.Statement, ...]) -> bool:
    """No loop and no RETURN below: a body whose code may be generated twice, and that
    leaves its loop only at the end of a pass or by EXIT."""
    return not any(
        isinstance(node, ast.For | ast.While | ast.Repeat | ast.Return) for node in _nodes(body)
    )


def _nodes(value: object) -> Iterator[object]:
    """Every node below a statement list (statements, expressions, arguments)."""
    if isinstance(value, tuple | list):
        for item in value:
            yield from _nodes(item)
    elif is_dataclass(value) and not isinstance(value, Pos | type):
        yield value
        for item in fields(value):
            yield from _nodes(getattr(value, item.name))


def key_of_root(target: ast.Expr) -> str | None:
    """The key of the variable an assignment target belongs to (`a` of `a.b[1].3`)."""
    while isinstance(target, ast.MemberRef | ast.IndexRef | ast.BitRef):
        target = target.base
    return key(target.name) if isinstance(target, ast.NameRef) else None


def _is_lvalue(expr: ast.Expr) -> bool:
    return isinstance(expr, ast.NameRef | ast.MemberRef | ast.IndexRef | ast.BitRef)


def _type(scope: Scope, expr: ast.Expr) -> Type:
    result = scope.type_of(expr)
    assert result is not None, f"generate called on unchecked code at {expr.pos}"
    return result


@dataclass(frozen=True)
class GeneratedUnit:
    unit: Unit  # the typed form
    source: str  # its Python text
    st_lines: tuple[int, ...]  # per line of `source`: the ST line it comes from, 0 for none


def generate_pou(
    resolved: Resolved, pou: PouSymbols, max_size: int = MAX_UNIT_CODE
) -> GeneratedUnit:
    """The typed form of one POU, and its Python text of at most `max_size` characters."""
    scope = Scope(resolved, pou)
    emitter = _Emitter(scope, local=pou.kind == "FUNCTION", at=pou.pou.pos, max_size=max_size)
    if pou.kind == "FUNCTION":
        return _printed(emitter, _function(emitter, pou, function_name(pou.name)))
    return _printed(emitter, _class(emitter, pou))


def _printed(emitter: _Emitter, unit: Unit) -> GeneratedUnit:
    """`unit` with its text, refused line by line where the text outgrows the unit's limit."""
    lines: list[str] = []
    st_lines: list[int] = []
    for line, st_line in unit_lines(unit):
        emitter.make_room(len(line) + 1)
        emitter.size += len(line) + 1
        lines.append(line)
        st_lines.append(st_line)
    return GeneratedUnit(unit, "\n".join(lines) + "\n", tuple(st_lines))


def _class(emitter: _Emitter, pou: PouSymbols) -> Class:
    fields = instance_fields(pou)
    sfc = pou.pou.sfc
    chart = _Chart(sfc) if sfc is not None else None
    edges = [v for v in fields if v.edge is not None]
    slots: list[Slot] = []
    for variable in fields:
        initial = emitter.initial(variable.type, variable.init)
        if chart is not None and variable.kind == "STEP" and key(variable.name) in chart.initial:
            active = Members((("X", Const(True, "BOOL")),))
            initial = intrinsic("_init", variable.type, initial, active)
        slots.append(Slot(variable.attr, initial))
    slots += [Slot(_edge_memory(v), Const(False, "BOOL")) for v in edges]
    if chart is not None:
        slots += [Slot(slot, Call("_ActionControl", (), "")) for slot in chart.slots()]
    kinds = _kinds(emitter.scope.resolved, pou)
    steps = chart is not None and bool(chart.sfc.steps)

    def call_body() -> None:
        if block_eno(pou) is not None:  # a call that runs has ENO TRUE unless its body says not
            emitter.add(Assign(Member(This(""), "ENO", "BOOL"), Const(True, "BOOL"), 0))
        for variable in edges:  # the body sees TRUE only in the call that brings the edge
            now = Member(This(""), variable.attr, "BOOL")
            before = Member(This(""), _edge_memory(variable), "BOOL")
            if variable.edge == "R_EDGE":
                edge = Logic("and", (now, Unary("not", before, "BOOL")))
            else:
                edge = Logic("and", (Unary("not", now, "BOOL"), before))
            memories = Sequence((now, before), "", as_tuple=True)
            emitter.add(Assign(memories, Sequence((edge, now), "", as_tuple=True), 0))
        _add_temporaries(emitter, pou)
        if pou.pou.body or not steps:  # a chart alone needs no `pass` before it
            emitter.add(*emitter.block(pou.pou.body, deeper=False))
        if chart is not None and steps:  # actions without steps run only when called
            chart.add_cycle(emitter)

    functions: list[Function | Inherited] = [
        Function("__call__", (), emitter.body_of(2, call_body), method=True)
    ]
    for action in chart.sfc.actions if chart is not None else ():

        def action_body(action: ast.Action = action) -> None:
            _add_temporaries(emitter, pou)  # an action's call has temporaries of its own
            emitter.add(*emitter.block(action.body, deeper=False))

        body = emitter.body_of(2, action_body)
        functions.append(Function(_action_method(action.name), (), body, method=True))
    functions += _methods(emitter, pou)
    # what `?=` finds an instance conforms to; a plain block's instance: its name alone
    conforms = kinds if len(kinds) > 1 else ()
    return Class(class_name(pou.name), tuple(slots), conforms, tuple(functions))


def _kinds(resolved: Resolved, pou: PouSymbols) -> tuple[str, ...]:
    """The keys an instance of `pou` conforms to: its block, its bases, its interfaces."""
    found = [key(pou.name), *pou.interfaces]
    base = pou.base
    while base is not None:
        found.append(base)
        base = resolved.pous[base].base
    return tuple(sorted(set(found)))


def _add_temporaries(emitter: _Emitter, pou: PouSymbols) -> None:
    for variable in pou.variables:
        if variable.kind == "VAR_TEMP":
            temporary = Var(variable.attr, "local", _t(variable.type))
            emitter.add(Assign(temporary, emitter.initial(variable.type, variable.init), 0))


def _action_method(name: str) -> str:
    return f"_action_{_ident(name)}"


def action_control(name: str) -> str:
    """The slot of an action's control block in its POU's class."""
    return f"_ac_{_ident(name)}"


class _Chart:
    """Code for one sequential function chart (IEC 61131-3 textual SFC), run after the POU's
    ST body in every call:

    1. the time of each active step (T is 0 in the first cycle a step is active),
    2. every action's control block from the steps that name it (qualifiers N, R, S, P,
       P0, P1, L, D, SD, DS, SL), then the actions, in the order they are first named,
    3. the transitions: enabled (all source steps active) and TRUE fire together; of two
       that share a source step only the first (PRIORITY, then text order) fires; the
       steps they leave are deactivated, then the steps they reach activated, so the new
       steps act from the next cycle on.
    """

    def __init__(self, sfc: ast.Sfc) -> None:
        self.sfc = sfc
        self.initial = {key(step.name) for step in sfc.steps if step.initial}
        named = [(step, a) for step in sfc.steps for a in step.associations]
        # the actions as first named (spelled as there), and where each is named, by key
        self.action_order = list(dict.fromkeys(association.action for _, association in named))
        self.named_by: dict[str, list[tuple[ast.Step, ast.ActionAssociation]]] = {}
        for step, association in named:
            self.named_by.setdefault(key(association.action), []).append((step, association))

    def slots(self) -> list[str]:
        return [action_control(name) for name in self.action_order]

    def add_cycle(self, emitter: _Emitter) -> None:
        scope = emitter.scope
        outer = emitter.st_line
        now = Var("now", "local", "TIME")
        emitter.add(Assign(now, Var("now_ns", "system", "TIME"), outer))
        for step in self.sfc.steps:
            ref = emitter.var_node(_step_variable(scope, step.name))
            # the line of the STEP: a debugger's breakpoint there stops while it is active
            time = intrinsic("_step_time", "TIME", ref, now)
            timed = Assign(Member(ref, "T", "TIME"), time, step.pos.line)
            emitter.add(If(Member(ref, "X", "BOOL"), (timed,), (), outer))
        declared = {key(action.name) for action in self.sfc.actions}
        for action in self.action_order:
            inputs: dict[str, list[Expr]] = {}
            durations: dict[str, Expr] = {}
            for step, association in self.named_by[key(action)]:
                flag = Member(emitter.var_node(_step_variable(scope, step.name)), "X", "BOOL")
                inputs.setdefault(association.qualifier, []).append(flag)
                if association.duration is not None:
                    durations[association.qualifier] = emitter.exact_node(association.duration)
            arguments = [
                (qualifier, _any_of(flags)) for qualifier, flags in sorted(inputs.items())
            ] + [(f"T{qualifier}", node) for qualifier, node in sorted(durations.items())]
            control = Member(This(""), action_control(action), "")
            update = Call(Member(control, "update", ""), (now,), "", tuple(arguments))
            emitter.add(Evaluate(update, outer))
            if key(action) in declared:
                run = Evaluate(Call(Member(This(""), _action_method(action), ""), (), ""), outer)
                emitter.add(If(Member(control, "A", "BOOL"), (run,), (), outer))
            else:  # a Boolean variable as action: it follows the action's Q
                variable = scope.variable(action)
                assert variable is not None
                follows = Assign(emitter.var_node(variable), Member(control, "Q", "BOOL"), outer)
                emitter.add(follows)
        self._add_transitions(emitter)

    def _add_transitions(self, emitter: _Emitter) -> None:
        scope = emitter.scope
        outer = emitter.st_line
        ordered = sorted(
            enumerate(self.sfc.transitions),
            key=lambda item: (item[1].priority if item[1].priority is not None else 0, item[0]),
        )
        fired: list[tuple[Var, ast.Transition]] = []
        leaving: dict[str, list[int]] = {}  # step -> the transitions in `fired` from it
        for number, transition in ordered:
            flag = Var(emitter.temp(), "local", "BOOL")
            sources: list[Expr] = [
                Member(emitter.var_node(_step_variable(scope, name)), "X", "BOOL")
                for name in transition.sources
            ]
            steps = {key(name) for name in transition.sources}
            earlier = sorted({i for step in steps for i in leaving.get(step, [])})
            blockers: list[Expr] = [Unary("not", fired[i][0], "BOOL") for i in earlier]
            # the line of the TRANSITION: a breakpoint there stops as it is evaluated
            emitter.st_line = line = transition.pos.line
            condition = emitter.exact_node(transition.condition)
            # the condition's value is kept where a live chart reads it, evaluated only
            # while the transition is enabled, as before
            kept = emitter.var_node(_transition_value(scope, number))
            emitter.add(Assign(flag, _all_of([*sources, *blockers]), line))
            evaluated = (Assign(kept, condition, line), Assign(flag, kept, line))
            emitter.add(If(flag, evaluated, (), line))
            emitter.st_line = outer
            for step in steps:
                leaving.setdefault(step, []).append(len(fired))
            fired.append((flag, transition))
        for flag, transition in fired:
            for name in transition.sources:
                active = Member(emitter.var_node(_step_variable(scope, name)), "X", "BOOL")
                emitter.add(If(flag, (Assign(active, Const(False, "BOOL"), outer),), (), outer))
        for flag, transition in fired:
            for name in transition.targets:
                entered = intrinsic(
                    "_step_enter", "", emitter.var_node(_step_variable(scope, name))
                )
                emitter.add(If(flag, (Evaluate(entered, outer),), (), outer))


def _any_of(values: list[Expr]) -> Expr:
    return values[0] if len(values) == 1 else Logic("or", tuple(values))


def _all_of(values: list[Expr]) -> Expr:
    return values[0] if len(values) == 1 else Logic("and", tuple(values))


def _transition_value(scope: Scope, number: int) -> Variable:
    """The hidden BOOL that keeps the last value of the chart's transition `number`."""
    variable = scope.variable(transition_variable(number))
    assert variable is not None, number
    return variable


def _step_variable(scope: Scope, name: str) -> Variable:
    variable = scope.variable(name)
    assert variable is not None and variable.kind == "STEP", name
    return variable


def _function(emitter: _Emitter, pou: PouSymbols, name: str, depth: int = 0) -> Function:
    """A FUNCTION as a Python function `name`; a method (kind METHOD, `depth` 1) as the
    function `name` of its block's class (a property's GET and SET too), whose first
    parameter is the instance."""
    inputs = [
        v
        for v in pou.variables
        if v.kind in ("VAR_INPUT", "VAR_IN_OUT") or isinstance(v.type, OpenArrayType)
    ]  # a variable-length output is bound to the caller's array like an in-out
    params = tuple(Param(v.attr, emitter.initial(v.type, v.init)) for v in inputs)

    def body() -> None:
        result = pou.by_key.get(key(pou.name))
        if result is not None and result.kind == "RETURN":
            returned = Var(result.attr, "local", _t(result.type))
            emitter.add(Assign(returned, emitter.initial(result.type, None), 0))
        for variable in pou.variables:
            if variable.kind in ("VAR", "VAR_TEMP", "VAR_STAT", "VAR_INST") or (
                variable.kind == "VAR_OUTPUT" and variable not in inputs
            ):
                local = Var(variable.attr, "local", _t(variable.type))
                emitter.add(Assign(local, emitter.initial(variable.type, variable.init), 0))
        emitter.add(*emitter.block(pou.pou.body, deeper=False))
        emitter.add(emitter.return_statement())

    return Function(name, params, emitter.body_of(depth + 1, body), method=pou.kind == "METHOD")


def _methods(emitter: _Emitter, pou: PouSymbols) -> list[Function | Inherited]:
    """The methods of a block's class: its own, and each one it inherits and does not
    override as the declaring block's function itself (the artifact lists, and the runtime
    makes, a block's class after the classes of the blocks it extends)."""
    resolved = emitter.scope.resolved
    accessors = [(method_attr(m.name), m) for _, m in sorted(pou.methods.items())]
    for _, prop in sorted(pou.properties.items()):
        if prop.getter is not None:
            accessors.append((getter_attr(prop.name), prop.getter))
        if prop.setter is not None:
            accessors.append((setter_attr(prop.name), prop.setter))
    methods: list[Function | Inherited] = []
    for attr, method in accessors:
        if method.declared_in != key(pou.name):  # the declaring class's own function
            owner = class_name(resolved.pous[method.declared_in].name)
            methods.append(Inherited(attr, owner))
            continue
        own = [*method.variables, *method.by_key.values()]
        inner = _Emitter(
            Scope(resolved, method), local=False, at=method.pou.pos,
            temp_count=emitter.temp_count, max_size=emitter.max_size,
            method_locals=frozenset(id(v) for v in own),
        )  # fmt: skip
        methods.append(_function(inner, method, attr, depth=1))
        emitter.temp_count = inner.temp_count
    return methods


def _data_class(emitter: _Emitter, name: str, fields: list[Variable]) -> GeneratedUnit:
    """A class that only holds data: slots with their initial values."""
    slots = tuple(Slot(v.attr, emitter.initial(v.type, v.init)) for v in fields)
    return _printed(emitter, Class(name, slots))


def declared_at(variables: list[Variable], any_pou: PouSymbols) -> Pos:
    """Where a structure or the globals are declared, to name in a diagnostic: at the first
    of their variables."""
    return variables[0].pos if variables else any_pou.pou.pos


def generate_struct(resolved: Resolved, info: StructInfo, any_pou: PouSymbols) -> GeneratedUnit:
    where = declared_at(info.members, any_pou)
    emitter = _Emitter(Scope(resolved, any_pou), local=False, at=where)
    if key(info.name) == key(STEP_STRUCT):  # SFC steps also remember when they started
        return _printed(emitter, Alias(struct_class(info.name), "_SfcStep"))
    return _data_class(emitter, struct_class(info.name), info.members)


def generate_globals(resolved: Resolved, any_pou: PouSymbols) -> GeneratedUnit:
    """The class whose single instance `_G` holds the global variables."""
    where = declared_at(resolved.globals, any_pou)
    emitter = _Emitter(Scope(resolved, any_pou), local=False, at=where, in_globals=True)
    return _data_class(emitter, "GLOBALS", resolved.globals)
