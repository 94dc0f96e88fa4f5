"""The typed form (runtime/contract/code/typed_form.py, statements.py) and its Python
text: every kind of node prints, what prints computes what the node says (an integer
wrapped to its bits, a chained comparison, a choice that evaluates one side), and every
statement's line keeps its ST line."""

from __future__ import annotations

import math
import typing

from hypothesis import given
from hypothesis import strategies as st

from runtime.contract.code import statements as sm
from runtime.contract.code import typed_form as tf
from runtime.contract.code.python_text import python_lines, python_text


def _run(node: tf.Expr, **names: object) -> object:
    return eval(python_text(node), {}, dict(names))  # our own printed node


def _wrapped(value: int, bits: int, signed: bool) -> int:
    value &= (1 << bits) - 1
    return value - (1 << bits) if signed and value >= 1 << (bits - 1) else value


@given(
    st.integers(min_value=-(2**70), max_value=2**70),
    st.sampled_from([8, 16, 32, 64]),
    st.booleans(),
    st.integers(min_value=-300, max_value=300),
)
def test_a_wrap_brings_any_integer_plus_its_offset_into_its_bits(
    value: int, bits: int, signed: bool, offset: int
) -> None:
    node = tf.Wrap(tf.Var("x", "local", "LINT"), bits, signed, offset, "INT")
    assert _run(node, x=value) == _wrapped(value + offset, bits, signed)


def test_a_chain_compares_each_neighbour_and_evaluates_each_value_once() -> None:
    seen: list[int] = []

    def once(value: int) -> int:
        seen.append(value)
        return value

    middle = tf.Call("once", (tf.Const(5, "INT"),), "INT")
    node = tf.Chain("<=", (tf.Const(1, "INT"), middle, tf.Const(9, "INT")))
    assert _run(node, once=once) is True
    assert seen == [5]
    outside = tf.Chain("<", (tf.Const(3, "INT"), tf.Const(2, "INT"), tf.Const(9, "INT")))
    assert _run(outside) is False


def test_a_choice_evaluates_only_the_side_chosen() -> None:
    def fault() -> int:
        raise AssertionError("the side not chosen ran")

    node = tf.Choice(
        tf.Var("ok", "local", "BOOL"), tf.Const(1, "INT"), tf.Call("fault", (), "INT"), "INT"
    )
    assert _run(node, ok=True, fault=fault) == 1


def test_constants_print_as_python_reads_them_back_infinities_and_nan_too() -> None:
    for value in (0, -7, 2**63, 0.1, -0.0, "it's", True, None):
        assert _run(tf.Const(value, "X")) == value
    assert _run(tf.Const(math.inf, "LREAL")) == math.inf
    assert _run(tf.Const(-math.inf, "LREAL")) == -math.inf
    assert math.isnan(typing.cast(float, _run(tf.Const(math.nan, "LREAL"))))


def test_every_kind_of_node_has_a_python_text() -> None:
    one, x = tf.Const(1, "INT"), tf.Var("x", "local", "INT")
    samples: dict[type, tf.Expr] = {
        tf.Const: one,
        tf.Var: x,
        tf.This: tf.This("P"),
        tf.Named: tf.Named("POU_P"),
        tf.Member: tf.Member(tf.This("P"), "x", "INT"),
        tf.Index: tf.Index(x, one, "INT"),
        tf.Slice: tf.Slice(x, None, 4, "STRING[4]"),
        tf.Unary: tf.Unary("-", x, "INT"),
        tf.Binary: tf.Binary("+", x, one, "INT"),
        tf.Chain: tf.Chain("<", (one, x)),
        tf.Logic: tf.Logic("or", (x, one)),
        tf.Choice: tf.Choice(x, one, x, "INT"),
        tf.Assigned: tf.Assigned("t", x, "INT"),
        tf.Wrap: tf.Wrap(x, 16, True, 0, "INT"),
        tf.Call: tf.Call("abs", (x,), "INT"),
        tf.Sequence: tf.Sequence((one, x), ""),
        tf.Repeated: tf.Repeated(one, 3, False, "ARRAY[1..3] OF INT"),
        tf.Members: tf.Members((("x", one),)),
    }
    assert set(samples) == set(typing.get_args(tf.Expr))
    texts = {kind.__name__: python_text(node) for kind, node in samples.items()}
    assert texts == {
        "Const": "1",
        "Var": "x",
        "This": "s",
        "Named": "POU_P",
        "Member": "s.x",
        "Index": "x[1]",
        "Slice": "x[:4]",
        "Unary": "(-x)",
        "Binary": "(x + 1)",
        "Chain": "(1 < x)",
        "Logic": "(x or 1)",
        "Choice": "(1 if x else x)",
        "Assigned": "(t := x)",
        "Wrap": "(((x) + 32768 & 65535) - 32768)",
        "Call": "abs(x)",
        "Sequence": "[1, x]",
        "Repeated": "[1] * 3",
        "Members": "{'x': 1}",
    }


def test_statements_print_as_lines_each_with_its_st_line() -> None:
    x, one = tf.Var("x", "local", "INT"), tf.Const(1, "INT")
    done = tf.Binary(">", x, one, "BOOL")
    body = (
        sm.Assign(x, one, 3),
        sm.Assign(x, one, 4, augmented="+"),
        sm.If(done, (sm.Break(6),), (sm.Pass(8),), 5, (sm.Elif(x, (sm.Continue(7),), 7),)),
        sm.While(done, (sm.Evaluate(tf.Call("abs", (x,), "INT"), 10),), 9),
        sm.ForEach("i", tf.Var("r", "local", ""), (sm.Pass(12),), (sm.Return(x, 13),), 11),
        sm.Return(None, 14),
    )
    assert list(python_lines(body, 1)) == [
        ("    x = 1", 3),
        ("    x += 1", 4),
        ("    if x > 1:", 5),
        ("        break", 6),
        ("    elif x:", 7),
        ("        continue", 7),
        ("    else:", 5),
        ("        pass", 8),
        ("    while x > 1:", 9),
        ("        abs(x)", 10),
        ("    for i in r:", 11),
        ("        pass", 12),
        ("    else:", 11),
        ("        return x", 13),
        ("    return", 14),
    ]
