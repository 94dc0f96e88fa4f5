"""The Zenoh key space, version 1 (documented in docs/architecture.md).

padt/v1/res/<resource>/cmd      queryable: JSON command in, JSON reply out
padt/v1/res/<resource>/status   published on change and every second
padt/v1/res/<resource>/alive    liveliness token while the runtime process lives
padt/v1/res/<resource>/events   every event of the event log, in order (reliable)
padt/v1/res/<resource>/watch/<id>     the values of watch set <id>, once per its period
padt/v1/res/<resource>/watchers/<id>  liveliness token of the client that owns watch set <id>
"""

from __future__ import annotations

import re
from collections.abc import Callable

ROOT = "padt/v1"
_RESOURCE_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_-]{0,63}$")
_WATCH_ID = re.compile(r"^[A-Za-z0-9_-]{1,64}$")


def valid_resource_name(name: str) -> bool:
    return bool(_RESOURCE_NAME.match(name))


def valid_watch_id(watch_id: str) -> bool:
    """A watch set id is one key chunk: no `/`, `*` or `$`."""
    return bool(_WATCH_ID.match(watch_id))


def command_key(resource: str) -> str:
    return f"{ROOT}/res/{resource}/cmd"


def status_key(resource: str) -> str:
    return f"{ROOT}/res/{resource}/status"


def watch_key(resource: str, watch_id: str) -> str:
    return f"{ROOT}/res/{resource}/watch/{watch_id}"


def watcher_key(resource: str, watch_id: str) -> str:
    return f"{ROOT}/res/{resource}/watchers/{watch_id}"


def watchers_key_expr(resource: str) -> str:
    return f"{ROOT}/res/{resource}/watchers/*"


def watch_id_of(key: str) -> str:
    """The watch set id at the end of a watcher or watch key."""
    return key.rsplit("/", 1)[-1]


def events_key(resource: str) -> str:
    return f"{ROOT}/res/{resource}/events"


def alive_key(resource: str) -> str:
    return f"{ROOT}/res/{resource}/alive"


def any_resource(key_for: Callable[[str], str]) -> str:
    """The key expression of `key_for` over all resources, e.g. any_resource(alive_key)."""
    return key_for("*")


def resource_of(key: str) -> str:
    """The resource named in a key of this space."""
    return key.removeprefix(f"{ROOT}/res/").split("/", 1)[0]
