"""What a subscriber of the exchange between resources makes of the bytes on its key
(runtime/field_io/peer_exchange/message.py): every message that is not what a publisher
of this project sends is refused with a reason (MessageRefused), never an exception of
another kind; a value comes only with its variable's type and range."""

from __future__ import annotations

import json
import math
from typing import Any

import pytest

from runtime.contract.exchange import ExchangePoint
from runtime.field_io.peer_exchange.message import MessageRefused, decode, encode, point_value

KEY = "AAAA"


def _message(values: Any, **fields: Any) -> bytes:
    body = {"resource": "Tank1", "publication": "levels", "running": True, "key": KEY}
    return json.dumps({**body, **fields, "values": values}).encode()


HOSTILE = {
    "not JSON": b"\xff\xfe not json",
    "a list": b"[1, 2, 3]",
    "nested far too deep": b"[" * 100_000 + b"]" * 100_000,
    "too large": b'{"values": {"a": ["INT", 1]}, "pad": "' + b"x" * 300_000 + b'"}',
    "no key": json.dumps({"resource": "Tank1", "publication": "p", "running": True}).encode(),
    "running as text": _message({}, running="yes"),
    "values as a list": _message([["a", "INT", 1]]),
    "a value nested": _message({"a": ["INT", [1, [2]]]}),
    "a value without its type": _message({"a": 1}),
    "a type that is no text": _message({"a": [3, 1]}),
    "three items": _message({"a": ["INT", 1, 2]}),
    "too many values": _message({f"v{i}": ["INT", i] for i in range(1001)}),
}


@pytest.mark.parametrize("payload", HOSTILE.values(), ids=HOSTILE.keys())
def test_a_message_not_made_by_a_publisher_is_refused(payload: bytes) -> None:
    with pytest.raises(MessageRefused):
        decode(payload)


def _point(type_name: str, source: str = "level") -> ExchangePoint:
    return ExchangePoint("fillerLevel", type_name, source, 0)


@pytest.mark.parametrize(
    ("type_name", "sent", "why"),
    [
        ("INT", ["INT", 40_000], "outside the range of INT"),
        ("INT", ["INT", True], "takes an integer"),
        ("INT", ["DINT", 5], "comes as DINT"),
        ("BOOL", ["BOOL", 1], "TRUE or FALSE"),
        ("STRING[4]", ["STRING[80]", "too long"], "at most 4 characters"),
        ("DINT", ["DINT", "inf"], "takes an integer"),
        ("REAL", ["REAL", "1.5"], "takes a number"),
    ],
)
def test_a_value_of_another_type_or_range_is_refused(
    type_name: str, sent: list[Any], why: str
) -> None:
    message = decode(_message({"level": sent}))
    with pytest.raises(MessageRefused, match=why):
        point_value(message, _point(type_name))


def test_values_as_the_variable_holds_them() -> None:
    values = [("Level", "REAL", 1.1), ("ok", "BOOL", True), ("name", "STRING[80]", "tank"),
              ("big", "LREAL", math.inf), ("t", "TIME", 1_500_000_000)]  # fmt: skip
    message = decode(encode("Tank1", "levels", True, KEY, values))
    # REAL rounded to 32 bits, a name in any case, a shorter STRING while the value fits,
    # a non-finite LREAL through its text
    assert point_value(message, _point("REAL", "LEVEL")) == pytest.approx(1.1, rel=1e-7)
    assert point_value(message, _point("BOOL", "ok")) is True
    assert point_value(message, _point("STRING[8]", "name")) == "tank"
    assert point_value(message, _point("LREAL", "big")) == math.inf
    assert point_value(message, _point("TIME", "t")) == 1_500_000_000
    with pytest.raises(MessageRefused, match="has no value 'missing'"):
        point_value(message, _point("INT", "missing"))
