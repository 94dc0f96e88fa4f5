"""The users' online test fields on drawn logic: kept per user and drawing across a new
store (a restart of the PADT), and what a page may send refused with the reason."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from backend.engineering.logic_fields import (
    FARTHEST,
    MAX_FIELDS,
    Field,
    FieldError,
    LogicFields,
    field,
)


def test_fields_are_kept_per_user_and_drawing(tmp_path: Path) -> None:
    path = tmp_path / "logic-fields.json"
    store = LogicFields(path)
    store.put("ann", "Counter", (field("count", 10, 20), field("t1.Q", -5.5, 300)))
    store.put("bob", "counter", (field("blink", 0, 0),))
    again = LogicFields(path)  # the PADT started again
    assert again.of("ann", "COUNTER") == (Field("count", 10.0, 20.0), Field("t1.Q", -5.5, 300.0))
    assert again.of("bob", "Counter") == (Field("blink", 0.0, 0.0),)
    assert again.of("ann", "LampRung") == ()
    again.put("ann", "Counter", ())  # the last one removed: the drawing is forgotten
    assert LogicFields(path).of("ann", "Counter") == ()
    assert path.stat().st_mode & 0o077 == 0  # the owner's only


@pytest.mark.parametrize(
    ("variable", "x", "y", "reason"),
    [
        ("", 0, 0, "a field shows a variable"),
        ("count; DELETE", 0, 0, "a field shows a variable"),
        ("<script>", 0, 0, "a field shows a variable"),
        ("x" * 300, 0, 0, "a field shows a variable"),
        ("count", math.nan, 0, "within 50000 units"),
        ("count", 0, FARTHEST + 1, "within 50000 units"),
        ("count", True, 0, "within 50000 units"),
        ("count", "12", 0, "within 50000 units"),
    ],
)
def test_what_a_page_sends_is_checked(variable: object, x: object, y: object, reason: str) -> None:
    with pytest.raises(FieldError, match=reason):
        field(variable, x, y)  # type: ignore[arg-type]


def test_too_many_fields_are_refused_and_a_broken_file_loses_only_what_does_not_read(
    tmp_path: Path,
) -> None:
    store = LogicFields(tmp_path / "f.json")
    with pytest.raises(FieldError, match=f"at most {MAX_FIELDS} fields"):
        store.put("ann", "Counter", tuple(field("count", n, n) for n in range(MAX_FIELDS + 1)))
    path = tmp_path / "edited.json"
    entries = [{"variable": "count", "x": 1, "y": 2}, {"variable": "a b", "x": 1, "y": 2}, 7]
    path.write_text(json.dumps({"ann": {"COUNTER": entries}, "bob": "nothing"}))
    assert LogicFields(path).of("ann", "Counter") == (Field("count", 1.0, 2.0),)
