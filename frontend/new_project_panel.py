"""Below the project chooser: a new project from a template (empty, the demo tank, an SFC
sequence), made by `ProjectShelf.new_project`, which checks the name, the template, the
level and records it in the audit log; the workspace then opens it in the tree. A name is
checked as it is typed, and a refusal is shown beside the field it is about."""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass

import viser

from backend.engineering.project_access import Editor
from backend.engineering.project_shelf import ProjectShelf, project_name_problem, templates
from frontend.permissions import PADT_ACTORS
from runtime.contract.refusal import Refusal

_PROBLEM = "color:#c92a2a;font-size:0.85em"
_NOTE = "color:#868e96;font-size:0.85em"


@dataclass(frozen=True)
class Maker:
    """Where new projects go, and what the workspace does with one made."""

    shelf: ProjectShelf
    editor: Editor
    made: Callable[[str], None]  # open the project of that name


@dataclass(frozen=True)
class NewProjectPanel:
    name: viser.GuiTextHandle
    template: viser.GuiDropdownHandle[str]
    note: viser.GuiHtmlHandle
    make: viser.GuiButtonHandle


def build(gui: viser.GuiApi, maker: Maker) -> NewProjectPanel:
    writes = maker.editor.level in PADT_ACTORS
    names = tuple(t.name for t in templates())
    with gui.add_folder("New project", expand_by_default=False):
        name = gui.add_text("Project name", "", disabled=not writes)
        template = gui.add_dropdown("Template", names, disabled=not writes)
        about = gui.add_html(_about(template.value))  # the whole title: the field is narrow
        note = gui.add_html(_note(_why_not(maker) if not writes else None))
        make = gui.add_button("Make project", color="blue", disabled=True)
    panel = NewProjectPanel(name, template, note, make)
    template.on_update(lambda _: _tell(about, template.value))
    if writes:
        name.on_update(lambda _: _check(panel, maker))
        make.on_click(lambda _: _make(panel, maker))
    return panel


def _tell(about: viser.GuiHtmlHandle, template: str) -> None:
    about.content = _about(template)


def _about(template: str) -> str:
    title = next((t.title for t in templates() if t.name == template), "")
    return f'<div data-testid="template-about" style="{_NOTE}">{html.escape(title)}</div>'


def _why_not(maker: Maker) -> str:
    return f"Your PADT account is {maker.editor.level}: making a project needs read-write."


def _problem(panel: NewProjectPanel, maker: Maker) -> str | None:
    name = panel.name.value
    problem = project_name_problem(name)
    if problem is None and name.casefold() in {n.casefold() for n in maker.shelf}:
        problem = f"there is a project '{name}' already"
    return problem


def _check(panel: NewProjectPanel, maker: Maker) -> None:
    problem = _problem(panel, maker) if panel.name.value else None
    panel.note.content = _note(problem)
    panel.make.disabled = not panel.name.value or problem is not None


def _make(panel: NewProjectPanel, maker: Maker) -> None:
    name = panel.name.value
    chosen = panel.template.value
    try:  # the shelf checks everything again: the page may send anything
        maker.shelf.new_project(name, chosen, maker.editor)
    except Refusal as refused:
        panel.note.content = _note(refused.message)
        return
    panel.note.content = (
        f'<div data-testid="new-project-made" style="{_NOTE}">Made project '
        f"<b>{html.escape(name)}</b> from the {html.escape(chosen)} template.</div>"
    )
    panel.make.disabled = True
    maker.made(name)


def _note(problem: str | None) -> str:
    if problem is None:
        return ""
    return f'<div data-testid="new-project-problem" style="{_PROBLEM}">{html.escape(problem)}</div>'
