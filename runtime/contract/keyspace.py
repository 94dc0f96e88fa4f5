"""The Zenoh key space, version 2 (documented in docs/architecture.md).

padt/v2/res/<resource>/cmd      queryable: JSON command in, JSON reply out
padt/v2/res/<resource>/status   published on change and every second
padt/v2/res/<resource>/alive    liveliness token while the runtime process lives
padt/v2/res/<resource>/events   every event of the event log, in order (reliable)
padt/v2/res/<resource>/watch/<id>     the values of watch set <id>, once per its period
padt/v2/res/<resource>/watchers/<id>  liveliness token of the client that owns watch set <id>
padt/v2/res/<resource>/exchange/<name>  publication <name> of the variable exchange between
                                        resources (docs/exchange.md)
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Callable

from runtime.contract.refusal import Refusal

ROOT = "padt/v2"  # 2: signed login challenges, signed logout, stamped publications
# A name in a key is one plain chunk: no `/` (a level), `*`, `**` or `$*` (wildcards),
# which would make a key expression that reaches other resources' keys
RESOURCE_NAME_RULE = "a letter or _, then up to 63 letters, digits, _ or -"
WATCH_ID_RULE = "1 to 64 of A-Z a-z 0-9 _ -"
WATCH_ID_PATTERN = r"[A-Za-z0-9_-]{1,64}"
_RESOURCE_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_-]{0,63}")
_WATCH_ID = re.compile(WATCH_ID_PATTERN)
_PLACEHOLDER = "_"  # a name that stands for any resource while `any_resource` makes a key


def resource_name_problem(name: str) -> str | None:
    """Why `name` cannot name a resource, or None when it can."""
    if _RESOURCE_NAME.fullmatch(name):
        return None
    return (
        f"resource name '{name[:80]}' is not a plain identifier ({RESOURCE_NAME_RULE}): "
        "it is part of the resource's Zenoh keys"
    )


def resource_name(name: str) -> str:
    """`name` when it can name a resource, else Refusal `bad_name`: every key of this
    module is made through here, so none of them is ever a wildcard."""
    problem = resource_name_problem(name)
    if problem is not None:
        raise Refusal("bad_name", problem)
    return name


def resource_argument(text: str) -> str:
    """`--resource NAME` of the runtime and of every client (argparse type): a name that
    is no plain identifier ends the command before it starts or asks anything."""
    problem = resource_name_problem(text)
    if problem is not None:
        raise argparse.ArgumentTypeError(problem)
    return text


def watch_id(chunk: str) -> str:
    """`chunk` when it can be a watch set id, else Refusal `bad_name`."""
    if not _WATCH_ID.fullmatch(chunk):
        raise Refusal("bad_name", f"watch set id '{chunk[:80]}' is not {WATCH_ID_RULE}")
    return chunk


def _key(resource: str, rest: str) -> str:
    return f"{ROOT}/res/{resource_name(resource)}/{rest}"


def command_key(resource: str) -> str:
    return _key(resource, "cmd")


def status_key(resource: str) -> str:
    return _key(resource, "status")


def watch_key(resource: str, watch_set: str) -> str:
    return _key(resource, f"watch/{watch_id(watch_set)}")


def watches_key_expr(resource: str) -> str:
    """The values of every watch set of a resource (a third party listening in)."""
    return _key(resource, "watch/*")


def watcher_key(resource: str, watch_set: str) -> str:
    return _key(resource, f"watchers/{watch_id(watch_set)}")


def exchange_key(resource: str, publication: str) -> str:
    """A publication of the variable exchange between resources; its name follows the
    rule of watch set ids (a plain chunk)."""
    return _key(resource, f"exchange/{watch_id(publication)}")


def events_key(resource: str) -> str:
    return _key(resource, "events")


def alive_key(resource: str) -> str:
    return _key(resource, "alive")


def any_resource(key_for: Callable[[str], str]) -> str:
    """The key expression of `key_for` over all resources, e.g. any_resource(alive_key):
    made for a placeholder name, which is then replaced by the wildcard (the wildcard
    itself is refused as a name)."""
    placed = f"{ROOT}/res/{_PLACEHOLDER}/"
    return f"{ROOT}/res/*/" + key_for(_PLACEHOLDER).removeprefix(placed)


def resource_of(key: str) -> str:
    """The resource named in a key of this space."""
    return key.removeprefix(f"{ROOT}/res/").split("/", 1)[0]
