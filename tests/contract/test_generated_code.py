"""What generated code may contain is checked on its typed form, where an artifact's form is
decoded (runtime/contract/code/form_check.py): the ways out of the restricted namespace
are refused with the unit, where in its form and what, the runtime compiles the Python it
prints without parsing it again (runtime/contract/generated_code.py), and every unit the
compiler makes passes.

Before, the runtime compiled whatever source an artifact carried: `_idiv.__globals__` led
from the first intrinsic to `__import__`, and a POU name put into the native tier's C went
into its text as it was. Then the Python printed from the form was parsed and checked as
text; each case that check refused is a form refused here."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import threading
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings

from backend.compiler import builtins as compiler_builtins
from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile, read_source
from runtime.code.code_image import CodeImage
from runtime.code.compile_worker import child_environment
from runtime.code.intrinsics import ProgramFault, Reference, SystemView, namespace, reference_maker
from runtime.code.native.worker import ArtifactTranslation
from runtime.contract.artifact import Artifact, ArtifactError, VarInfo, load_artifact
from runtime.contract.code.form_check import check_unit
from runtime.contract.code.form_json import FORM_DEPTH, FormRefused, decode_unit, encode_unit
from runtime.contract.code.names import BUILTINS, INTRINSICS, MATH_FUNCTIONS
from runtime.contract.code.python_text import unit_lines
from runtime.contract.code.statements import (
    Assign,
    Break,
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
    Call,
    Const,
    Expr,
    Index,
    Member,
    Members,
    Named,
    Repeated,
    Sequence,
    This,
    Var,
    Wrap,
)
from runtime.contract.code.units import Alias, Class, Function, Inherited, Param, Slot, Unit
from runtime.contract.generated_code import GeneratedCodeError, check_artifact_names, compile_unit
from runtime.contract.layout import Layouts, class_layouts, image_layout
from runtime.contract.wire import depth
from tests.compiler.test_corpus_iec import FOLDERS, KNOWN, name_of, st_files
from tests.compiler.test_differential import programs
from tests.compiler.test_generated_names import KITCHEN_SINK
from tests.compiler.test_oop import DRIVES, MACHINES, MOTOR
from tests.compiler.test_sfc import QUALIFIERS
from tests.conftest import REPO
from tests.support.c_structs import compile_errors, struct_source
from tests.support.corpus_paths import corpus_dir
from tests.support.crafted_units import escape, first_in_body

N = Var("n", "instance", "INT")
TEXT = Var("text", "instance", "STRING")
FB_VAR = Var("fb", "instance", "FB_VAR")
TICK = Var("__t1", "local", "")


def const(value: bool | int | float | str | None) -> Const:
    return Const(value, "")


def member(base: Expr, name: str) -> Member:
    return Member(base, name, "")


def call(callee: str | Expr, *args: Expr, keywords: tuple[tuple[str, Expr], ...] = ()) -> Call:
    return Call(callee, args, "", keywords)


def set_n(value: Expr) -> Assign:
    return Assign(N, value, 12)


def run(value: Expr) -> Evaluate:
    return Evaluate(value, 12)


def local(name: str) -> Var:
    return Var(name, "local", "")


def block(*body: Stmt) -> Class:
    """A block as the compiler builds one, `body` at the end of its `__call__`."""
    counted = Call("_idiv", (Binary("+", N, const(1), "INT"), const(2)), "INT")
    call_body = (Assign(TICK, Named("_tick"), 10), Assign(N, counted, 11), *body)
    slots = (Slot("n", const(0)), Slot("text", const("")), Slot("fb", call("POU_OTHER")))
    return Class("POU_M", slots, functions=(Function("__call__", (), call_body, method=True),))


def function(*params: Param, body: tuple[Stmt, ...] = (Return(const(1), 2),)) -> Function:
    return Function("FN_X", params, body)


def refusal(unit: Unit, kind: str = "PROGRAM", class_name: str | None = None) -> str:
    """Why the check refuses `unit`, a form the decoder takes (so that the check, and not the
    decoder, is what refuses it)."""
    decoded = decode_unit(encode_unit(unit), "the form of PROGRAM Main")
    assert decoded == unit
    with pytest.raises(FormRefused) as refused:
        name = decoded.name if class_name is None else class_name
        check_unit(decoded, kind, name, "the form of PROGRAM Main")
    return str(refused.value)


def test_a_block_as_the_compiler_builds_it_passes() -> None:
    ticked = If(Binary("is not", Named("_tick"), const(None), "BOOL"), (run(call(TICK)),), (), 12)
    held = local("__t2")
    ran = (Assign(held, FB_VAR, 13), run(call(member(held, "__call__"))))
    check_unit(block(ticked, *ran), "PROGRAM", "POU_M", "the form of PROGRAM M")


def _deref_class(held: Expr | None = None) -> Member:
    """`_deref(held).__class__`, `held` the local `__t2` by default."""
    return member(call("_deref", local("__t2") if held is None else held), "__class__")


_GLOBALS = Index(member(Named("_idiv"), "__globals__"), const("builtins"), "")
_KIND_LOOKUP = member(member(_deref_class(), "__dict__"), "get")

# (body statements, what the refusal names): each line the check of the printed Python
# refused that the form can describe, and the escapes only a form can spell
ESCAPES: list[tuple[tuple[Stmt, ...], str]] = [
    ((set_n(_GLOBALS),), "the attribute '__globals__'"),
    ((run(call(member(call(member(_GLOBALS, "__import__"), const("os")), "system"))),),
     "a call of the attribute 'system'"),
    ((set_n(member(member(const(1), "__class__"), "__mro__")),), "the attribute '__mro__'"),
    ((set_n(call(member(member(member(const(""), "__class__"), "__base__"), "__subclasses__"))),),
     "a call of the attribute '__subclasses__'"),
    ((set_n(member(Named("_copy"), "__closure__")),), "the attribute '__closure__'"),
    ((set_n(call(member(Named("str"), "mro"))),), "a call of the attribute 'mro'"),
    ((set_n(member(Named("str"), "mro")),), "str other than called"),
    ((Assign(TEXT, call(member(const("{0.__globals__}"), "format"), Named("_idiv")), 12),),
     "a call of the attribute 'format'"),
    ((Assign(TEXT, call(member(TEXT, "format_map"), This("")), 12),),
     "a call of the attribute 'format_map'"),
    ((set_n(call("getattr", This(""), const("__class__"))),), "a call of 'getattr'"),
    ((set_n(call("type", This(""))),), "a call of 'type'"),
    ((set_n(call("eval", const("1"))),), "a call of 'eval'"),
    ((run(call("exec", const("import os"))),), "a call of 'exec'"),
    ((run(call("open", const("/tmp/padt-escape"), const("w"))),), "a call of 'open'"),
    ((run(call("__import__", const("os"))),), "a call of '__import__'"),
    ((set_n(local("__builtins__")),), "the name '__builtins__'"),
    ((set_n(Named("__builtins__")),), "the name '__builtins__'"),
    ((set_n(Named("_math.pi")),), "_math.pi other than called"),
    ((set_n(call("_safe_math", Named("_math.__loader__"), const(1.0))),),
     "_safe_math of anything but a function of _math"),
    ((set_n(call("_safe_math", member(TEXT, "format"), const(1.0))),),
     "_safe_math of anything but a function of _math"),
    ((Assign(member(Named("_math"), "sqrt"), Named("_copy"), 12),), "_math other than called"),
    ((set_n(Members((("a", const(1)),))),), "a dict other than the members of _init"),
    ((set_n(call("max", N, keywords=(("key", Named("_copy")),))),), "max() with keywords"),
    ((set_n(call("max", call("range", const(10**18)))),), "max() of fewer than two values"),
    ((set_n(call("min", N)),), "min() of fewer than two values"),
    ((set_n(Binary("<<", const(1), const(2**33), "LWORD")),),
     "a shift left by more than 64 or by an unbounded count"),
    ((set_n(Binary("<<", const(1), N, "LWORD")),),
     "a shift left by more than 64 or by an unbounded count"),
    ((set_n(Binary("<<", const(1), call("min", N, const(65)), "LWORD")),),
     "a shift left by more than 64 or by an unbounded count"),
    ((set_n(Binary("<<", const(1), call("max", N, const(64)), "LWORD")),),
     "a shift left by more than 64 or by an unbounded count"),
    ((set_n(call("_copy", FB_VAR, keywords=(("memo", This("")),))),), "_copy() with keywords"),
    ((set_n(call("FN_X", keywords=(("__kw", FB_VAR),))),), "the keyword '__kw'"),
    ((Assign(local("__builtins__"), Members(()), 12),), "the local name '__builtins__'"),
    ((Assign(local("_copy"), member(TEXT, "format"), 12), run(call("_copy", This("")))),
     "_copy as a local"),
    ((run(Assigned("_deref", member(TEXT, "format"), "")), set_n(call("_deref", This("")))),
     "_deref as a local"),
    ((Assign(local("__t2"), member(TEXT, "format"), 12), run(call(local("__t2"), const("x")))),
     "a call of '__t2' with arguments"),
    ((Assign(TICK, member(TEXT, "format"), 12), run(call(TICK))), "a call of '__t1'"),
    ((run(call(local("__t3"))),), "a call of '__t3'"),
    ((Assign(Var("now_ns", "system", "TIME"), const(0), 12),), "an assignment to _SYS.now_ns"),
    ((Assign(member(Named("_SYS"), "COLDSTART"), const(True), 12),),
     "an assignment to _SYS.COLDSTART"),
    ((set_n(member(Named("_SYS"), "__class__")),), "the attribute _SYS.__class__"),
    ((set_n(Var("__class__", "system", "")),), "the attribute _SYS.__class__"),
    ((Assign(Var("POU_M", "programs", ""), This(""), 12),), "an assignment to _P.POU_M"),
    ((set_n(Var("n", "programs", "")),), "the attribute _P.n"),
    ((set_n(Var("__dict__", "globals", "")),), "the attribute _G.__dict__"),
    ((set_n(member(This(""), "M__run")),), "the attribute 'M__run'"),
    ((set_n(Var("KIND__", "instance", "")),), "the attribute 'KIND__'"),
    ((set_n(member(TEXT, "__call__")),), "the attribute '__call__'"),
    ((run(call(member(Named("POU_M"), "__call__"), Named("_idiv"))),),
     "__call__ other than of a block instance or SUPER^()"),
    ((run(call(member(FB_VAR, "__call__"))),), "__call__ other than of a block instance"),
    ((set_n(call("_ref", This(""), Sequence((const("__class__"),), "", True), const(""))),),
     "a reference through '__class__'"),
    ((set_n(call("_ref", Named("_SYS"), Sequence((const("COLDSTART"),), "", True), const(""))),),
     "_SYS other than called or with its attributes"),
    ((set_n(call("_init", This(""), Members((("__class__", const(1)),)))),),
     "_init of the member '__class__'"),
    ((set_n(member(_deref_class(FB_VAR), "__base__")),), "the attribute '__base__'"),
    ((set_n(call(_KIND_LOOKUP, const("__init__"), Sequence((), "", True))),),
     "a call of the attribute 'get'"),
    ((set_n(Index(member(_deref_class(FB_VAR), "__dict__"), const("KIND__"), "")),),
     "the attribute '__dict__'"),
    ((set_n(member(_deref_class(FB_VAR), "__name__")),), "the attribute '__name__'"),
    ((set_n(Named("_idiv")),), "_idiv other than called"),
    ((set_n(local("_idiv")),), "_idiv other than called"),
    ((set_n(local("x")),), "the name 'x'"),
    ((set_n(call(Named("_idiv"), const(1), const(2))),), "a call of a Named"),
    ((set_n(call("_SfcStep")),), "a call of '_SfcStep'"),
    ((set_n(call("_reference_roots")),), "a call of '_reference_roots'"),
    ((set_n(Named("_tick")),), "_tick other than called"),
    ((Assign(local("range"), const(0), 12), set_n(Repeated(const(0), 2, True, ""))),
     "range as a local"),
    ((Assign(local("float"), const(0), 12), set_n(const(float("inf")))), "float as a local"),
    ((set_n(Repeated(local("_"), 2, False, "")),), "the name '_'"),
    ((Break(12),), "a Break outside a loop"),
    ((While(const(True), (Pass(12),), 12), Break(13)), "a Break outside a loop"),
    ((Assign(const(1), const(2), 12),), "an assignment to a Const"),
    ((Assign(This(""), const(2), 12),), "an assignment to a This"),
    ((Assign(Sequence((N, N), "", True), const(1), 12, "+"),), "an assignment to a Sequence"),
]  # fmt: skip


@pytest.mark.parametrize(("body", "reason"), ESCAPES, ids=[r for _, r in ESCAPES])
def test_an_escape_is_refused_naming_the_unit_where_and_what(
    body: tuple[Stmt, ...], reason: str
) -> None:
    found = refusal(block(*body))
    assert found.startswith("the form of PROGRAM Main: Class.functions[0].body["), found
    assert reason in found, found
    assert found.endswith(" is not allowed"), found


def test_the_place_named_is_the_node_at_fault() -> None:
    found = refusal(block(set_n(const(1)), set_n(_GLOBALS)))
    assert "Class.functions[0].body[3].value.base: the attribute '__globals__'" in found, found
    found = refusal(block(set_n(call("FN_X", keywords=(("a", N), ("__b", N))))))
    assert "body[2].value.keywords[1]: the keyword '__b'" in found, found


def test_what_passes_where_the_compiler_writes_it_is_refused_elsewhere() -> None:
    """The shapes of dunders the compiler writes, each only where it writes them."""
    deref_name = member(_deref_class(), "__name__")
    kinds = call(_KIND_LOOKUP, const("KIND__"), Sequence((), "", True))
    held = (Assign(local("__t2"), FB_VAR, 12),)
    check_unit(block(*held, set_n(deref_name), set_n(kinds)), "PROGRAM", "POU_M", "M")
    super_call = run(call(member(Named("POU_BASE"), "__call__"), This("")))
    check_unit(block(super_call), "PROGRAM", "POU_M", "M")
    outside = function(Param("s", const(0)), body=(super_call, Return(const(1), 2)))
    assert "__call__ other than of a block instance or SUPER^()" in refusal(outside, "FUNCTION")


def _method(*params: Param, name: str = "M__a", method: bool = True) -> Function:
    return Function(name, params, (Pass(1),), method)


def _class(*functions: Function | Inherited, slots: tuple[Slot, ...] = ()) -> Class:
    return Class("POU_M", slots, (), functions)


# (a unit, its kind, what the refusal names): the shape of the unit around the bodies
UNITS: list[tuple[Unit, str, str]] = [
    (Class("_idiv", ()), "PROGRAM", "a Class named '_idiv'"),
    (Class("FN_X", ()), "PROGRAM", "a Class named 'FN_X'"),
    (function(), "PROGRAM", "a Function for a PROGRAM"),
    (block(), "FUNCTION", "a Class for a FUNCTION"),
    (Alias("POU_M", "_SfcStep"), "FUNCTION_BLOCK", "an Alias for a FUNCTION_BLOCK"),
    (block(), "MODULE", "a unit of kind 'MODULE'"),
    (replace(function(), name="POU_X"), "FUNCTION", "a Function named 'POU_X'"),
    (function(Param("a", call("open", const("/tmp/x"), const("w")))), "FUNCTION",
     "a call of 'open'"),
    (function(Param("a", member(Named("_idiv"), "__globals__"))), "FUNCTION",
     "the attribute '__globals__'"),
    (function(Param("a", Assigned("_idiv", const(1), ""))), "FUNCTION",
     "binding '_idiv' where the unit is defined"),
    (function(Param("a", Wrap(local("a"), 32, True, 0, ""))), "FUNCTION", "the name 'a'"),
    (function(Param("a", const(0)), Param("a", const(1))), "FUNCTION", "a second parameter 'a'"),
    (function(Param("__class__", const(0))), "FUNCTION", "the local name '__class__'"),
    (replace(function(), method=True), "FUNCTION", "a function taking an instance outside"),
    (function(body=(ForEach("__x__", const(0), (Pass(1),), (), 1),)), "FUNCTION",
     "the local name '__x__'"),
    (function(body=(run(call(local("a"))),)), "FUNCTION", "a call of 'a'"),
    (function(Param("a", const(0)), body=(run(call(local("a"))),)), "FUNCTION", "a call of 'a'"),
    (function(body=(Return(This(""), 1),)), "FUNCTION", "the name 's'"),
    (_class(slots=(Slot("__dict__", const(0)),)), "PROGRAM", "the slot '__dict__'"),
    (_class(slots=(Slot("M__run", const(0)),)), "PROGRAM", "the slot 'M__run'"),
    (_class(slots=(Slot("KIND__", const(0)),)), "PROGRAM", "the slot 'KIND__'"),
    (_class(slots=(Slot("a", local("x")),)), "PROGRAM", "the name 'x'"),
    (_class(slots=(Slot("a", call("open", const("f"))),)), "PROGRAM", "a call of 'open'"),
    (Class("POU_M", (), ("FB_VAR", "a')\nimport os #")), "PROGRAM", "the KIND__ entry"),
    (_class(_method(name="__del__")), "PROGRAM", "a method named '__del__'"),
    (_class(_method(name="__init__")), "PROGRAM", "a method named '__init__'"),
    (_class(_method(method=False)), "PROGRAM", "the method M__a without its instance"),
    (_class(_method(Param("a", const(0)), name="__call__")), "PROGRAM",
     "__call__ with parameters"),
    (_class(_method(Param("x", call("open", const("f"))))), "PROGRAM", "a call of 'open'"),
    (_class(_method(Param("x", This("")))), "PROGRAM", "the name 's'"),
    (_class(_method(Param("x", N))), "PROGRAM", "the name 's'"),
    (_class(Inherited("__getattr__", "POU_BASE")), "PROGRAM", "inheriting '__getattr__'"),
    (_class(Inherited("M__a", "_idiv")), "PROGRAM", "inheriting from '_idiv'"),
    (_class(Inherited("M__a", "FN_X")), "PROGRAM", "inheriting from 'FN_X'"),
    (Alias("STRUCT_M", "_idiv"), "STRUCT", "an alias of '_idiv'"),
    (Alias("STRUCT_M", "__builtins__"), "STRUCT", "an alias of '__builtins__'"),
    (Alias("_idiv", "_SfcStep"), "STRUCT", "an Alias named '_idiv'"),
]  # fmt: skip


@pytest.mark.parametrize(("unit", "kind", "reason"), UNITS, ids=[r for *_, r in UNITS])
def test_a_unit_of_another_shape_is_refused(unit: Unit, kind: str, reason: str) -> None:
    found = refusal(unit, kind)
    assert found.startswith("the form of PROGRAM Main: "), found
    assert reason in found, found


def test_a_unit_is_the_class_of_its_name() -> None:
    """The runtime finds a unit's class by the artifact's name for it: a form of another
    name (another unit's) is refused."""
    found = refusal(block(), "PROGRAM", "POU_OTHER")
    assert "Class.name: the name 'POU_M' for the unit 'POU_OTHER' is not allowed" in found


# the constructs the check of the printed Python refused by name: the form has no node for
# any of them, so no artifact can carry one
NO_NODE = [
    "Import", "ImportFrom", "Lambda", "GeneratorExp", "Yield", "Await", "Try", "With",
    "Global", "Nonlocal", "Delete", "JoinedStr", "Starred", "Dict", "Set", "DictComp",
    "Raise", "Assert", "ClassDef", "FunctionDef", "AsyncFunctionDef", "Match", "Attribute",
    "Name", "Subscript",
]  # fmt: skip


@pytest.mark.parametrize("tag", NO_NODE)
def test_a_construct_the_form_has_no_node_for_is_refused_as_it_is_decoded(tag: str) -> None:
    data = json.loads(encode_unit(block()))
    body = data[4][0][3]  # the __call__'s body
    for node in (["Evaluate", [tag, "os"], 1], [tag, "os"]):
        crafted = json.dumps([*data[:4], [[*data[4][0][:3], [*body, node], True]]])
        with pytest.raises(FormRefused, match=f"is a '{tag}' node, not "):
            decode_unit(crafted, "the form of PROGRAM Main")


def test_nothing_of_a_form_that_is_refused_runs_nor_is_compiled(tmp_path: Path) -> None:
    """A crafted artifact's code is refused where it is decoded: by load_artifact, and by
    a code image made of the artifact as it is (never loaded), before anything compiles."""
    written = tmp_path / "escaped"
    crafted = first_in_body(_fb_first(_artifact(FB)), escape(written))
    with pytest.raises(ArtifactError, match=r"the form of FUNCTION_BLOCK Fb: Class\.functions"):
        load_artifact(crafted.to_json())
    compiled: list[object] = []
    with pytest.raises(FormRefused, match="a call of the attribute 'write_text' is not allowed"):
        CodeImage(crafted, SystemView(), compile_units=compiled.extend)  # type: ignore[arg-type]
    assert not compiled and not written.exists()


def test_compile_unit_compiles_the_printed_python_and_refuses_what_does_not_compile() -> None:
    assert compile_unit(_printed(block()), "<PROGRAM Main>").co_filename == "<PROGRAM Main>"
    repeated = block(set_n(call("FN_X", keywords=(("a", N), ("a", N)))))
    check_unit(repeated, "PROGRAM", "POU_M", "M")  # Python's to refuse
    with pytest.raises(GeneratedCodeError, match="Main, line 12: keyword argument repeated"):
        compile_unit(_printed(repeated), "<PROGRAM Main>")


def _printed(unit: Unit) -> str:
    return "\n".join(line for line, _ in unit_lines(unit)) + "\n"


@pytest.mark.parametrize("kind", ["Member", "Call"])
def test_the_deepest_form_is_checked_in_a_thread(kind: str) -> None:
    """The nests the check takes the most frames for (two a level of JSON: a member's
    base, a call's argument), FORM_DEPTH deep, decoded and checked under the recursion
    limit a fresh thread has."""
    expr: list[Any] = ["Var", "a", "local", ""]
    levels = FORM_DEPTH - 4  # the Function, its body, the Evaluate, the Var
    while levels > 1:
        if kind == "Member":
            expr, levels = ["Member", expr, "b", ""], levels - 1
        else:  # a Call and its arguments: two levels
            expr, levels = ["Call", "abs", [expr], "", []], levels - 2
    param = ["Param", "a", ["Const", 0, "INT"]]
    data = ["Function", "FN_T", [param], [["Evaluate", expr, 7]], False]
    assert depth(data, 10**6) >= FORM_DEPTH - 1
    failures: list[BaseException] = []

    def run() -> None:
        try:
            unit = decode_unit(json.dumps(data), "the form of FUNCTION T")
            check_unit(unit, "FUNCTION", "FN_T", "the form of FUNCTION T")
        except BaseException as exc:  # a RecursionError must fail the test, not the thread
            failures.append(exc)

    thread = threading.Thread(target=run)
    thread.start()
    thread.join()
    assert not failures, failures


def test_the_runtime_names_are_one_table() -> None:
    names = namespace(SystemView())
    assert names.keys() - {"__builtins__", "__name__"} == INTRINSICS
    assert names["__builtins__"].keys() - {"__build_class__"} == BUILTINS
    emitted = {code.removeprefix("_math.") for code in compiler_builtins._MATH.values()}
    assert emitted <= MATH_FUNCTIONS


def test_a_reference_made_at_run_time_keeps_to_variables_of_generated_objects() -> None:
    """A step the check of the form cannot see (`'__glo' + 'bals__'`) is refused when the
    code runs, and a reference once made cannot be changed."""
    made_of = replace(block(), slots=block().slots[:2])
    code = compile_unit(_printed(made_of), "<PROGRAM M>")
    names = namespace(SystemView())
    exec(code, names)
    instance = names["POU_M"]()
    make = reference_maker({})
    assert make(instance, ("n",), "n").get() == 0
    with pytest.raises(ProgramFault, match="through '__globals__'"):
        make(instance, ("__glo" + "bals__",), "")
    with pytest.raises(ProgramFault, match="a reference into a module"):
        make(names["_math"], ("sqrt",), "")
    with pytest.raises(ProgramFault, match="a reference into a function"):
        make(names["_idiv"], ("x",), "")
    made = make(instance, ("n",), "n")
    assert isinstance(made, Reference)
    with pytest.raises(AttributeError):
        made.steps = ("__class__",)
    with pytest.raises(AttributeError):
        made.root = names["_idiv"]


def test_a_whole_store_writes_into_variables_of_generated_objects_only() -> None:
    """`_fill` (an array or structure written whole, in place) takes a structure of a
    generated class, a list or an image's array, never the runtime's objects: not `_SYS`
    (whose read-only members the checked stores never write), nor a dict the code names."""
    code = compile_unit(_printed(replace(block(), slots=block().slots[:2])), "<PROGRAM M>")
    names = namespace(SystemView())
    exec(code, names)
    fill, first, second = names["_fill"], names["POU_M"](), names["POU_M"]()
    second.n = 7
    fill(first, second)
    assert first.n == 7
    numbers = [1, 2]
    fill(numbers, [3, 4])
    assert numbers == [3, 4]
    with pytest.raises(ProgramFault, match="a whole store into a SystemView"):
        fill(names["_SYS"], second)
    with pytest.raises(ProgramFault, match="a whole store into a dict"):
        fill(names["_reference_roots"], [1, 2])


# ---- the names an artifact gives its units, which the runtime and the native tier use


def _artifact(source: str) -> Artifact:
    return _compiled([SourceFile("t.st", source)])


def _compiled(sources: list[SourceFile]) -> Artifact:
    result = compile_sources(sources)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


FB = """
FUNCTION_BLOCK Fb
VAR_INPUT x : DINT; END_VAR
VAR_OUTPUT y : DINT; END_VAR
y := x * 2;
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : Fb; END_VAR
f(x := 1);
END_PROGRAM
"""
C_INJECTION = 'X */ __attribute__((constructor)) static void f(void) { system("touch x"); } /*'


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        ({"name": C_INJECTION}, "is not an identifier"),
        ({"class_name": "POU_X */ int y; /*"}, "is not the name of such a unit"),
        ({"class_name": "_idiv"}, "is not the name of such a unit"),
        ({"kind": "MODULE"}, "a unit of kind 'MODULE'"),
        ({"variables": (VarInfo("x", "__class__", "DINT", "VAR"),)}, "'__class__' is not a"),
        ({"variables": (VarInfo("x", "x */ y", "DINT", "VAR"),)}, "'x */ y' is not a"),
    ],
)
def test_a_unit_named_otherwise_than_the_compiler_names_it_is_refused(
    change: dict[str, object], reason: str
) -> None:
    artifact = _artifact(FB)
    fb = artifact.pou("Fb")
    hostile = replace(fb, **change)  # type: ignore[arg-type]
    others = tuple(p for p in artifact.pous if p is not fb)
    bad = replace(artifact, pous=(hostile, *others)).with_crc()
    with pytest.raises(GeneratedCodeError, match=reason.replace("*", r"\*")):
        check_artifact_names(bad)
    with pytest.raises(GeneratedCodeError):
        ArtifactTranslation.of(bad)  # nothing of it is translated to C


