"""What a project tree shows: the POUs by kind, the data types and the global variable
lists of each file (from its tokens, so that a file with a syntax error keeps its entries
while it is being typed), and from padt.toml the resource with its program instances and
settings, the Modbus devices, and the PES accounts by name and level (never a hash).

A file's outline is kept by its content hash: opening the tree again reads only the files
that changed since, so that a project of thousands of POUs (OSCAT) opens fast.
"""

from __future__ import annotations

import threading
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from backend.compiler.language.tokens import declarations, lex
from backend.compiler.test_functions import is_test_file
from backend.engineering.project import PROJECT_FILE
from backend.engineering.project_access import READ, Editor, require
from backend.engineering.project_files import FileText, ProjectFile, folder_files, folder_text
from backend.engineering.project_shelf import ProjectShelf
from runtime.contract.refusal import Refusal

POU_KINDS = ("PROGRAM", "FUNCTION_BLOCK", "FUNCTION", "INTERFACE")
MAX_CACHED_OUTLINES = 8_192


@dataclass(frozen=True)
class TreeItem:
    name: str
    kind: str  # PROGRAM, FUNCTION_BLOCK, FUNCTION, INTERFACE, TYPE, VAR_GLOBAL
    file: str
    line: int
    detail: str = ""  # a FUNCTION's return type, a type's kind (STRUCT, enum, ...)


def in_tests(item: TreeItem) -> bool:
    """Whether a declaration is one of the project's tests' (a file below its `test/`
    folder, docs/testing.md): shown apart from the configuration's."""
    return is_test_file(item.file)


@dataclass(frozen=True)
class FileOutline:
    path: str
    hash: str
    items: tuple[TreeItem, ...]


@dataclass(frozen=True)
class ProgramInstance:
    name: str
    pou: str
    id: int | None
    priority: int | None


@dataclass(frozen=True)
class ResourceNode:
    name: str
    settings: dict[str, Any]  # target_cycle_ms, watchdog_ms, ... as padt.toml has them
    programs: tuple[ProgramInstance, ...]


@dataclass(frozen=True)
class ModbusDeviceNode:
    name: str
    host: str
    port: int | None
    points: int


@dataclass(frozen=True)
class AccountNode:
    name: str
    level: str


@dataclass(frozen=True)
class ProjectTree:
    project: str  # its name on the shelf (the folder's name otherwise)
    files: tuple[ProjectFile, ...]
    pous: tuple[TreeItem, ...]  # by kind (POU_KINDS order), then name
    types: tuple[TreeItem, ...]
    globals: tuple[TreeItem, ...]  # one per file with VAR_GLOBAL, named after the file
    resource: ResourceNode | None
    modbus: tuple[ModbusDeviceNode, ...]
    accounts: tuple[AccountNode, ...]  # the PES accounts by name and level, never a hash
    problems: tuple[str, ...] = field(default=())  # files that cannot be read, a bad padt.toml


