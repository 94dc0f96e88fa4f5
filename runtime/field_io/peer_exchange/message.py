"""The message of a publication of the exchange between resources: what the publisher
encodes, and what a subscriber reads of it, every byte checked (it comes from the bus).

`{"resource": R, "publication": P, "running": bool, "key": public key, "values": {name:
[type, value]}}`, canonical JSON; signed and stamped as every publication of a resource
(`runtime/contract/signatures.py`). A non-finite REAL travels as the text `inf`, `-inf` or
`nan`, as strict JSON cannot hold it.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

from runtime.contract.exchange import MAX_MESSAGE_BYTES, MAX_VARIABLES, ExchangePoint
from runtime.contract.outside_json import JsonRefused, read_json
from runtime.contract.values import ValueRejected, base_type, jsonable, representation

_NON_FINITE = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}


class MessageRefused(ValueError):
    """A message a subscriber does not take; the text says why."""


@dataclass(frozen=True)
class Message:
    resource: str
    publication: str
    running: bool
    key: str  # the publisher's public key (base64)
    values: dict[str, tuple[str, Any]]  # by upper-case name: (type, value as sent)


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
    return json.dumps(body, sort_keys=True, separators=(",", ":")).encode()


def decode(payload: bytes) -> Message:
    try:
        data = read_json(payload, "the exchange message", MAX_MESSAGE_BYTES, max_depth=4)
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
    taken: dict[str, tuple[str, Any]] = {}
    for name, entry in values.items():
        if not isinstance(entry, list) or len(entry) != 2 or not isinstance(entry[0], str):
            raise MessageRefused(f"value '{name[:64]}' is not [type, value]")
        taken[name.upper()] = (entry[0], entry[1])
    return Message(resource, publication, running, key, taken)


def point_value(message: Message, point: ExchangePoint) -> Any:
    """The value of `point` in `message` as its variable holds it; MessageRefused when the
    message has none, or one of another type or that the variable cannot hold."""
    entry = message.values.get(point.source.upper())
    if entry is None:
        raise MessageRefused(f"the publication has no value '{point.source}'")
    sent_type, value = entry
    wanted = base_type(point.type)[0]
    if base_type(sent_type)[0] != wanted:
        raise MessageRefused(
            f"'{point.source}' comes as {sent_type[:40]}, '{point.variable}' is {point.type}"
        )
    if wanted in ("REAL", "LREAL") and isinstance(value, str) and value in _NON_FINITE:
        value = _NON_FINITE[value]
    try:
        return representation(point.type, value)
    except ValueRejected as exc:
        raise MessageRefused(f"'{point.source}' for '{point.variable}': {exc}") from None
