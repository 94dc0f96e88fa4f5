"""The users' layouts are kept across restarts of the PADT; what is put is checked: a
width no panel can have, an empty path or too many files are not kept, and a damaged
entry of the file is left out."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from backend.engineering.user_layouts import Layout, LayoutError, UserLayouts


def test_a_layout_is_kept_per_user_across_restarts(tmp_path: Path) -> None:
    path = tmp_path / "layouts.json"
    store = UserLayouts(path)
    assert store.of("ann") == Layout()
    mine = Layout(420, 700, False, True, "demo", ("tank.st", "lib/valve.st"))
    store.put("ann", mine)
    again = UserLayouts(path)
    assert again.of("ann") == mine
    assert again.of("bob") == Layout()


@pytest.mark.parametrize(
    "layout",
    [
        Layout(navigation_width=5),
        Layout(work_width=100_000),
        Layout(open_files=("",)),
        Layout(open_files=tuple(f"f{i}.st" for i in range(21))),
        Layout(project="x" * 513),
    ],
)
def test_what_no_workspace_has_is_refused(tmp_path: Path, layout: Layout) -> None:
    with pytest.raises(LayoutError):
        UserLayouts(tmp_path / "layouts.json").put("ann", layout)


def test_a_damaged_entry_is_left_out_and_the_rest_read(tmp_path: Path) -> None:
    path = tmp_path / "layouts.json"
    good = {"navigation_width": 400, "open_files": ["tank.st"]}
    path.write_text(json.dumps({"ann": good, "bob": {"work_width": "wide"}, "eve": 3}))
    store = UserLayouts(path)
    assert store.of("ann") == Layout(navigation_width=400, open_files=("tank.st",))
    assert store.of("bob") == Layout()
    assert store.of("eve") == Layout()
