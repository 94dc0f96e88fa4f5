"""Below the project tree: add a POU, a type or a global variable list, and rename or
delete the one selected in the tree. Each is one call of `backend/engineering/
project_edits.py`, which checks the name, the level and what uses the declaration itself;
a name is checked as it is typed, and a refusal is shown beside the field it is about."""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass

import viser

from backend.engineering.project_access import Editor
from backend.engineering.project_edits import (
    add_declaration,
    delete_declaration,
    name_problem,
    rename_declaration,
)
from backend.engineering.project_shelf import ProjectShelf
from frontend.confirm import confirm
from frontend.gui_value import set_value
from frontend.permissions import PADT_ACTORS
from frontend.project_tree_view import Entry
from runtime.contract.refusal import Refusal

KIND_WORDS = {
    "PROGRAM": "PROGRAM",
    "FUNCTION_BLOCK": "FUNCTION_BLOCK",
    "FUNCTION": "FUNCTION",
    "STRUCT": "TYPE (structure)",
    "ENUM": "TYPE (enumeration)",
    "GLOBALS": "Global variable list",
}
_NOTE = "color:#868e96;font-size:0.85em"
_PROBLEM = "color:#c92a2a;font-size:0.85em"


@dataclass(frozen=True)
class EditTarget:
    """Where the panel's edits go, and what it tells when one was made."""

    client: viser.ClientHandle
    shelf: ProjectShelf
    editor: Editor
    project: Callable[[], str | None]  # the project chosen in the navigation
    chosen: Callable[[], Entry | None]  # the tree's selection
    edited: Callable[[str | None], None]  # after an edit: the file to open, if any


@dataclass
class EditPanel:
    kind: viser.GuiDropdownHandle[str]
    name: viser.GuiTextHandle
    name_note: viser.GuiHtmlHandle
    add: viser.GuiButtonHandle
    selected: viser.GuiHtmlHandle
    rename_to: viser.GuiTextHandle
    rename_note: viser.GuiHtmlHandle
    rename: viser.GuiButtonHandle
    delete: viser.GuiButtonHandle
    shown: Entry | None = None
    shown_once: bool = False


def build(gui: viser.GuiApi, target: EditTarget) -> EditPanel:
    writes = target.editor.level in PADT_ACTORS
    with gui.add_folder("Add to the project", expand_by_default=False):
        kind = gui.add_dropdown("Kind", tuple(KIND_WORDS.values()), disabled=not writes)
        name = gui.add_text("New name", "", disabled=not writes)
        name_note = gui.add_html(_level_note(target.editor) if not writes else "")
        add = gui.add_button("Add", color="blue", disabled=True)
        selected = gui.add_html("")
        rename_to = gui.add_text("Rename to", "", disabled=True)
        rename_note = gui.add_html("")
        rename = gui.add_button("Rename", disabled=True)
        delete = gui.add_button("Delete", color="red", disabled=True)
    panel = EditPanel(kind, name, name_note, add, selected, rename_to, rename_note, rename, delete)
    if writes:
        name.on_update(lambda _: _check_new(panel, target))
        add.on_click(lambda _: _add(panel, target))
        rename_to.on_update(lambda _: _check_rename(panel, target))
        rename.on_click(lambda _: _rename(panel, target))
        delete.on_click(lambda _: _ask_delete(panel, target))
    return panel


def refresh(panel: EditPanel, target: EditTarget) -> None:
    """Follow the tree's selection: rename and delete act on the declaration chosen."""
    entry = target.chosen()
    declaration = entry if entry is not None and entry.kind == "file" else None
    if panel.shown_once and declaration == panel.shown:
        return
    panel.shown, panel.shown_once = declaration, True
    if declaration is None:
        panel.selected.content = (
            f'<div data-testid="edit-selected" style="{_NOTE}">Select a POU, type or global '
            "list in the tree to rename or delete it.</div>"
        )
    else:
        panel.selected.content = (
            f'<div data-testid="edit-selected">Selected: <b>{html.escape(declaration.name)}'
            f"</b> ({html.escape(declaration.file)}:{declaration.line})</div>"
        )
    writes = target.editor.level in PADT_ACTORS and declaration is not None
    panel.rename_to.disabled = not writes
    panel.delete.disabled = not writes
    set_value(panel.rename_to, "")
    panel.rename_note.content = ""
    panel.rename.disabled = True


def _kind(panel: EditPanel) -> str:
    return next(key for key, words in KIND_WORDS.items() if words == panel.kind.value)


def _problem(target: EditTarget, name: str) -> str | None:
    project = target.project()
    if project is None:
        return "choose a project first"
    return name_problem(target.shelf, project, name, target.editor)


def _check_new(panel: EditPanel, target: EditTarget) -> None:
    name = panel.name.value.strip()
    problem = _problem(target, name) if name else None
    panel.name_note.content = _note("new-name-problem", problem)
    panel.add.disabled = not name or problem is not None


def _check_rename(panel: EditPanel, target: EditTarget) -> None:
    new = panel.rename_to.value.strip()
    old = panel.shown
    case_only = old is not None and new.casefold() == old.name.casefold()
    problem = _problem(target, new) if new and not case_only else None
    panel.rename_note.content = _note("rename-problem", problem)
    panel.rename.disabled = not new or problem is not None or old is None or new == old.name


def _add(panel: EditPanel, target: EditTarget) -> None:
    project, name, kind = target.project(), panel.name.value.strip(), _kind(panel)
    if project is None:
        return
    try:
        saved = add_declaration(target.shelf, project, kind, name, target.editor)
    except Refusal as refused:
        panel.name_note.content = _note("new-name-problem", refused.message)
        return
    set_value(panel.name, "")
    panel.add.disabled = True
    panel.name_note.content = _note("new-name-done", f"{saved.path} added", error=False)
    target.edited(saved.path)


def _rename(panel: EditPanel, target: EditTarget) -> None:
    project, old, new = target.project(), panel.shown, panel.rename_to.value.strip()
    if project is None or old is None:
        return
    try:
        written = rename_declaration(target.shelf, project, old.name, new, target.editor)
    except Refusal as refused:
        panel.rename_note.content = _note("rename-problem", refused.message)
        return
    files = ", ".join(saved.path for saved in written)
    panel.rename_note.content = _note("rename-done", f"renamed in {files}", error=False)
    panel.rename.disabled = True
    target.edited(None)


def _ask_delete(panel: EditPanel, target: EditTarget) -> None:
    project, chosen = target.project(), panel.shown
    if project is None or chosen is None:
        return

    def delete() -> None:
        try:
            delete_declaration(target.shelf, project, chosen.name, target.editor)
        except Refusal as refused:
            panel.rename_note.content = _note("delete-problem", refused.message)
            return
        panel.rename_note.content = _note("delete-done", f"{chosen.file} deleted", error=False)
        target.edited(None)

    question = f"Delete {chosen.name} and its file {chosen.file} from project {project}?"
    confirm(target.client, f"Delete {chosen.name}", question, delete)


def _note(testid: str, text: str | None, error: bool = True) -> str:
    if not text:
        return ""
    style = _PROBLEM if error else _NOTE
    return f'<div data-testid="{testid}" style="{style}">{html.escape(text)}</div>'


def _level_note(editor: Editor) -> str:
    return (
        f'<div data-testid="edit-level" style="{_NOTE}">Your PADT account is '
        f"{html.escape(editor.level)}: it may look at the project, not change it.</div>"
    )