def test_the_native_worker_builds_nothing_of_an_artifact_with_a_name_of_its_own(
    tmp_path: Path,
) -> None:
    """The worker process, fed as the runtime feeds it: a POU name that would close the
    comment it is written into and add C of its own is refused, nothing is compiled."""
    artifact = _artifact(FB)
    fb = artifact.pou("Fb")
    named = replace(fb, name=C_INJECTION)
    bad = replace(artifact, pous=(named, *(p for p in artifact.pous if p is not fb))).with_crc()
    done = subprocess.run(
        [sys.executable, "-m", "runtime.code.native.worker", str(tmp_path / "cache")],
        input=bad.to_json().encode(),
        capture_output=True,
        env=child_environment(),
        timeout=300,
        check=False,
    )
    answer = json.loads(done.stdout)
    assert "is not an identifier" in answer.get("error", ""), answer
    assert not [p for p in tmp_path.rglob("*") if p.suffix in (".c", ".so")]
    assert not (tmp_path / "x").exists()


def test_a_name_that_reached_the_translator_stays_in_its_comment() -> None:
    """Behind the check, the translator's comments hold any name (the unit's name goes
    into the C source's first comment)."""
    artifact = _artifact(FB)
    translation = ArtifactTranslation.of(artifact)
    fb = artifact.pou("Fb")
    source = translation.translate(replace(fb, name=C_INJECTION)).source
    first = source.splitlines()[0]
    assert first.startswith("/* native code of <FUNCTION_BLOCK X * / __attribute__")
    assert first.endswith("runtime/code/native/translate.py */") and first.count("*/") == 1


