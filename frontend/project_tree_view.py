"""The project tree in the left panel: the project as `backend/engineering/project_tree.py`
reads it, drawn as folding groups (POUs by kind, data types, global variable lists, the
declarations of the test files apart from them, the resource with its program instances,
Modbus, accounts). Each entry carries `data-tree`;
a click on it is reported by the page script (frontend/page_clicks.py) and read back with
`entry_of`, as untrusted text. The tree is read on a thread of its own (OSCAT's project
takes a second and a half the first time) and again every few seconds: what another tool
changed on disk shows."""

from __future__ import annotations

import html
import threading
from dataclasses import dataclass

from backend.engineering.project_access import Editor
from backend.engineering.project_shelf import ProjectShelf
from backend.engineering.project_tree import ProjectTree, in_tests, project_tree
from runtime.contract.refusal import Refusal

LOOK_AGAIN_S = 2.0  # how often the folder is looked at for files changed by other tools
OPEN_UP_TO = 40  # a group of more entries starts folded (OSCAT has 400 functions)
KINDS = {
    "PROGRAM": "Programs",
    "FUNCTION_BLOCK": "Function blocks",
    "FUNCTION": "Functions",
    "INTERFACE": "Interfaces",
}
_ROW = "padding:1px 4px;cursor:pointer;white-space:nowrap;overflow:hidden;text-overflow:ellipsis"
_NOTE = "color:#868e96;font-size:0.85em"


@dataclass(frozen=True)
class Entry:
    """What a click in the tree chose: a place in a file, or a part of the settings."""

    kind: str  # "file" (with file and line), "resource", "program", "modbus", "account"
    name: str
    file: str = ""
    line: int = 0


class TreeReader:
    """Reads one project's tree on a thread of its own, and again every few seconds (a
    file changed by another tool shows; unchanged files are not parsed again); the
    refresher takes the latest tree without waiting."""

    def __init__(self, shelf: ProjectShelf, project: str, editor: Editor) -> None:
        self._of = (shelf, project, editor)
        self._lock = threading.Lock()
        self._tree: ProjectTree | str | None = None  # a refusal's message
        self._version = 0
        self._stop = threading.Event()
        self._again = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True, name="project-tree")
        self._thread.start()

    def latest(self) -> tuple[int, ProjectTree | str | None]:
        with self._lock:
            return self._version, self._tree

    def read_again(self) -> None:
        """After an edit made here: at once, not at the next look."""
        self._again.set()

    def close(self) -> None:
        self._stop.set()
        self._again.set()

    def _run(self) -> None:
        while not self._stop.is_set():
            tree: ProjectTree | str
            try:
                tree = project_tree(*self._of)
            except Refusal as refused:
                tree = refused.message
            with self._lock:
                if tree != self._tree:
                    self._tree, self._version = tree, self._version + 1
            self._again.wait(LOOK_AGAIN_S)
            self._again.clear()


def entry_of(text: str) -> Entry | None:
    """A tree entry as the page reported it (`data-tree`); None for anything else."""
    kind, _, rest = text.partition(":")
    if kind == "file":
        name, _, place = rest.rpartition("@")
        file, _, line = place.rpartition(":")
        if name and file and line.isdigit():
            return Entry("file", name, file, int(line))
        return None
    if kind in ("resource", "program", "modbus", "account") and rest:
        return Entry(kind, rest)
    return None


def render(tree: ProjectTree | str | None, chosen: Entry | None) -> str:
    if tree is None or isinstance(tree, str):
        words = html.escape(tree or "reading the project ...")
        return f'<div data-testid="project-tree" style="{_NOTE}">{words}</div>'
    groups: list[str] = []
    pous = [i for i in tree.pous if not in_tests(i)]
    types = [t for t in tree.types if not in_tests(t)]
    for kind, title in KINDS.items():
        rows = [_file_row(i.name, i.file, i.line, chosen) for i in pous if i.kind == kind]
        groups.append(_group(title, f"pous-{kind.lower()}", rows))
    rows = [_file_row(t.name, t.file, t.line, chosen) for t in types]
    groups.append(_group("Data types", "types", rows))
    rows = [_file_row(g.name, g.file, g.line, chosen) for g in tree.globals if not in_tests(g)]
    groups.append(_group("Global variables", "globals", rows))
    # the suites and helpers of test/ (padt test's), which no download holds
    tests = sorted(
        (i for i in (*tree.pous, *tree.types, *tree.globals) if in_tests(i)),
        key=lambda i: (i.file, i.line),
    )
    rows = [_file_row(i.name, i.file, i.line, chosen) for i in tests]
    groups.append(_group("Tests (test/)", "tests", rows))
    resource = []
    if tree.resource is not None:
        name = tree.resource.name
        resource.append(_row("resource", name, f"Resource {name}", chosen))
        for program in tree.resource.programs:
            words = f"{program.name} : {program.pou}"
            if program.priority is not None:
                words += f" (priority {program.priority})"
            resource.append(_row("program", program.name, words, chosen, indent=1))
    groups.append(_group("Resource", "resource", resource))
    modbus = [
        _row("modbus", d.name, f"{d.name} at {d.host}:{d.port} ({d.points} points)", chosen)
        for d in tree.modbus
    ]
    groups.append(_group("Modbus devices", "modbus", modbus))
    accounts = [_row("account", a.name, f"{a.name} ({a.level})", chosen) for a in tree.accounts]
    groups.append(_group("Accounts", "accounts", accounts))
    problems = "".join(
        f'<div style="color:#c92a2a;font-size:0.85em">{html.escape(p)}</div>' for p in tree.problems
    )
    counts = f"{len(pous)} POUs, {len(types)} types, {len(tree.files)} files"
    return (
        f'<div data-testid="project-tree" style="font-size:0.9em">'
        f'<div style="{_NOTE}">{html.escape(tree.project)}: {counts}</div>'
        f'<div style="max-height:40vh;overflow:auto">{"".join(groups)}</div>{problems}</div>'
    )


def _group(title: str, testid: str, rows: list[str]) -> str:
    opened = " open" if rows and len(rows) <= OPEN_UP_TO else ""
    body = "".join(rows) or f'<div style="{_NOTE};padding-left:14px">none</div>'
    return (
        f'<details data-testid="tree-{testid}"{opened}><summary style="cursor:pointer">'
        f'<b>{html.escape(title)}</b> <span style="{_NOTE}">{len(rows)}</span></summary>'
        f"{body}</details>"
    )


def _file_row(name: str, file: str, line: int, chosen: Entry | None) -> str:
    entry = Entry("file", name, file, line)
    return _tagged(f"file:{name}@{file}:{line}", html.escape(name), entry == chosen, 1)


def _row(kind: str, name: str, words: str, chosen: Entry | None, indent: int = 0) -> str:
    picked = chosen is not None and chosen.kind == kind and chosen.name == name
    return _tagged(f"{kind}:{name}", html.escape(words), picked, indent + 1)


def _tagged(tag: str, words: str, picked: bool, indent: int) -> str:
    background = "background:#d0ebff;" if picked else ""
    return (
        f'<div data-tree="{html.escape(tag)}" title="{words}" '
        f'style="{_ROW};{background}padding-left:{indent * 14}px">{words}</div>'
    )
