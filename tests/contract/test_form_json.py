"""The typed form as JSON (runtime/contract/code/form_json.py): a unit survives the round
trip exactly, and anything the compiler could not have built is refused with where."""

from __future__ import annotations

import json
import math
import threading
from typing import Any

import pytest

from runtime.contract.code import statements as sm
from runtime.contract.code import typed_form as tf
from runtime.contract.code.form_json import (
    FORM_DEPTH,
    MAX_COUNT,
    MAX_FORM_BYTES,
    FormRefused,
    decode_unit,
    encode_unit,
)
from runtime.contract.code.python_text import unit_lines
from runtime.contract.code.units import Alias, Class, Function, Inherited, Param, Slot, Unit
from runtime.contract.wire import depth

X = tf.Var("x", "instance", "INT")
ONE = tf.Const(1, "INT")
TRUE = tf.Const(True, "BOOL")


def _body() -> tuple[sm.Stmt, ...]:
    """Statements of every kind, holding expressions of every kind."""
    items = tf.Var("items", "instance", "ARRAY[1..3] OF INT")
    nested = sm.If(
        tf.Binary("<", X, ONE, "BOOL"),
        (sm.Break(5),),
        (sm.If(TRUE, (sm.Continue(6),), (sm.Pass(7),), 6),),
        5,
        (sm.Elif(X, (sm.Pass(8),), 8),),
    )
    call = tf.Call(
        "_limit",
        (
            tf.Chain("<", (ONE, X, tf.Const(3, "INT"))),
            tf.Slice(tf.Const("abc", "STRING"), 1, None, "STRING"),
        ),
        "INT",
        (("low", tf.Unary("-", ONE, "INT")),),
    )
    return (
        sm.Assign(X, tf.Wrap(tf.Binary("+", X, ONE, "INT"), 16, True, -3, "INT"), 2),
        sm.Assign(tf.Index(items, tf.Assigned("i", X, "INT"), "INT"), call, 3, augmented="+"),
        sm.ForEach(
            "n",
            tf.Call("range", (tf.Const(0, "DINT"), tf.Const(10, "DINT")), ""),
            (
                nested,
                sm.While(tf.Logic("and", (TRUE, tf.Unary("not", TRUE, "BOOL"))), (sm.Pass(8),), 8),
            ),
            (sm.Evaluate(tf.Call(tf.Member(tf.This("POU_T"), "M__GO", ""), (), ""), 9),),
            4,
        ),
        sm.Evaluate(tf.Choice(TRUE, tf.Const(1.5, "REAL"), tf.Const(-0.0, "REAL"), "REAL"), 10),
        sm.Evaluate(
            tf.Sequence((tf.Const(None, ""), tf.Named("_math.sin")), "", as_tuple=True), 11
        ),
        sm.Return(tf.Const("\u00e9\n'\"", "STRING"), 12),
        sm.Return(None, 13),
    )


CLASS = Class(
    "POU_T",
    (
        Slot("x", ONE),
        Slot("items", tf.Repeated(tf.Const(0, "INT"), 3, False, "ARRAY[1..3] OF INT")),
        Slot(
            "point",
            tf.Members(
                (
                    ("a b", ONE),
                    ("", tf.Sequence((), "")),
                ),
                "POINT",
            ),
        ),
        Slot("blocks", tf.Repeated(tf.Call("POU_B", (), "B"), 2, True, "ARRAY[1..2] OF B")),
    ),
    kinds=("POU_T", "I_ANY'\n"),
    functions=(Function("__call__", (), _body(), method=True), Inherited("M__GO", "POU_BASE")),
)
FUNCTION = Function(
    "FN_ADD",
    (Param("a", tf.Const(0, "INT")), Param("b", tf.Const(2**100, "LINT"))),
    (
        sm.Return(
            tf.Binary("+", tf.Var("a", "local", "INT"), tf.Var("b", "local", "INT"), "INT"), 1
        ),
    ),
)
ALIAS = Alias("STRUCT_SFC_STEP", "_SfcStep")


@pytest.mark.parametrize("unit", [CLASS, FUNCTION, ALIAS], ids=["class", "function", "alias"])
def test_a_unit_survives_the_round_trip_exactly(unit: Unit) -> None:
    text = encode_unit(unit)
    decoded = decode_unit(text, "unit T")
    assert decoded == unit
    assert encode_unit(decoded) == text
    lines = list(unit_lines(decoded))
    assert lines == list(unit_lines(unit))
    compile("\n".join(line for line, _ in lines), "unit T", "exec")


