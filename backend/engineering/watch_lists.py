"""The users' watch lists: named lists of variables that a user composes in the Online test
and finds again at the next login, from any browser. The PADT keeps them (not the browser,
not the resource), all users' in one file; the lists name variables by their paths, so one
list can serve every resource whose configuration has them."""

from __future__ import annotations

import json
import threading
from dataclasses import dataclass
from pathlib import Path

from runtime.contract.outside_json import MIB, read_json_file
from runtime.contract.private_files import write_private

MAX_LISTS = 50  # per user
MAX_VARIABLES = 20_000  # per list: what one watch set may hold
MAX_LIST_NAME = 64
MAX_PATH = 256
MAX_FILE_BYTES = 256 * MIB  # the file read back: room for the lists of several users


class WatchListError(ValueError):
    """A name or a list the store does not take; the message says why."""


@dataclass(frozen=True)
class WatchList:
    name: str
    variables: tuple[str, ...]


def list_name(text: str) -> str:
    """A list's name as the user typed it, checked."""
    name = " ".join(text.split())
    if not name:
        raise WatchListError("give the list a name")
    if len(name) > MAX_LIST_NAME:
        raise WatchListError(f"a list name has at most {MAX_LIST_NAME} characters")
    return name


def with_variables(variables: tuple[str, ...], added: list[str]) -> tuple[str, ...]:
    """`variables` with `added` at the end, each once, in the order the user added them."""
    seen = set(variables)
    more = [path for path in dict.fromkeys(added) if path not in seen]
    result = variables + tuple(more)
    if len(result) > MAX_VARIABLES:
        raise WatchListError(f"a watch list holds at most {MAX_VARIABLES:,} variables")
    if any(len(path) > MAX_PATH for path in more):
        raise WatchListError(f"a variable path has at most {MAX_PATH} characters")
    return result


def without_variable(variables: tuple[str, ...], removed: str) -> tuple[str, ...]:
    return tuple(path for path in variables if path != removed)


class WatchLists:
    """The store: a JSON file `{user: {list name: [paths]}}`, read once and written whole
    (owner-only) on each change. A lock, because the browsers of all users share it."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._lock = threading.Lock()
        self._lists: dict[str, dict[str, tuple[str, ...]]] = _read(path)

    def of(self, user: str) -> tuple[WatchList, ...]:
        with self._lock:
            lists = self._lists.get(user, {})
            return tuple(WatchList(name, lists[name]) for name in sorted(lists))

    def put(self, user: str, name: str, variables: tuple[str, ...]) -> None:
        """Create or replace the user's list `name`."""
        name = list_name(name)
        with_variables((), list(variables))  # the same limits as adding one by one
        with self._lock:
            lists = self._lists.setdefault(user, {})
            if name not in lists and len(lists) >= MAX_LISTS:
                raise WatchListError(f"a user keeps at most {MAX_LISTS} watch lists")
            lists[name] = tuple(variables)
            self._save()

    def delete(self, user: str, name: str) -> None:
        with self._lock:
            self._lists.get(user, {}).pop(name, None)
            self._save()

    def _save(self) -> None:
        data = {
            user: {name: list(paths) for name, paths in sorted(lists.items())}
            for user, lists in sorted(self._lists.items())
            if lists
        }
        self.path.parent.mkdir(parents=True, exist_ok=True)
        write_private(self.path, json.dumps(data, indent=1).encode("utf-8"))


def _read(path: Path) -> dict[str, dict[str, tuple[str, ...]]]:
    """The file as it was left; a missing file is no lists. A file that is not ours is
    an error to the operator who pointed us at it, not something to overwrite."""
    if not path.exists():
        return {}
    try:
        data = read_json_file(path, MAX_FILE_BYTES)
        return {
            str(user): {str(name): tuple(str(p) for p in paths) for name, paths in lists.items()}
            for user, lists in data.items()
        }
    except (ValueError, AttributeError, TypeError) as exc:
        raise WatchListError(f"{path} is not a watch list file: {exc}") from None