class _Outlines:
    """Outlines by (path, hash), shared by every tree; the oldest dropped past the limit."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._known: dict[tuple[str, str], FileOutline] = {}

    def of(self, file: FileText) -> FileOutline:
        key = (file.path, file.hash)
        with self._lock:
            known = self._known.get(key)
        if known is not None:
            return known
        outline = file_outline(file)
        with self._lock:
            if len(self._known) >= MAX_CACHED_OUTLINES:
                self._known.pop(next(iter(self._known)))
            self._known[key] = outline
        return outline


_OUTLINES = _Outlines()


def file_outline(file: FileText) -> FileOutline:
    """The declarations of one .st file, from its tokens and the blocks their keywords
    open (the language services' lexer): the tree lists a file's POUs while it does not
    parse, as it is being typed (the editor's problems say why), and OSCAT's 800 POUs
    are listed in a fifth of the time a parse takes."""
    lexed = lex(file.text)
    items: list[TreeItem] = []
    for index, span in enumerate(lexed.spans):
        top = span.parent < 0 or lexed.spans[span.parent].kind in ("CONFIGURATION", "RESOURCE")
        if not top:
            continue
        line = span.start[0]
        if span.kind in POU_KINDS and span.name_token >= 0:
            name = lexed.tokens[span.name_token]
            detail = ""
            after = lexed.tokens[span.name_token + 1 : span.name_token + 3]
            if span.kind == "FUNCTION" and len(after) == 2 and after[0].text == ":":
                detail = after[1].text
            items.append(TreeItem(name.text, span.kind, file.path, line, detail))
        elif span.kind == "TYPE":
            structs = {
                s.name_token for s in lexed.spans if s.parent == index and s.kind == "STRUCT"
            }
            for name_index, type_text in declarations(lexed, index):
                name = lexed.tokens[name_index]
                kind = "Struct" if name_index in structs else _type_kind(type_text)
                items.append(TreeItem(name.text, "TYPE", file.path, name.line, kind))
        elif span.kind == "VAR_GLOBAL":
            count = len(declarations(lexed, index))
            items.append(TreeItem("", "VAR_GLOBAL", file.path, line, f"{count} variables"))
    lists = [i for i in items if i.kind == "VAR_GLOBAL"]
    if lists:  # one global variable list a file, named after it
        stem = file.path.rsplit("/", 1)[-1].removesuffix(".st")
        count = sum(int(i.detail.split()[0]) for i in lists)
        items = [i for i in items if i.kind != "VAR_GLOBAL"]
        items.append(TreeItem(stem, "VAR_GLOBAL", file.path, lists[0].line, f"{count} variables"))
    return FileOutline(file.path, file.hash, tuple(items))


def _type_kind(type_text: str) -> str:
    """What a TYPE declares, in a word: Enum, Array, String, or the type it names."""
    text = type_text.strip()
    if text.startswith("("):
        return "Enum"
    first = text.split("(", 1)[0].split("[", 1)[0].split()[0] if text else ""
    upper = first.upper()
    if upper == "ARRAY":
        return "Array"
    if upper in ("STRING", "WSTRING"):
        return "String"
    if "(" in text and ".." in text:
        return "Subrange"
    return first[:40]


def project_tree(shelf: ProjectShelf, project: str, editor: Editor) -> ProjectTree:
    """The tree of a project on the shelf, for a user who may read it."""
    require(editor, READ)
    return read_tree(shelf.folder(project), project)


def read_tree(folder: Path, name: str | None = None) -> ProjectTree:
    """The tree of a project folder (no level checked: for the services and screens that
    checked it already)."""
    files = folder_files(folder)
    outlines: list[FileOutline] = []
    problems: list[str] = []
    config: dict[str, Any] = {}
    for entry in files:
        try:
            text = folder_text(folder, entry.path)
        except Refusal as refused:
            problems.append(f"{entry.path}: {refused.message}")
            continue
        if entry.kind == "st":
            outlines.append(_OUTLINES.of(text))
        else:
            try:
                config = tomllib.loads(text.text)
            except (tomllib.TOMLDecodeError, RecursionError) as exc:
                problems.append(f"{PROJECT_FILE}: {exc}")
    items = [item for outline in outlines for item in outline.items]
    order = {kind: index for index, kind in enumerate(POU_KINDS)}
    pous = sorted(
        (i for i in items if i.kind in order), key=lambda i: (order[i.kind], *_by_name(i))
    )
    return ProjectTree(
        name if name is not None else folder.name,
        tuple(files),
        tuple(pous),
        tuple(sorted((i for i in items if i.kind == "TYPE"), key=_by_name)),
        tuple(sorted((i for i in items if i.kind == "VAR_GLOBAL"), key=lambda i: i.file)),
        _resource(config),
        _devices(config),
        _accounts(config),
        tuple(problems),
    )


def _by_name(item: TreeItem) -> tuple[str, str]:
    return item.name.casefold(), item.file


def _type_text(ref: Any) -> str:
    name = getattr(ref, "name", None)
    return name if isinstance(name, str) else type(ref).__name__.removesuffix("Type").upper()


def _table(value: Any) -> dict[str, Any]:
    return value if isinstance(value, dict) else {}


def _tables(value: Any) -> list[dict[str, Any]]:
    return [v for v in value if isinstance(v, dict)] if isinstance(value, list) else []


def _int(value: Any) -> int | None:
    return value if isinstance(value, int) and not isinstance(value, bool) else None


def _resource(config: dict[str, Any]) -> ResourceNode | None:
    res = _table(config.get("resource"))
    if not res:
        return None
    settings = {
        k: v
        for k, v in sorted(res.items())
        if k not in ("name", "program", "user", "safe_values") and not isinstance(v, dict | list)
    }
    programs = tuple(
        ProgramInstance(
            str(p.get("name", "")),
            str(p.get("pou", p.get("name", ""))),
            _int(p.get("id")),
            _int(p.get("priority")),
        )
        for p in _tables(res.get("program"))
    )
    return ResourceNode(str(res.get("name", "")), settings, programs)


def _devices(config: dict[str, Any]) -> tuple[ModbusDeviceNode, ...]:
    return tuple(
        ModbusDeviceNode(
            str(d.get("name", "")),
            str(d.get("host", "")),
            _int(d.get("port")),
            len(_tables(d.get("point"))),
        )
        for d in _tables(_table(config.get("modbus")).get("device"))
    )


def _accounts(config: dict[str, Any]) -> tuple[AccountNode, ...]:
    users = _tables(_table(config.get("resource")).get("user"))
    found = (AccountNode(str(u.get("name", "")), str(u.get("level", ""))) for u in users)
    return tuple(sorted(found, key=lambda a: a.name))