def test_a_constant_keeps_its_json_type() -> None:
    """Const(True) == Const(1) == Const(1.0) as dataclasses: only the text tells them apart."""
    texts = {encode_unit(tf_unit(tf.Const(value, "T"))) for value in (True, 1, 1.0)}
    assert len(texts) == 3
    for text in texts:
        assert encode_unit(decode_unit(text, "unit T")) == text


def test_every_node_kind_is_in_the_round_trip() -> None:
    text = encode_unit(CLASS) + encode_unit(FUNCTION) + encode_unit(ALIAS)
    kinds = [*tf.Expr.__args__, *sm.Stmt.__args__, Slot, Param, Function, Inherited, Class, Alias]
    assert [k.__name__ for k in kinds if f'["{k.__name__}",' not in text] == []


def test_the_encoding_is_canonical_json() -> None:
    text = encode_unit(Alias("A", "_B"))
    assert text == '["Alias","A","_B"]'
    assert encode_unit(tf_unit(tf.Binary("+", ONE, ONE, "INT"))) == (
        '["Function","FN_T",[],[["Evaluate",["Binary","+",["Const",1,"INT"],'
        '["Const",1,"INT"],"INT"],7]],false]'
    )
    assert encode_unit(CLASS) == encode_unit(CLASS)
    assert encode_unit(tf_unit(tf.Const("\u00e9", "STRING"))).isascii()


def test_non_finite_floats_are_spelled_as_arrays() -> None:
    values = (math.inf, -math.inf, math.nan)
    unit = tf_unit(tf.Sequence(tuple(tf.Const(v, "LREAL") for v in values), ""))
    text = encode_unit(unit)
    assert '["Const",["float","inf"],"LREAL"],["Const",["float","-inf"],"LREAL"]' in text
    assert '["Const",["float","nan"],"LREAL"]' in text
    decoded = decode_unit(text, "unit T")
    assert isinstance(decoded, Function) and isinstance(decoded.body[0], sm.Evaluate)
    sequence = decoded.body[0].value
    assert isinstance(sequence, tf.Sequence)
    got = [item.value for item in sequence.items if isinstance(item, tf.Const)]
    assert got[:2] == [math.inf, -math.inf] and isinstance(got[2], float) and math.isnan(got[2])
    assert encode_unit(decoded) == text


def tf_unit(expr: tf.Expr) -> Function:
    return Function("FN_T", (), (sm.Evaluate(expr, 7),))


def form(expr: Any) -> list[Any]:
    """A FUNCTION whose one statement evaluates `expr` (at Function.body[0].value)."""
    return ["Function", "FN_T", [], [["Evaluate", expr, 7]], False]


def refused(data: Any) -> str:
    with pytest.raises(FormRefused) as caught:
        decode_unit(data if isinstance(data, str | bytes) else json.dumps(data), "unit FN_T")
    message = str(caught.value)
    assert message.startswith("unit FN_T")
    return message


C = ["Const", 1, "INT"]
V = "Function.body[0].value"
ALIAS_FORM = ["Alias", "A", "_B"]