def test_no_text_of_a_source_reaches_the_c_of_the_native_tier_unchecked() -> None:
    """A string constant with C in it reaches the C only as a string literal, escaped
    (what is left without the literals and comments has none of it); a source that does
    not pass is not translated at all."""
    artifact = _artifact(
        FB.replace("y := x * 2;", 'y := x * 2; s := \'"); system("x"); ("\';').replace(
            "VAR_OUTPUT y : DINT;", "VAR_OUTPUT y : DINT; s : STRING;"
        )
    )
    translation = ArtifactTranslation.of(artifact)
    sources = [translation.translate(unit).source for unit in translation.units]
    assert any('\\"); system(\\"x\\"); (\\"' in source for source in sources)
    for source in sources:
        assert "system(" not in _LITERALS_AND_COMMENTS.sub("", source)
    imported = Evaluate(Call("__import__", (Const("os", "STRING"),), ""), 0)
    with pytest.raises(ArtifactError, match=r"the form of FUNCTION_BLOCK Fb: Class\.functions"):
        load_artifact(first_in_body(_fb_first(artifact), imported).to_json())


_LITERALS_AND_COMMENTS = re.compile(r'/\*.*?\*/|"(?:\\.|[^"\\])*"', re.DOTALL)


def _fb_first(artifact: Artifact) -> Artifact:
    fb = artifact.pou("Fb")
    return replace(artifact, pous=(fb, *(p for p in artifact.pous if p is not fb)))


