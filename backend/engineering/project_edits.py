"""Adding, renaming and deleting the declarations of a project, one file each: a PROGRAM,
FUNCTION_BLOCK or FUNCTION, a data type (a STRUCT or an enumeration) or a global variable
list is a new file named after it (`MotorControl.st` for FUNCTION_BLOCK MotorControl),
made from a skeleton that compiles.

A rename changes the declaration, the file's name when it is named after it, and the
program instances of padt.toml that instantiate it; the uses in other files are the
language services' rename (backend/compiler/language). A delete is refused while a
program instance of padt.toml uses the POU. Every change goes through project_files: the
levels, the conflicts, the limits and the audit log are theirs.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from functools import cache

import tomlkit

from backend.compiler.builtins import lookup
from backend.compiler.diagnostics import CompileError
from backend.compiler.language.tokens import KEYWORDS
from backend.compiler.parse import parse_source
from backend.compiler.source import stdlib_sources
from backend.compiler.types import elementary
from backend.engineering.project import PROJECT_FILE
from backend.engineering.project_access import WRITE, Editor, require
from backend.engineering.project_files import (
    Saved,
    delete_file,
    editable_path,
    read_file,
    rename_file,
    save_file,
)
from backend.engineering.project_shelf import ProjectShelf
from backend.engineering.project_tree import project_tree
from runtime.contract.refusal import Refusal

# what a user may add, and the tree kind each becomes
NEW_KINDS = {
    "PROGRAM": "PROGRAM",
    "FUNCTION_BLOCK": "FUNCTION_BLOCK",
    "FUNCTION": "FUNCTION",
    "STRUCT": "TYPE",
    "ENUM": "TYPE",
    "GLOBALS": "VAR_GLOBAL",
}
MAX_NAME = 64
INTEGERS = frozenset(
    [
        "SINT",
        "INT",
        "DINT",
        "LINT",
        "USINT",
        "UINT",
        "UDINT",
        "ULINT",
        "BYTE",
        "WORD",
        "DWORD",
        "LWORD",
    ]
)


@dataclass(frozen=True)
class Declaration:
    """A declaration of the project as an edit finds it: what the tree lists."""

    name: str
    kind: str  # as the tree: PROGRAM, FUNCTION_BLOCK, FUNCTION, INTERFACE, TYPE, VAR_GLOBAL
    file: str
    line: int


def skeleton(kind: str, name: str, return_type: str = "") -> str:
    """The text of a new declaration of `kind` (a key of NEW_KINDS)."""
    match kind:
        case "PROGRAM" | "FUNCTION_BLOCK":
            inputs = "VAR_INPUT\nEND_VAR\nVAR_OUTPUT\nEND_VAR\n" if kind == "FUNCTION_BLOCK" else ""
            return f"{kind} {name}\n{inputs}VAR\nEND_VAR\n\nEND_{kind}\n"
        case "FUNCTION":
            typed = return_type or "BOOL"
            zero = _zero(typed)
            result = f"{name} := {zero};\n" if zero is not None else ""
            declared = f"FUNCTION {name} : {typed}\nVAR_INPUT\nEND_VAR\nVAR\nEND_VAR\n"
            return f"{declared}\n{result}END_FUNCTION\n"
        case "STRUCT":
            return f"TYPE {name} :\nSTRUCT\n  value : INT;\nEND_STRUCT;\nEND_TYPE\n"
        case "ENUM":
            return f"TYPE {name} : (Off, On);\nEND_TYPE\n"
        case "GLOBALS":
            return f"(* global variable list {name} *)\nVAR_GLOBAL\nEND_VAR\n"
    raise Refusal("bad_value", f"cannot add a '{kind}': one of {', '.join(NEW_KINDS)}")


def add_declaration(
    shelf: ProjectShelf,
    project: str,
    kind: str,
    name: str,
    editor: Editor,
    return_type: str = "",
    folder: str = "",
) -> Saved:
    """A new file `[folder/]NAME.st` holding a new declaration. Refused: a name the
    compiler does not take as one, a name or file the project has already."""
    require(editor, WRITE)
    if kind not in NEW_KINDS:
        raise Refusal("bad_value", f"cannot add a '{kind}': one of {', '.join(NEW_KINDS)}")
    _check_name(name)
    if return_type and (
        kind != "FUNCTION" or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", return_type)
    ):
        raise Refusal("bad_value", f"'{return_type[:40]}' is no return type of a FUNCTION")
    text = skeleton(kind, name, return_type)
    _check_parses(name, text, NEW_KINDS[kind] if kind != "GLOBALS" else None)
    path = f"{folder.strip('/')}/{name}.st" if folder.strip("/") else f"{name}.st"
    _free(shelf, project, name, path, editor)
    return save_file(shelf, project, path, text, None, editor, action="create")


def declarations(shelf: ProjectShelf, project: str, editor: Editor) -> list[Declaration]:
    tree = project_tree(shelf, project, editor)
    return [
        Declaration(i.name, i.kind, i.file, i.line)
        for i in (*tree.pous, *tree.types, *tree.globals)
    ]


def rename_declaration(
    shelf: ProjectShelf, project: str, old: str, new: str, editor: Editor
) -> list[Saved]:
    """Rename a POU, a type or a global variable list: its declaration (a FUNCTION also
    where its body assigns its result), its file when named after it, and padt.toml's
    program instances of it. Returns the files written, in order."""
    require(editor, WRITE)
    found = _declaration(shelf, project, old, editor)
    _check_name(new)
    if new.casefold() != old.casefold():
        _free(shelf, project, new, None, editor)
    written = []
    stem = found.file.rsplit("/", 1)[-1].removesuffix(".st")
    if found.kind != "VAR_GLOBAL":
        source = read_file(shelf, project, found.file, editor)
        text = _renamed_in_text(source.text, found, new)
        written.append(save_file(shelf, project, found.file, text, source.hash, editor))
    if stem.casefold() == old.casefold():
        folder = found.file.rpartition("/")[0]
        target = f"{folder}/{new}.st" if folder else f"{new}.st"
        if target != found.file:
            written.append(rename_file(shelf, project, found.file, target, editor))
    if found.kind == "PROGRAM":
        saved = _renamed_in_config(shelf, project, old, new, editor)
        if saved is not None:
            written.append(saved)
    return written


def delete_declaration(shelf: ProjectShelf, project: str, name: str, editor: Editor) -> Saved:
    """Delete the file of a POU, a type or a global variable list. Refused while padt.toml
    runs the POU as a program instance, or while the file declares more than it."""
    require(editor, WRITE)
    found = _declaration(shelf, project, name, editor)
    users = [
        p for p in _program_instances(shelf, project, editor) if p[1].casefold() == name.casefold()
    ]
    if users:
        instances = ", ".join(sorted(p[0] for p in users))
        raise Refusal(
            "in_use",
            f"{found.name} runs as program instance {instances} of padt.toml: remove the "
            "instance from the resource first",
        )
    others = sorted(
        d.name for d in declarations(shelf, project, editor) if d.file == found.file and d != found
    )
    if others:
        raise Refusal(
            "in_use",
            f"{found.file} declares {', '.join(others)} as well: delete {found.name} there "
            "in the editor",
        )
    current = read_file(shelf, project, found.file, editor)
    return delete_file(shelf, project, found.file, current.hash, editor)


def name_problem(shelf: ProjectShelf, project: str, name: str, editor: Editor) -> str | None:
    """Why `name` cannot name a new declaration of the project, said as one types it (the
    same checks as an add or a rename makes); None when it can."""
    try:
        _check_name(name)
        _free(shelf, project, name, None, editor)
    except Refusal as refused:
        return refused.message
    return None


def _check_name(name: str) -> None:
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise Refusal(
            "bad_value",
            f"'{str(name)[:40]}' is no name: a letter or _, then letters, digits or _",
        )
    if len(name) > MAX_NAME:
        raise Refusal("bad_value", f"a name has at most {MAX_NAME} characters")
    upper = name.upper()
    if upper in KEYWORDS:
        raise Refusal("bad_value", f"'{name}' cannot be declared: it is a keyword of ST")
    if elementary(upper) is not None or lookup(upper) is not None or upper in _standard_pous():
        raise Refusal(
            "bad_value", f"'{name}' cannot be declared: it is a standard type, function or block"
        )


@cache
def _standard_pous() -> frozenset[str]:
    """The function blocks and functions of the standard library (TON, CTU, ...)."""
    names: set[str] = set()
    for source in stdlib_sources():
        unit = parse_source(source.name, source.text)
        names.update(p.name.upper() for p in unit.pous)
    return frozenset(names)


def _check_parses(name: str, text: str, kind: str | None) -> None:
    """The compiler takes the skeleton, and `name` as the name it declares (not a keyword,
    no `__`)."""
    try:
        unit = parse_source(f"{name}.st", text)
    except CompileError as exc:
        raise Refusal(
            "bad_value", f"'{name}' cannot be declared: {exc.diagnostics[0].message}"
        ) from None
    declared = [p.name for p in unit.pous] + [t.name for t in unit.types]
    if kind is not None and declared != [name]:
        raise Refusal("bad_value", f"'{name}' cannot be declared by that name")


def _free(shelf: ProjectShelf, project: str, name: str, path: str | None, editor: Editor) -> None:
    """Refused when the project declares `name` (IEC names are not case sensitive) or has
    a file of the same name but for its case."""
    clash = next(
        (d for d in declarations(shelf, project, editor) if d.name.casefold() == name.casefold()),
        None,
    )
    if clash is not None:
        raise Refusal("exists", f"{clash.file} declares {clash.name} already")
    if path is not None:
        editable_path(shelf.folder(project), path)
        root = shelf.folder(project)
        wanted = path.casefold()
        for existing in root.rglob("*.st"):
            if existing.relative_to(root).as_posix().casefold() == wanted:
                raise Refusal("exists", f"{path} exists already")


def _declaration(shelf: ProjectShelf, project: str, name: str, editor: Editor) -> Declaration:
    matches = [
        d for d in declarations(shelf, project, editor) if d.name.casefold() == str(name).casefold()
    ]
    if not matches:
        raise Refusal("not_found", f"project {project} declares no '{str(name)[:64]}'")
    return matches[0]


def _renamed_in_text(text: str, found: Declaration, new: str) -> str:
    """The declaration's name from its line on (its first use as a word after the
    keyword); for a FUNCTION also each use up to its END_FUNCTION, where the body assigns
    the result."""
    lines = text.splitlines(keepends=True)
    head = "".join(lines[: found.line - 1])
    rest = "".join(lines[found.line - 1 :])
    word = re.compile(rf"(?<![A-Za-z0-9_]){re.escape(found.name)}(?![A-Za-z0-9_])", re.IGNORECASE)
    if found.kind == "FUNCTION":
        end = re.search(r"\bEND_FUNCTION\b", rest, re.IGNORECASE)
        stop = end.end() if end is not None else len(rest)
        return head + word.sub(new, rest[:stop]) + rest[stop:]
    return head + word.sub(new, rest, count=1)


def _program_instances(shelf: ProjectShelf, project: str, editor: Editor) -> list[tuple[str, str]]:
    """(instance, POU) of each `[[resource.program]]`."""
    try:
        text = read_file(shelf, project, PROJECT_FILE, editor).text
        programs = tomllib.loads(text).get("resource", {}).get("program", [])
    except Refusal as refused:
        if refused.code == "not_found":
            return []
        raise
    except (tomllib.TOMLDecodeError, AttributeError, RecursionError):
        raise Refusal("project", "padt.toml cannot be read: correct it first") from None
    found = []
    for entry in programs if isinstance(programs, list) else []:
        if isinstance(entry, dict):
            name = str(entry.get("name", ""))
            found.append((name, str(entry.get("pou", name))))
    return found


def _renamed_in_config(
    shelf: ProjectShelf, project: str, old: str, new: str, editor: Editor
) -> Saved | None:
    """padt.toml with each program instance of POU `old` instantiating `new` (an instance
    named after its POU by default keeps its name: its variables' paths are the
    instance's)."""
    try:
        current = read_file(shelf, project, PROJECT_FILE, editor)
    except Refusal as refused:
        if refused.code == "not_found":
            return None
        raise
    document = tomlkit.parse(current.text)
    resource = document.get("resource")
    programs = resource.get("program") if isinstance(resource, dict) else None
    changed = False
    for entry in programs if isinstance(programs, list) else []:
        if not isinstance(entry, dict):
            continue
        pou = str(entry.get("pou", entry.get("name", "")))
        if pou.casefold() == old.casefold():
            entry["pou"] = new
            changed = True
    if not changed:
        return None
    return save_file(shelf, project, PROJECT_FILE, tomlkit.dumps(document), current.hash, editor)


def _zero(type_name: str) -> str | None:
    """The initial value of an elementary type; None for another (a structure: its
    components' initial values are the result until the body assigns one)."""
    upper = type_name.upper()
    if upper == "BOOL":
        return "FALSE"
    if upper in ("REAL", "LREAL"):
        return "0.0"
    if upper in ("TIME", "LTIME"):
        return "T#0s"
    if upper == "STRING":
        return "''"
    if upper in INTEGERS:
        return "0"
    return None
