"""The users' workspace layouts: how wide each user left the navigation and the work
panel, whether either was folded away, and the project and files open in the editor, so
that the next login, from any browser, finds the workspace as it was left. The PADT keeps
them (not the browser), all users' in one file, like the watch lists. What a page reports
is untrusted: each value is checked against its limits before it is kept."""

from __future__ import annotations

import json
import threading
from dataclasses import asdict, dataclass, field
from pathlib import Path

from runtime.contract.outside_json import MIB, read_json_file
from runtime.contract.private_files import write_private

MIN_WIDTH, MAX_WIDTH = 120, 4000  # pixels: what a panel of a browser window can be
MAX_OPEN_FILES = 20
MAX_PATH = 512
MAX_FILE_BYTES = 16 * MIB


class LayoutError(ValueError):
    """A layout the store does not take; the message says why."""


@dataclass(frozen=True)
class Layout:
    navigation_width: int | None = None  # None: the workspace's own choice
    work_width: int | None = None
    navigation_folded: bool = False
    work_folded: bool = False
    project: str = ""  # the project open in the editor
    open_files: tuple[str, ...] = field(default=())  # its files in tabs, in order


def checked(layout: Layout) -> Layout:
    """The layout if every value is within its limits; LayoutError says which is not."""
    for name in ("navigation_width", "work_width"):
        width = getattr(layout, name)
        number = isinstance(width, int) and not isinstance(width, bool)
        if width is not None and not (number and MIN_WIDTH <= width <= MAX_WIDTH):
            raise LayoutError(f"{name} must be from {MIN_WIDTH} to {MAX_WIDTH} pixels")
    for name in ("navigation_folded", "work_folded"):
        if not isinstance(getattr(layout, name), bool):
            raise LayoutError(f"{name} must be true or false")
    if not isinstance(layout.project, str) or len(layout.project) > MAX_PATH:
        raise LayoutError(f"a project name has at most {MAX_PATH} characters")
    files = layout.open_files
    if len(files) > MAX_OPEN_FILES:
        raise LayoutError(f"at most {MAX_OPEN_FILES} open files are kept")
    if any(not isinstance(f, str) or not f or len(f) > MAX_PATH for f in files):
        raise LayoutError(f"an open file's path has 1 to {MAX_PATH} characters")
    return layout


class UserLayouts:
    """The store: a JSON file `{user: layout}`, read once and written whole (owner-only) on
    each change. A lock, because the browsers of all users share it."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._lock = threading.Lock()
        self._layouts: dict[str, Layout] = _read(path)

    def of(self, user: str) -> Layout:
        with self._lock:
            return self._layouts.get(user, Layout())

    def put(self, user: str, layout: Layout) -> None:
        checked(layout)
        with self._lock:
            if self._layouts.get(user) == layout:
                return  # nothing to write
            self._layouts[user] = layout
            data = {name: asdict(kept) for name, kept in sorted(self._layouts.items())}
            self.path.parent.mkdir(parents=True, exist_ok=True)
            write_private(self.path, json.dumps(data, indent=1).encode("utf-8"))


def _read(path: Path) -> dict[str, Layout]:
    """The file as it was left; a missing file is no layouts. A layout that does not read
    is left out (the user gets the workspace's own), never a failure of the UI."""
    if not path.exists():
        return {}
    try:
        data = read_json_file(path, MAX_FILE_BYTES)
    except ValueError as exc:
        raise LayoutError(f"{path} is not a layout file: {exc}") from None
    if not isinstance(data, dict):
        raise LayoutError(f"{path} is not a layout file: not a JSON object")
    layouts = {}
    for user, entry in data.items():
        try:
            files = tuple(entry.get("open_files", ()))
            layouts[str(user)] = checked(Layout(**{**entry, "open_files": files}))
        except (LayoutError, TypeError, AttributeError):
            continue
    return layouts