# ---- every artifact the compiler makes passes


def _check_all(artifact: Artifact, laid_out: list[Layouts] | None = None) -> None:
    """Every unit of the compiler's `artifact` passes: its form as the compiler built it
    (the compiler's own code is not checked as it runs, `PouCode.knowing`); and every
    class gets a layout in native memory, the configuration an image (into `laid_out`,
    for a C compiler to check)."""
    check_artifact_names(artifact)
    for unit in artifact.units():
        check_unit(unit.unit, unit.kind, unit.class_name, f"the form of {unit.kind} {unit.name}")
    layouts = class_layouts(artifact.units())
    image_layout(artifact, layouts)
    if laid_out is not None:
        laid_out.append(layouts)


def test_every_unit_of_the_demo_the_language_tests_and_the_feature_samples_passes() -> None:
    files = sorted(
        p for p in REPO.rglob("*.st") if ".venv" not in p.parts and "node_modules" not in p.parts
    )
    assert len(files) >= 10
    laid_out: list[Layouts] = []
    # a project's files (a folder with its padt.toml) compile together: one may declare the
    # globals another names (the SFC template does)
    projects = sorted({p.parent for p in files if (p.parent / "padt.toml").is_file()})
    # a project's tests (its test/ folder) compile with it, as `padt test` compiles them;
    # the OSCAT example's need the OSCAT library from the corpus (its own test has it)
    tests = {p: folder for folder in projects for p in files if p.is_relative_to(folder / "test")}
    for folder in projects:
        if folder.name == "oscat-tests":
            continue
        together = [
            SourceFile(p.relative_to(folder).as_posix(), p.read_text())
            for p in files
            if p.parent == folder or tests.get(p) == folder
        ]
        _check_all(_compiled(together), laid_out)
    for path in files:
        if path.parent not in projects and path not in tests:
            _check_all(_artifact(path.read_text()), laid_out)
    samples = [
        KITCHEN_SINK.format(names=""),
        DRIVES + "PROGRAM Main\nVAR s : Servo; END_VAR\ns(speed := 1); s.Run();\nEND_PROGRAM\n",
        MACHINES
        + "PROGRAM Main\nVAR m : Mixer; i : INamed; r : REF_TO FastMixer; k : INT; END_VAR\n"
        "i := m; r ?= i; k := i.Run(1);\nEND_PROGRAM\n",
        MOTOR + "PROGRAM Main\nVAR m : Motor; v : INT; END_VAR\nm(); v := m.Velocity;\n"
        "m.Velocity := 3;\nEND_PROGRAM\n",
        QUALIFIERS,
    ]
    for sample in samples:
        _check_all(_artifact(sample), laid_out)
    assert compile_errors(struct_source(laid_out)) == ""


def test_every_unit_of_the_corpus_passes() -> None:
    """OSCAT, matiec and the rest of ../shared/corpus (skipped when it is absent, never in
    CI)."""
    corpus_dir("oscat")
    checked = 0
    laid_out: list[Layouts] = []
    for folder, together in sorted(FOLDERS.items()):
        files = [p for p in st_files(corpus_dir(folder)) if name_of(p) not in KNOWN]
        sets = [files] if together else [[p] for p in files]
        for paths in sets:
            result = compile_sources([read_source(p, name_of(p)) for p in paths], programs=[])
            assert result.artifact is not None, paths
            _check_all(result.artifact, laid_out)
            checked += len(result.artifact.pous)
    assert checked > 500
    assert compile_errors(struct_source(laid_out)) == ""


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(programs())
def test_every_random_program_passes(program: str) -> None:
    _check_all(_artifact(program))
