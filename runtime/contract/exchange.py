"""The variable exchange between resources in the artifact, and its message on the bus
(docs/exchange.md).

A resource publishes chosen global variables as named publications, each every
`period_ms`, on `padt/v2/res/<resource>/exchange/<name>`; another resource subscribes to a
publication and takes its values into globals of its own, each with a safe value that
stands while the publisher is stale, stopped or lost. The compiler checks a project's
`[exchange]` settings and writes what it found here; the runtime publishes and subscribes
exactly that.

The message is JSON, signed and stamped as every publication of a resource is
(`signatures.py`): `{"resource", "publication", "running", "key", "values": {name: [type,
value]}}`. `key` is the publisher's public key; a subscriber pins the first one it took
per resource and refuses any other after that.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from runtime.contract.keyspace import resource_name_problem
from runtime.contract.values import ValueRejected, representation

PUBLICATION_NAME = re.compile(r"[A-Za-z0-9_-]{1,64}")  # a plain chunk of a key
MIN_PERIOD_MS, MAX_PERIOD_MS = 10, 60_000
DEFAULT_PERIOD_MS, DEFAULT_TIMEOUT_MS = 100, 1000
MAX_VARIABLES = 1000  # in one publication
MAX_MESSAGE_BYTES = 256 * 1024


@dataclass(frozen=True)
class Published:
    """A global variable in a publication."""

    variable: str  # as declared
    type: str  # its elementary type


@dataclass(frozen=True)
class Publication:
    name: str
    variables: tuple[Published, ...]  # sorted by name
    period_ms: int = DEFAULT_PERIOD_MS


@dataclass(frozen=True)
class ExchangePoint:
    """A global of the subscriber that takes one value of a publication."""

    variable: str  # the subscriber's global, as declared
    type: str  # its elementary type: the publication's value must be of the same
    source: str  # the variable's name in the publication (the publisher's global)
    safe_value: bool | int | float | str = 0  # while the publication is not fresh

    @property
    def is_input(self) -> bool:  # for `RemoteDevices`: every point is one
        return True

    @property
    def input_safe_value(self) -> Any:
        """The safe value as the variable holds it (`exchange_config` checked it fits)."""
        return representation(self.type, self.safe_value)


@dataclass(frozen=True)
class Subscription:
    resource: str  # the publisher
    publication: str
    timeout_ms: int = DEFAULT_TIMEOUT_MS  # no fresh message this long: safe values
    points: tuple[ExchangePoint, ...] = ()  # sorted by variable

    @property
    def name(self) -> str:
        """How events and the status name it."""
        return f"{self.resource}/{self.publication}"


@dataclass(frozen=True)
class ExchangeConfig:
    publications: tuple[Publication, ...] = ()  # sorted by name
    subscriptions: tuple[Subscription, ...] = ()  # sorted by resource, publication

    def __bool__(self) -> bool:
        return bool(self.publications or self.subscriptions)


def exchange_config(data: dict[str, Any]) -> ExchangeConfig:
    """The artifact's `exchange` object back into its dataclasses (KeyError, TypeError when
    it is incomplete or of the wrong types)."""
    return ExchangeConfig(
        publications=tuple(_publication(p) for p in data["publications"]),
        subscriptions=tuple(_subscription(s) for s in data["subscriptions"]),
    )


def _publication(data: dict[str, Any]) -> Publication:
    publication = Publication(
        name=_name(data["name"]),
        variables=tuple(
            Published(_text(v["variable"]), _text(v["type"])) for v in data["variables"]
        ),
        period_ms=_period(data["period_ms"]),
    )
    if len(publication.variables) > MAX_VARIABLES:
        raise TypeError(f"publication '{publication.name}' has more than {MAX_VARIABLES} values")
    return publication


def _subscription(data: dict[str, Any]) -> Subscription:
    subscription = Subscription(
        resource=_resource(data["resource"]),
        publication=_name(data["publication"]),
        timeout_ms=_period(data["timeout_ms"]),
        points=tuple(_point(p) for p in data["points"]),
    )
    return subscription


def _point(data: dict[str, Any]) -> ExchangePoint:
    point = ExchangePoint(
        variable=_text(data["variable"]),
        type=_text(data["type"]),
        source=_text(data["source"]),
        safe_value=data["safe_value"],
    )
    try:
        point.input_safe_value  # noqa: B018 (checked here, so that the driver never raises)
    except ValueRejected as exc:
        raise TypeError(f"the safe value of exchanged '{point.variable}': {exc}") from None
    return point


def _resource(value: Any) -> str:
    """A publisher's name, one plain chunk of a key (never a wildcard that would reach
    other resources' keys)."""
    problem = resource_name_problem(value) if isinstance(value, str) else "no text"
    if problem is not None:
        raise TypeError(f"{value!r} is no resource name: {problem}")
    return str(value)


def _name(value: Any) -> str:
    if not isinstance(value, str) or not PUBLICATION_NAME.fullmatch(value):
        raise TypeError(f"{value!r} is no publication name")
    return value


def _text(value: Any) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{value!r} in the exchange configuration is not text")
    return value


def _period(value: Any) -> int:
    if type(value) is not int or not MIN_PERIOD_MS <= value <= MAX_PERIOD_MS:
        raise TypeError(f"{value!r} is no period of {MIN_PERIOD_MS}..{MAX_PERIOD_MS} ms")
    return value
