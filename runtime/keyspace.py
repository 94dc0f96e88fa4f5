"""The Zenoh key space, version 1 (documented in docs/architecture.md).

padt/v1/res/<resource>/cmd      queryable: JSON command in, JSON reply out
padt/v1/res/<resource>/status   published on change and every second
padt/v1/res/<resource>/values   live values, published every cycle
padt/v1/res/<resource>/alive    liveliness token while the runtime process lives
"""

from __future__ import annotations

import re

ROOT = "padt/v1"
_RESOURCE_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_-]{0,63}$")


def valid_resource_name(name: str) -> bool:
    return bool(_RESOURCE_NAME.match(name))


def command_key(resource: str) -> str:
    return f"{ROOT}/res/{resource}/cmd"


def status_key(resource: str) -> str:
    return f"{ROOT}/res/{resource}/status"


def values_key(resource: str) -> str:
    return f"{ROOT}/res/{resource}/values"


def alive_key(resource: str) -> str:
    return f"{ROOT}/res/{resource}/alive"
