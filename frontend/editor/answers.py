"""The editor's questions answered by the compiler's language services
(`backend/compiler/language/`), over the analysis of the project as the editor has it, and
turned into what the page script reads. The page counts columns in UTF-16 code units, the
services in characters: converted here, both ways."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from backend.engineering.language_service import ProjectLanguage
from frontend.editor.document import BadChange, python_col, utf16_col
from frontend.editor.messages import Question, Rename

MAX_REFERENCES = 2000  # rows of a references list
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_CHAIN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)*")


class _Range(Protocol):
    @property
    def line(self) -> int: ...
    @property
    def col(self) -> int: ...


class Location(Protocol):
    """A place the language services name (their `Location`, read as it is used here)."""

    @property
    def file(self) -> str: ...
    @property
    def range(self) -> _Range: ...


# a single-line edit: (line, column, end line, end column, new text), columns 1-based UTF-16
Edit = tuple[int, int, int, int, str]


@dataclass(frozen=True)
class RenameEdits:
    old: str
    new: str
    per_file: tuple[tuple[str, tuple[Edit, ...]], ...]  # by file, each ascending


def answer(
    language: ProjectLanguage,
    question: Question,
    line_text: str,
    live_value: Callable[[str], str | None],
) -> dict[str, Any]:
    """The answer to a question, as the page reads it; an empty one when there is none."""
    try:
        col = python_col(line_text, question.col - 1) + 1
    except BadChange:
        return {}
    file, line = question.file, question.line
    if question.kind == "complete":
        return {"items": [_completion(item) for item in language.complete(file, line, col)]}
    if question.kind == "hover":
        hovered = language.hover(file, line, col)
        if hovered is None:
            return {}
        place = ""
        if hovered.declared is not None:
            where = f"{hovered.declared.file}:{hovered.declared.range.line}"
            owner = f" in {hovered.owner}" if hovered.owner else ""
            place = f"declared{owner} at {where}"
        value = live_value(chain_at(line_text, col))
        return {
            "signature": hovered.signature,
            "comment": hovered.comment,
            "place": place,
            "value": value or "",
        }
    if question.kind == "definition":
        found = language.definition(file, line, col)
        if found is None:
            return {"reason": "No definition in the project's files here."}
        return _place(language, found)
    if question.kind == "references":
        places = language.references(file, line, col)[:MAX_REFERENCES]
        return {
            "name": name_at(line_text, col),
            "items": [_reference(language, p) for p in places],
        }
    return {}


def chain_at(line_text: str, col: int) -> str:
    """The dotted name (`refillDelay.Q`) up to the end of the identifier at the 1-based
    column `col`: what a live value beside the line is labelled with."""
    for match in _CHAIN.finditer(line_text):
        if match.start() < col <= match.end() + 1:
            end = line_text.find(".", col - 1, match.end())
            return line_text[match.start() : end if end >= 0 else match.end()]
    return ""


# the icon CodeMirror draws for each kind of completion
_ICONS = {
    "variable": "variable",
    "function": "function",
    "function_block": "class",
    "method": "method",
    "property": "property",
    "type": "type",
    "keyword": "keyword",
    "snippet": "text",
    "member": "property",
    "enum_value": "enum",
}


class Completion(Protocol):
    @property
    def label(self) -> str: ...
    @property
    def kind(self) -> str: ...
    @property
    def detail(self) -> str: ...
    @property
    def insert_text(self) -> str: ...
    @property
    def snippet(self) -> bool: ...
    @property
    def documentation(self) -> str: ...


def _completion(item: Completion) -> dict[str, Any]:
    return {
        "label": item.label,
        "kind": _ICONS.get(item.kind, "text"),
        "detail": item.detail,
        "insert": item.insert_text,
        "snippet": item.snippet,
        "info": item.documentation,
    }


def name_at(line_text: str, col: int) -> str:
    """The identifier at (or just before) the 1-based column `col` of a line."""
    for match in _NAME.finditer(line_text):
        if match.start() < col <= match.end() + 1:
            return match.group()
    return ""


def _place(language: ProjectLanguage, location: Location) -> dict[str, Any]:
    line = location.range.line
    text = _line(language, location.file, line)
    return {
        "file": location.file,
        "line": line,
        "col": utf16_col(text, location.range.col - 1) + 1,
    }


def _reference(language: ProjectLanguage, location: Location) -> dict[str, Any]:
    place = _place(language, location)
    place["text"] = _line(language, location.file, location.range.line).strip()[:200]
    return place


def _line(language: ProjectLanguage, file: str, line: int) -> str:
    lines = language.text(file).split("\n")
    return lines[line - 1] if 1 <= line <= len(lines) else ""


def apply_edits(text: str, edits: tuple[Edit, ...]) -> str:
    """`edits` (ascending, not overlapping) made to `text`."""
    lines = text.split("\n")
    for line, col, end_line, end_col, new in reversed(edits):
        first, last = lines[line - 1], lines[end_line - 1]
        start, end = python_col(first, col - 1), python_col(last, end_col - 1)
        lines[line - 1 : end_line] = (first[:start] + new + last[end:]).split("\n")
    return "\n".join(lines)


def rename(language: ProjectLanguage, message: Rename, line_text: str) -> RenameEdits | str:
    """The edits of a rename checked by the compiler, or why it is refused."""
    try:
        col = python_col(line_text, message.col - 1) + 1
    except BadChange:
        return "There is no name to rename here."
    result = language.rename(message.file, message.line, col, message.name)
    if result.refusal:
        return f"Not renamed: {result.refusal}."
    per_file = []
    for changed in result.files:
        lines = language.text(changed.file).split("\n")
        edits = []
        for edit in changed.edits:
            where = edit.range
            start = utf16_col(_at(lines, where.line), where.col - 1) + 1
            end = utf16_col(_at(lines, where.end_line), where.end_col - 1) + 1
            edits.append((where.line, start, where.end_line, end, edit.new_text))
        per_file.append((changed.file, tuple(edits)))
    return RenameEdits(name_at(line_text, col), message.name, tuple(per_file))


def _at(lines: list[str], number: int) -> str:
    return lines[number - 1] if 1 <= number <= len(lines) else ""