@pytest.mark.parametrize(
    ("data", "where", "why"),
    [
        (form(["Eval", 1]), V, "'Eval' node, not one of Assigned, Binary"),
        (form(["Pass", 1]), V, "'Pass' node, not one of"),
        (form(["Const", 1]), V, "a Const of 1 fields; a Const has 2"),
        (form(["Const", 1, "INT", "INT"]), V, "a Const of 3 fields"),
        (form([]), V, "an array, not one of"),
        (form({"Const": 1}), V, "an object"),
        (form("x"), V, "str 'x', not one of"),
        (form(["Wrap", C, True, True, 0, "INT"]), V + ".bits", "bool True, not an int"),
        (form(["Wrap", C, 16, 1, 0, "INT"]), V + ".signed", "int 1, not a bool"),
        (form(["Wrap", C, 16.0, True, 0, "INT"]), V + ".bits", "float 16.0, not an int"),
        (form(["Wrap", C, 0, True, 0, "INT"]), V + ".bits", "is 0, not 1 to 64"),
        (form(["Wrap", C, 65, True, 0, "INT"]), V + ".bits", "is 65, not 1 to 64"),
        (form(["Wrap", C, 64, True, 2**64, "INT"]), V + ".offset", "more than 64 bits"),
        (form(["Var", "x\nimport os", "local", "INT"]), V + ".name", "not an identifier"),
        (form(["Var", "a b", "local", "INT"]), V + ".name", "not an identifier"),
        (form(["Var", "import", "local", "INT"]), V + ".name", "not an identifier"),
        (form(["Var", "a.b", "local", "INT"]), V + ".name", "not an identifier"),
        (form(["Var", "\u00e9", "local", "INT"]), V + ".name", "not an identifier"),
        (form(["Var", "x", "heap", "INT"]), V + ".where", "str 'heap', not one of 'globals'"),
        (form(["Named", "_math.", ""]), V + ".name", "not a dotted name"),
        (form(["Named", "a.if", ""]), V + ".name", "not a dotted name"),
        (form(["Member", C, "x()", ""]), V + ".name", "not an identifier"),
        (form(["Binary", "**", C, C, "INT"]), V + ".op", "str '**', not one of"),
        (form(["Binary", "+", C, ["Pass", 1], "INT"]), V + ".right", "'Pass' node"),
        (form(["Unary", "+", C, "INT"]), V + ".op", "str '+'"),
        (form(["Call", "f(1);g", [], "", []]), V + ".callee", "not an identifier"),
        (form(["Call", "f", [], "", [["k=1,j", C]]]), V + ".keywords[0][0]", "identifier"),
        (form(["Call", "f", [], "", [["k", C, C]]]), V + ".keywords[0]", "has 3 items, not 2"),
        (form(["Call", "f", [C, ["Unary", "-", "x", ""]], "", []]), V + ".args[1].operand", "str"),
        (form(["Repeated", C, MAX_COUNT + 1, False, ""]), V + ".count", "not 0 to 1,000,000"),
        (form(["Repeated", C, -1, False, ""]), V + ".count", "is -1, not 0 to"),
        (form(["Slice", C, None, -1, ""]), V + ".stop", "is -1"),
        (form(["Const", 2**128, "INT"]), V + ".value", "more than 128 bits"),
        (form(["Const", "x" * 65_536, "STRING"]), V + ".value", "longer than 65,535"),
        (form(["Const", ["float", "1e3"], "REAL"]), V + ".value", "'float' node, not a constant"),
        (form(["Const", "x", "T" * 1001]), V + ".type", "longer than 1,000"),
        (form(["Members", [["m" * 1001, C]], ""]), V + ".items[0][0]", "longer than 1,000"),
        (form(["Sequence", [C], "", 0]), V + ".as_tuple", "int 0, not a bool"),
        (["Function", "FN_T", [], [["Evaluate", C, -1]], False], "Function.body[0].line", "-1"),
        (["Function", "FN_T", [], [["Pass", 10**9]], False], "Function.body[0].line", "not 0"),
        (["Function", "FN_T", [], [], False], "Function.body", "has 0 items, not 1 to"),
        (
            ["Function", "FN_T", [], [["If", C, [], [], 1, []]], False],
            "Function.body[0].body",
            "has 0 items",
        ),
        (
            ["Function", "FN_T", [], [["While", C, [C], 1]], False],
            "Function.body[0].body[0]",
            "'Const' node, not one of Assign, Break",
        ),
        (
            ["Function", "FN_T", [["Param", "s", C]], [["Pass", 1]], True],
            "the form",
            "a method with a parameter named 's'",
        ),
        (["Function", "FN_T", [], [["Pass", 1]], 1], "Function.method", "int 1, not a bool"),
        (["Function", "FN T", [], [["Pass", 1]], False], "Function.name", "not an identifier"),
        (["Binary", "+", C, C, "INT"], "the form", "not one of Alias, Class, Function"),
        (["Class", "POU_T", [], [], [ALIAS_FORM]], "Class.functions[0]", "not one of Function"),
        (["Class", "POU_T", [["Slot", "x=1", C]], [], []], "Class.slots[0].name", "identifier"),
        (["Class", "POU_T", [], [7], []], "Class.kinds[0]", "int 7, not a str"),
        (["Alias", "A", "os.system"], "Alias.target", "not an identifier"),
        (["Inherited", "M__GO", "POU_B"], "the form", "'Inherited' node, not one of"),
        (1, "the form", "int 1, not one of Alias"),
    ],
)
def test_what_the_compiler_could_not_have_built_is_refused(data: Any, where: str, why: str) -> None:
    message = refused(data)
    assert f"unit FN_T: {where} " in message
    assert why in message


def test_a_float_json_spells_as_a_number_must_be_finite() -> None:
    for token in ("NaN", "Infinity", "-Infinity", "1e999"):
        message = refused(json.dumps(form(C)).replace("1", token, 1))
        assert f"{V}.value is a non-finite float" in message


def test_a_form_of_many_items_within_limits_decodes() -> None:
    args = [["Named", "_math.sin", ""], ["Members", [["any 'text'\n", C]], ""]] * 1000
    unit = decode_unit(json.dumps(form(["Call", "f", args, "", []])), "unit T")
    assert isinstance(unit, Function) and isinstance(unit.body[0], sm.Evaluate)
    call = unit.body[0].value
    assert isinstance(call, tf.Call) and len(call.args) == 2000


