"""The message of a publication of the exchange between resources: what the publisher
encodes, and what a subscriber reads of it, every byte checked (it comes from the bus).

`{"resource": R, "publication": P, "running": bool, "key": public key, "values": {name:
[type, value]}}`, canonical JSON; signed and stamped as every publication of a resource
(`runtime/contract/signatures.py`). A non-finite REAL travels as the text `inf`, `-inf` or
`nan`, as strict JSON cannot hold it.
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass
from typing import Any

from runtime.contract.exchange import MAX_MESSAGE_BYTES, MAX_VARIABLES, ExchangePoint
from runtime.contract.outside_json import JsonRefused, read_json
from runtime.contract.values import ValueRejected, base_type, jsonable, representation_of

_NON_FINITE = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}
_SCALARS = (bool, int, float, str)
_REALS = ("REAL", "LREAL")


class MessageRefused(ValueError):
    """A message a subscriber does not take; the text says why."""


@dataclass(frozen=True)
class Message:
    resource: str
    publication: str
    running: bool
    key: str  # the publisher's public key (base64)
    values: dict[str, list[Any]]  # by name as sent: [type, value], each checked a scalar

    @functools.cached_property
    def folded(self) -> dict[str, list[Any]]:
        """The values by upper-case name: ST names are the same in any case (made only
        when a subscriber names a value in another case than the publisher)."""
        return {name.upper(): entry for name, entry in self.values.items()}


def encode(
    resource: str, publication: str, running: bool, key: str, values: list[tuple[str, str, Any]]
) -> bytes:
    """`values`: (name, type, value) of each published variable."""
    body = {
        "key": key,
        "publication": publication,
        "resource": resource,
        "running": running,
        "values": {name: [type_, jsonable(value)] for name, type_, value in values},
    }
    # in the order made (the publication's variables are sorted): the bytes are signed as
    # they are, and sorting a thousand keys again would only cost the I/O thread
    return json.dumps(body, separators=(",", ":")).encode()


def decode(payload: bytes) -> Message:
    """The message checked in shape: every value a `[type, scalar]` pair, so that nothing
    in it is nested (no walk of its depth is needed: json.loads' own recursion is caught)."""
    try:
        data = read_json(payload, "the exchange message", MAX_MESSAGE_BYTES, max_depth=None)
    except JsonRefused as exc:
        raise MessageRefused(str(exc)) from None
    if not isinstance(data, dict):
        raise MessageRefused("the message is no JSON object")
    resource, publication = data.get("resource"), data.get("publication")
    running, key, values = data.get("running"), data.get("key"), data.get("values")
    if not (isinstance(resource, str) and isinstance(publication, str) and isinstance(key, str)):
        raise MessageRefused("the message does not name its resource, publication and key")
    if not isinstance(running, bool) or not isinstance(values, dict):
        raise MessageRefused("the message has no state or no values")
    if len(values) > MAX_VARIABLES:
        raise MessageRefused(f"the message holds more than {MAX_VARIABLES} values")
    for name, entry in values.items():
        if (
            type(entry) is not list
            or len(entry) != 2
            or type(entry[0]) is not str
            or type(entry[1]) not in _SCALARS
        ):
            raise MessageRefused(f"value '{name[:64]}' is not [type, value]")
    return Message(resource, publication, running, key, values)


def point_value(message: Message, point: ExchangePoint) -> Any:
    """The value of `point` in `message` as its variable holds it; MessageRefused when the
    message has none, or one of another type or that the variable cannot hold."""
    entry = message.values.get(point.source) or message.folded.get(point.source.upper())
    if entry is None:
        raise MessageRefused(f"the publication has no value '{point.source}'")
    sent_type, value = entry
    if sent_type != point.type:  # the same name is the same type; else compare the bases
        wanted = base_type(point.type)[0]
        if base_type(sent_type)[0] != wanted:
            raise MessageRefused(
                f"'{point.source}' comes as {sent_type[:40]}, '{point.variable}' is {point.type}"
            )
    if type(value) is str and value in _NON_FINITE and base_type(point.type)[0] in _REALS:
        value = _NON_FINITE[value]
    try:
        return representation_of(point.type)(value)
    except ValueRejected as exc:
        raise MessageRefused(f"'{point.source}' for '{point.variable}': {exc}") from None
