"""The users' online test fields on drawn logic: each field a variable shown with its live
value at a place of an FBD or LD drawing (SILworX puts its online test fields in the logic).
A field belongs to the drawing of a POU, so it shows on every instance of it; its variable
is named as in the POU (`count`, `t1.Q`, a global `blink`). The PADT keeps them per user
(not the browser), all users' in one file beside the watch lists. What a page sends is
untrusted: every value is checked against its limits before it is kept."""

from __future__ import annotations

import json
import math
import re
import threading
from dataclasses import asdict, dataclass
from pathlib import Path

from runtime.contract.outside_json import MIB, read_json_file
from runtime.contract.private_files import write_private

MAX_FIELDS = 64  # on one drawing
MAX_DRAWINGS = 256  # per user
MAX_NAME = 256  # characters of a POU's name or a field's variable
FARTHEST = 50_000  # drawing units from the origin (TC6 sheets: a few 1,000)
MAX_FILE_BYTES = 16 * MIB
_VARIABLE = re.compile(r"[A-Za-z_]\w*(?:\[\d+(?:,\d+)*\])?(?:\.[A-Za-z_]\w*(?:\[\d+(?:,\d+)*\])?)*")


class FieldError(ValueError):
    """A field the store does not take; the message says why."""


@dataclass(frozen=True)
class Field:
    variable: str  # as named in the POU
    x: float  # where its box's top left corner stands, in the drawing's units
    y: float


def field(variable: str, x: float, y: float) -> Field:
    """A field checked: a variable's name, a place on a sheet; FieldError says what not."""
    name = variable.strip() if isinstance(variable, str) else ""
    if not name or len(name) > MAX_NAME or not _VARIABLE.fullmatch(name):
        raise FieldError(
            f"a field shows a variable, named as in the POU (`count`, `t1.Q`): {name!r}"
        )
    for coordinate in (x, y):
        number = isinstance(coordinate, (int, float)) and not isinstance(coordinate, bool)
        if not number or not math.isfinite(coordinate) or abs(coordinate) > FARTHEST:
            raise FieldError(f"a field's place is within {FARTHEST} units of the sheet's origin")
    return Field(name, float(x), float(y))


class LogicFields:
    """The store: a JSON file `{user: {POU: [field, ...]}}`, read once and written whole
    (owner-only) on each change. A lock, because the browsers of all users share it."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._lock = threading.Lock()
        self._fields: dict[str, dict[str, tuple[Field, ...]]] = _read(path)

    def of(self, user: str, pou: str) -> tuple[Field, ...]:
        with self._lock:
            return self._fields.get(user, {}).get(pou.upper(), ())

    def put(self, user: str, pou: str, fields: tuple[Field, ...]) -> None:
        """The fields of a drawing, in place of those it had."""
        if len(fields) > MAX_FIELDS:
            raise FieldError(f"at most {MAX_FIELDS} fields on a drawing")
        checked = tuple(field(f.variable, f.x, f.y) for f in fields)
        with self._lock:
            drawings = dict(self._fields.get(user, {}))
            if checked:
                drawings[pou.upper()] = checked
            else:
                drawings.pop(pou.upper(), None)
            if len(drawings) > MAX_DRAWINGS:
                raise FieldError(f"fields are kept on at most {MAX_DRAWINGS} drawings")
            self._fields[user] = drawings
            data = {
                name: {key: [asdict(f) for f in kept] for key, kept in sorted(mine.items())}
                for name, mine in sorted(self._fields.items())
            }
            self.path.parent.mkdir(parents=True, exist_ok=True)
            write_private(self.path, json.dumps(data, indent=1).encode("utf-8"))


def _read(path: Path) -> dict[str, dict[str, tuple[Field, ...]]]:
    """The file as it was left; a missing file is no fields. A field that does not read is
    left out, never a failure of the UI."""
    if not path.exists():
        return {}
    try:
        data = read_json_file(path, MAX_FILE_BYTES)
    except ValueError as exc:
        raise FieldError(f"{path} is not a file of fields: {exc}") from None
    if not isinstance(data, dict):
        raise FieldError(f"{path} is not a file of fields: not a JSON object")
    found: dict[str, dict[str, tuple[Field, ...]]] = {}
    for user, drawings in data.items():
        if not isinstance(drawings, dict):
            continue
        mine: dict[str, tuple[Field, ...]] = {}
        for pou, entries in list(drawings.items())[:MAX_DRAWINGS]:
            if not isinstance(entries, list) or len(str(pou)) > MAX_NAME:
                continue
            kept = []
            for entry in entries[:MAX_FIELDS]:
                try:
                    kept.append(field(entry["variable"], entry["x"], entry["y"]))
                except (FieldError, TypeError, KeyError):
                    continue
            if kept:
                mine[str(pou).upper()] = tuple(kept)
        found[str(user)] = mine
    return found