def test_text_that_is_no_json_or_too_large_is_refused() -> None:
    assert "unit FN_T is not valid JSON" in refused("[1, ")
    assert "unit FN_T is not valid JSON" in refused(b"\xff")
    assert "larger than" in refused(b" " * (MAX_FORM_BYTES + 1))
    for other in (None, 12, ["Pass", 1]):  # a form must be a text, as an artifact carries it
        with pytest.raises(FormRefused, match=r"unit FN_T is .*, not a text"):
            decode_unit(other, "unit FN_T")  # type: ignore[arg-type]


def unary_nest(levels: int) -> list[Any]:
    """A form nested `levels` deep in JSON: Unary nodes around a constant."""
    expr: list[Any] = C
    for _ in range(levels - 4):  # the Function, its body, the Evaluate, the Const
        expr = ["Unary", "-", expr, "INT"]
    return form(expr)


def nested_ifs(levels: int) -> Function:
    """IFs each in the ELSE of the one before: two levels of JSON each (the If, its orelse)."""
    orelse: tuple[sm.Stmt, ...] = ()
    for _ in range(levels):
        orelse = (sm.If(TRUE, (sm.Pass(1),), orelse, 1),)
    return Function("FN_T", (), orelse)


def test_a_unit_nested_too_deep_for_its_form_is_not_encoded() -> None:
    deepest = encode_unit(nested_ifs((FORM_DEPTH - 4) // 2))
    assert depth(json.loads(deepest), 10**6) == FORM_DEPTH - 1
    assert decode_unit(deepest, "unit T") == nested_ifs((FORM_DEPTH - 4) // 2)
    for levels in ((FORM_DEPTH - 2) // 2, 999):
        with pytest.raises(
            FormRefused, match=f"FN_T: the typed form is nested deeper than {FORM_DEPTH}"
        ):
            encode_unit(nested_ifs(levels))


def test_a_thousand_elsifs_are_a_list_not_a_nest() -> None:
    """The 999 ELSIFs the compiler allows (backend/compiler/limits.py MAX_BRANCH_DEPTH)."""
    branches = tuple(sm.Elif(X, (sm.Pass(n),), n) for n in range(2, 1001))
    unit = Function("FN_T", (), (sm.If(TRUE, (sm.Pass(1),), (sm.Pass(1001),), 1, branches),))
    text = encode_unit(unit)
    assert depth(json.loads(text), 10**6) < 10
    assert encode_unit(decode_unit(text, "unit T")) == text
    assert sum(line.strip().startswith("elif ") for line, _ in unit_lines(unit)) == 999


def test_a_form_nested_deeper_than_form_depth_is_refused() -> None:
    assert depth(unary_nest(FORM_DEPTH + 1), 10**6) == FORM_DEPTH + 1
    assert f"nested deeper than {FORM_DEPTH}" in refused(unary_nest(FORM_DEPTH + 1))
    assert "nested far too deep" in refused("[" * 100_000 + "]" * 100_000)


@pytest.mark.parametrize("kind", ["Wrap", "Index", "Chain"])
def test_the_deepest_form_decodes_and_prints_in_a_thread(kind: str) -> None:
    """The nests printing takes the most frames for (two a level for a Wrap or an Index),
    FORM_DEPTH deep, under the recursion limit a fresh thread has."""
    expr: list[Any] = C
    levels = FORM_DEPTH - 4  # the Function, its body, the Evaluate, the Const
    while levels:
        if kind == "Wrap":
            expr = ["Wrap", expr, 16, True, 1, "INT"]
        elif kind == "Index":
            expr = ["Index", ["Var", "a", "local", ""], expr, "INT"]
        elif levels >= 2:  # a Chain and its values: two levels
            expr, levels = ["Chain", "<", [expr, C], "BOOL"], levels - 1
        else:
            expr = ["Unary", "-", expr, "INT"]
        levels -= 1
    data = form(expr)
    assert depth(data, 10**6) == FORM_DEPTH
    lines: list[tuple[str, int]] = []
    failures: list[BaseException] = []

    def run() -> None:
        try:
            lines.extend(unit_lines(decode_unit(json.dumps(data), "unit T")))
        except BaseException as exc:  # a RecursionError must fail the test, not the thread
            failures.append(exc)

    thread = threading.Thread(target=run)
    thread.start()
    thread.join()
    assert not failures
    assert lines[0] == ("def FN_T():", 0) and len(lines) == 2
    text = json.dumps(data, separators=(",", ":"))
    assert encode_unit(decode_unit(text, "unit T")) == text
