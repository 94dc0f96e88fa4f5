"""The Logic screen's online test fields: a user places variables with their live values on
an FBD or LD drawing (a click on the drawing says where), moves and removes them; the PADT
keeps them per user and drawing (`backend/engineering/logic_fields.py`), so they are there
at the next login, from any browser, on every instance of the POU."""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass, field

import viser

from backend.engineering.logic_fields import FARTHEST, Field, FieldError, LogicFields
from backend.engineering.logic_fields import field as checked_field
from backend.engineering.logic_view import LiveChart, LiveGraphic, variable_path
from frontend.gui_value import set_value
from frontend.logic_view.fbd_ld import PlacedField

NO_FIELD = "(no field)"


@dataclass
class FieldPanel:
    store: LogicFields
    user: str
    folder: viser.GuiFolderHandle
    variable: viser.GuiTextHandle
    x: viser.GuiNumberHandle[float]
    y: viser.GuiNumberHandle[float]
    chosen: viser.GuiDropdownHandle[str]
    note: viser.GuiHtmlHandle
    pou: str = ""  # the POU of the drawing in view ("" for none)
    known: tuple[int, dict[str, str]] = (0, {})  # (id of the variable table, paths by upper)
    placed: list[PlacedField] = field(default_factory=list)


def build(gui: viser.GuiApi, store: LogicFields, user: str) -> FieldPanel:
    with gui.add_folder("Online test fields", expand_by_default=False) as folder:
        variable = gui.add_text(
            "Field variable", "", hint="as the POU names it: count, t1.Q, or a global"
        )
        x = gui.add_number("Field x", 0.0, min=-FARTHEST, max=FARTHEST, step=1.0)
        y = gui.add_number("Field y", 0.0, min=-FARTHEST, max=FARTHEST, step=1.0)
        add = gui.add_button("Add field", icon=viser.Icon.PLUS)
        chosen = gui.add_dropdown("Field", (NO_FIELD,))
        move = gui.add_button("Move field to x, y")
        remove = gui.add_button("Remove field", icon=viser.Icon.MINUS)
        note = gui.add_html(_note("Click the drawing where a field goes: x and y take the place."))
    panel = FieldPanel(store, user, folder, variable, x, y, chosen, note)

    def on(button: viser.GuiButtonHandle, action: Callable[[FieldPanel], None]) -> None:
        button.on_click(lambda _: action(panel))

    on(add, add_field)
    on(move, move_field)
    on(remove, remove_field)
    return panel


def add_field(panel: FieldPanel) -> None:
    try:
        new = checked_field(panel.variable.value, panel.x.value, panel.y.value)
        _put(panel, (*_fields(panel), new))
    except FieldError as refused:
        return _say(panel, str(refused), error=True)
    set_value(panel.chosen, _label(len(_fields(panel)) - 1, new))
    _say(panel, f"{new.variable} placed at {new.x:g}, {new.y:g}.")


def move_field(panel: FieldPanel) -> None:
    index = _chosen(panel)
    if index is None:
        return _say(panel, "choose a field to move", error=True)
    fields = list(_fields(panel))
    try:
        moved = checked_field(fields[index].variable, panel.x.value, panel.y.value)
        fields[index] = moved
        _put(panel, tuple(fields))
    except FieldError as refused:
        return _say(panel, str(refused), error=True)
    set_value(panel.chosen, _label(index, moved))
    _say(panel, f"{moved.variable} moved to {moved.x:g}, {moved.y:g}.")


def remove_field(panel: FieldPanel) -> None:
    index = _chosen(panel)
    if index is None:
        return _say(panel, "choose a field to remove", error=True)
    fields = list(_fields(panel))
    gone = fields.pop(index)
    _put(panel, tuple(fields))
    _say(panel, f"{gone.variable} removed.")


def place(panel: FieldPanel, where: str) -> None:
    """A click on the drawing at `where` ("x,y" in the drawing's units, as the page says)."""
    x, _, y = where.partition(",")
    try:
        at = (float(int(x)), float(int(y)))
    except ValueError:
        return  # not what the page script sends: nothing to take
    if all(abs(c) <= FARTHEST for c in at):
        set_value(panel.x, at[0])
        set_value(panel.y, at[1])


def refresh(
    panel: FieldPanel, drawn: LiveChart | LiveGraphic | None, instance: str, types: dict[str, str]
) -> None:
    """The fields of the drawing in view, with the paths their variables have in the
    resource; the panel shown only for a drawing that takes fields (FBD, LD)."""
    graphic = drawn if isinstance(drawn, LiveGraphic) else None
    if panel.folder.visible != (graphic is not None):
        panel.folder.visible = graphic is not None
    panel.pou = graphic.pou if graphic is not None else ""
    if panel.known[0] != id(types):
        panel.known = (id(types), {path.upper(): path for path in types})
    fields = _fields(panel)
    panel.placed = [
        PlacedField(f.variable, variable_path(instance, f.variable, panel.known[1]), f.x, f.y)
        for f in fields
    ]
    options = tuple(_label(i, f) for i, f in enumerate(fields)) or (NO_FIELD,)
    if tuple(panel.chosen.options) != options:
        panel.chosen.options = options


def wanted(panel: FieldPanel) -> list[str]:
    return [f.path for f in panel.placed if f.path is not None]


def _fields(panel: FieldPanel) -> tuple[Field, ...]:
    return panel.store.of(panel.user, panel.pou) if panel.pou else ()


def _put(panel: FieldPanel, fields: tuple[Field, ...]) -> None:
    if not panel.pou:
        raise FieldError("fields go on an FBD or LD drawing: choose an instance drawn so")
    panel.store.put(panel.user, panel.pou, fields)


def _chosen(panel: FieldPanel) -> int | None:
    fields = _fields(panel)
    labels = [_label(i, f) for i, f in enumerate(fields)]
    return labels.index(panel.chosen.value) if panel.chosen.value in labels else None


def _label(index: int, placed: Field) -> str:
    return f"{index + 1}: {placed.variable} at {placed.x:g}, {placed.y:g}"


def _say(panel: FieldPanel, text: str, error: bool = False) -> None:
    panel.note.content = _note(text, error)


def _note(text: str, error: bool = False) -> str:
    color = "#c92a2a" if error else "#868e96"
    return (
        f'<div data-testid="field-note" style="font-size:0.85em;color:{color}">'
        f"{html.escape(text)}</div>"
    )
