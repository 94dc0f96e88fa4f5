"""The Online test screen: the variables of a watch list with their live values and
qualities, a page at a time. "All variables" lists the whole resource; the user composes
lists of their own by search and from the instance tree, and the PADT keeps them. Only the
rows of the page in view are watched. Values are one HTML table per browser, which costs
the browser far less than one input widget per variable."""

from __future__ import annotations

import html
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import viser

from backend.engineering import variable_tree
from backend.engineering.watch_lists import (
    WatchListError,
    WatchLists,
    list_name,
    with_variables,
    without_variable,
)
from frontend.gui_value import set_value
from frontend.page_clicks import Click
from frontend.resource_feed import ResourceFeed
from frontend.screen_registry import Now, Screen, Work
from frontend.screens import value_edit
from runtime.contract.values import format_for_display

ALL = "All variables"
PAGE_SIZES = ("25", "50", "100", "200", "500", "1000")
MAX_MATCHES = 100  # options in the Matches dropdown
NO_MATCH = "(no match)"
NO_INSTANCE = "(no instances)"
NOTHING = "(empty list)"
ADD_MATCH, ADD_ALL = "Add to list", "Add all matches"
PREVIOUS, NEXT = "Previous page", "Next page"


@dataclass
class OnlineTestScreen:
    user: str
    lists: WatchLists
    chosen: viser.GuiDropdownHandle[str]
    search: viser.GuiTextHandle
    matches: viser.GuiDropdownHandle[str]
    instance: viser.GuiDropdownHandle[str]
    removable: viser.GuiDropdownHandle[str]
    new_name: viser.GuiTextHandle
    note: viser.GuiHtmlHandle
    own_list_buttons: list[viser.GuiButtonHandle]
    first_row: viser.GuiNumberHandle[int]
    page_size: viser.GuiDropdownHandle[str]
    range_note: viser.GuiHtmlHandle
    table: viser.GuiHtmlHandle
    patch: viser.GuiHtmlHandle  # the values of the page, as a patch of the table's cells
    types: dict[str, str] = field(default_factory=dict)  # the resource's variables
    all_rows: list[str] = field(default_factory=list)  # them in tree order
    types_version: int = -1
    shown: str = ""
    shown_key: tuple[Any, ...] = ()  # the page `shown` was drawn for
    patched_version: int = -1
    rows: list[str] = field(default_factory=list)  # the page in view


def build(gui: viser.GuiApi, user: str, lists: WatchLists) -> OnlineTestScreen:
    chosen = gui.add_dropdown("Watch list", (ALL,))
    with gui.add_folder("Compose watch lists", expand_by_default=False):
        new_name = gui.add_text("New list", "")
        create = gui.add_button("Create list", icon=viser.Icon.PLUS)
        search = gui.add_text("Search", "")
        matches = gui.add_dropdown("Matches", (NO_MATCH,))
        # buttons, not a button group: viser cannot disable a group
        add_match = gui.add_button(ADD_MATCH, icon=viser.Icon.PLUS)
        add_all = gui.add_button(ADD_ALL)
        instance = gui.add_dropdown("Instance", (NO_INSTANCE,))
        add_instance = gui.add_button("Add the instance's variables")
        removable = gui.add_dropdown("On this page", (NOTHING,))
        remove = gui.add_button("Remove from list", icon=viser.Icon.MINUS)
        delete = gui.add_button("Delete this list", color="red")
        note = gui.add_html("")
    first_row = gui.add_number("First row", 1, min=1, step=1)
    page_size = gui.add_dropdown("Rows per page", PAGE_SIZES, initial_value="50")
    paging = gui.add_button_group("Page", (PREVIOUS, NEXT))
    range_note = gui.add_html("")
    gui.add_html(legend())
    table = gui.add_html("")
    patch = gui.add_html("")
    screen = OnlineTestScreen(
        user,
        lists,
        chosen,
        search,
        matches,
        instance,
        removable,
        new_name,
        note,
        [add_match, add_all, add_instance, remove, delete],
        first_row,
        page_size,
        range_note,
        table,
        patch,
    )
    _set_options(chosen, list_names(screen))

    def on(handle: Any, action: Callable[[OnlineTestScreen], None]) -> None:
        handle.on_click(lambda _: action(screen))

    on(create, create_list)
    on(add_match, lambda s: add_to_list(s, [s.matches.value]))
    on(add_all, lambda s: add_to_list(s, match_paths(s, limit=None)))
    on(add_instance, lambda s: add_to_list(s, variable_tree.below(s.types, s.instance.value)))
    on(remove, remove_from_list)
    on(delete, delete_list)
    paging.on_click(lambda event: turn_page(screen, -1 if event.target.value == PREVIOUS else 1))
    search.on_update(lambda _: show_matches(screen))
    chosen.on_update(lambda _: _list_chosen(screen))
    return screen


# ---- what the user does
def create_list(screen: OnlineTestScreen) -> None:
    try:
        name = list_name(screen.new_name.value)
        if name == ALL or name in list_names(screen):
            raise WatchListError(f"there is a list '{name}' already")
        screen.lists.put(screen.user, name, ())
    except WatchListError as refused:
        return _say(screen, str(refused), error=True)
    set_value(screen.new_name, "")
    _set_options(screen.chosen, list_names(screen))
    set_value(screen.chosen, name)
    _say(screen, f"List '{name}' created: add variables by search or from an instance.")


def add_to_list(screen: OnlineTestScreen, paths: list[str]) -> None:
    name = own_list(screen)
    paths = [path for path in paths if path in screen.types]
    if name is None or not paths:
        return
    current = _variables_of(screen, name)
    try:
        screen.lists.put(screen.user, name, with_variables(current, paths))
    except WatchListError as refused:
        return _say(screen, str(refused), error=True)
    added = len(_variables_of(screen, name)) - len(current)
    _say(screen, f"{added} added to '{name}'" + ("" if added else " (all were in it)"))


def remove_from_list(screen: OnlineTestScreen) -> None:
    name = own_list(screen)
    if name is None or screen.removable.value == NOTHING:
        return
    gone = screen.removable.value
    screen.lists.put(screen.user, name, without_variable(_variables_of(screen, name), gone))
    _say(screen, f"{gone} removed from '{name}'")


def delete_list(screen: OnlineTestScreen) -> None:
    name = own_list(screen)
    if name is None:
        return
    screen.lists.delete(screen.user, name)
    _set_options(screen.chosen, list_names(screen))
    set_value(screen.chosen, ALL)
    _say(screen, f"List '{name}' deleted.")


def turn_page(screen: OnlineTestScreen, direction: int) -> None:
    size = int(screen.page_size.value)
    last_first = max(1, len(rows_of(screen)) - size + 1)
    wanted = min(max(1, int(screen.first_row.value) + direction * size), last_first)
    set_value(screen.first_row, wanted)


def show_matches(screen: OnlineTestScreen) -> None:
    found, count = variable_tree.search(screen.types, screen.search.value, MAX_MATCHES)
    _set_options(screen.matches, found or [NO_MATCH])
    if screen.search.value.strip():
        more = f" (the first {MAX_MATCHES} in Matches)" if count > MAX_MATCHES else ""
        _say(screen, f"{count} variable{'s' if count != 1 else ''} match{more}")


def _list_chosen(screen: OnlineTestScreen) -> None:
    set_value(screen.first_row, 1)
    _say(screen, "")


# ---- what the screen shows
def list_names(screen: OnlineTestScreen) -> list[str]:
    return [ALL] + [x.name for x in screen.lists.of(screen.user)]


def own_list(screen: OnlineTestScreen) -> str | None:
    name = screen.chosen.value
    return None if name == ALL else name


def rows_of(screen: OnlineTestScreen) -> list[str]:
    name = own_list(screen)
    return screen.all_rows if name is None else list(_variables_of(screen, name))


def match_paths(screen: OnlineTestScreen, limit: int | None) -> list[str]:
    return variable_tree.search(screen.types, screen.search.value, limit or len(screen.types))[0]


def wanted(screen: OnlineTestScreen) -> list[str]:
    """The variables of the page in view: the only ones this screen needs watched."""
    return screen.rows


def refresh(screen: OnlineTestScreen, feed: ResourceFeed | None) -> None:
    if feed is None:
        screen.rows = []
        _show(screen, "<p>Select a resource you are logged in to.</p>")
        return
    latest = feed.latest
    with latest.lock:
        types_version, types = latest.types_version, latest.types
        values, quality, values_version = latest.values, latest.quality, latest.values_version
    if types_version != screen.types_version:
        screen.types, screen.types_version = types, types_version
        screen.all_rows = variable_tree.in_tree_order(types)
        _set_options(screen.instance, variable_tree.instances(types) or [NO_INSTANCE])
        show_matches(screen)
    if screen.chosen.value not in list_names(screen):  # deleted in another browser
        _set_options(screen.chosen, list_names(screen))
        set_value(screen.chosen, ALL)
    rows = rows_of(screen)
    size = int(screen.page_size.value)
    first = min(max(1, int(screen.first_row.value)), max(1, len(rows)))
    screen.rows = rows[first - 1 : first - 1 + size]
    removable = screen.rows if own_list(screen) and screen.rows else [NOTHING]
    _set_options(screen.removable, removable)  # the page in view: a list may be long
    _refresh_buttons(screen)
    last = first - 1 + len(screen.rows)
    range_text = f"rows {first} to {last} of {len(rows)}" if rows else "no rows"
    if screen.range_note.content != _range_html(range_text):
        screen.range_note.content = _range_html(range_text)
    if not rows and own_list(screen):
        return _show(screen, "<p>This list is empty: add variables under Compose watch lists.</p>")
    # The table is drawn when the page changes; new values then travel as a patch of
    # the value cells alone: a fifth of the bytes, and the browser keeps its rows.
    key = (types_version, first, tuple(screen.rows))
    if key != screen.shown_key:
        _show(screen, render_values(screen.rows, types, values, quality, first))
        screen.shown_key = key
    elif values_version != screen.patched_version:
        screen.patch.content = render_patch(screen.rows, types, values, quality)
    screen.patched_version = values_version


def _refresh_buttons(screen: OnlineTestScreen) -> None:
    reason = None if own_list(screen) else "choose or create a list of your own"
    for button in screen.own_list_buttons:
        if button.disabled != (reason is not None):
            button.disabled = reason is not None
            button.hint = reason


_QUALITY_STYLES = {
    "forced": "color:#c92a2a;font-weight:600",
    "stale": "color:#868e96",
    "deleted": "color:#868e96;text-decoration:line-through",
    "bad": "color:#e8590c;font-style:italic",
    "unknown": "color:#868e96;font-style:italic",
    "waiting": "color:#868e96",
}


def legend() -> str:
    samples = [
        ("live", "live", "changes as the controller runs"),
        ("forced", "forced", "held by forcing"),
        ("stale", "stale", "nothing that could change it runs"),
        ("deleted", "deleted", "gone with a reload"),
        ("bad", "bad", "input of a lost Modbus device, at its safe value"),
    ]
    items = "".join(
        f'<span style="margin-right:14px"><span style="{_QUALITY_STYLES.get(key, "")}">'
        f"{label}</span> <span style='color:#868e96'>{html.escape(meaning)}</span></span>"
        for key, label, meaning in samples
    )
    style = "font-size:0.8em;line-height:1.6"
    return f'<div data-testid="quality-legend" style="{style}">{items}</div>'


# One stylesheet in the page and short classes per cell: a page of 1,000 rows is redrawn
# ten times a second, and the browser parses every byte of it each time.
_STYLE = (
    "<style>.olt{font-size:0.9em;width:100%;table-layout:fixed;border-collapse:collapse}"
    ".olt td,.olt th{padding:2px 8px;border-bottom:1px solid #e5e5e5;vertical-align:top}"
    ".olt .n{color:#868e96;text-align:right;width:3em}.olt .p{overflow-wrap:anywhere}"
    ".olt .t{color:#868e96}.olt .v{text-align:right;font-family:monospace;"
    "overflow-wrap:anywhere}.olt tr:has(td.v){cursor:pointer}"
    ".olt tr:has(td.v):hover td{background:#f1f3f5}"
    ".olt td:last-child,.olt th:last-child{padding-right:16px}"  # clear of the scrollbar
    + "".join(f".olt .{key}{{{style}}}" for key, style in _QUALITY_STYLES.items())
    + "</style>"
)
_HEAD = (
    '<tr><th class="n"></th><th style="text-align:left;width:45%">Variable</th>'
    '<th style="text-align:left;width:15%">Type</th><th style="text-align:right">Value</th></tr>'
)


def render_values(
    rows: list[str],
    types: dict[str, str],
    values: dict[str, Any],
    quality: dict[str, str] | None = None,
    first: int = 1,
) -> str:
    lines = []
    for number, path in enumerate(rows, start=first):
        type_name = types.get(path, "")
        how, shown = _cell(path, types, values, quality or {})
        name = html.escape(path)
        lines.append(
            f'<tr><td class="n">{number}</td><td class="p">{name}</td>'
            f'<td class="t">{html.escape(type_name)}</td><td class="v {how}" '
            f'data-var="{name}" data-quality="{how}">{html.escape(shown)}</td></tr>'
        )
    return f'{_STYLE}<table class="olt">{_HEAD}{"".join(lines)}</table>'


def _cell(
    path: str, types: dict[str, str], values: dict[str, Any], quality: dict[str, str]
) -> tuple[str, str]:
    """A value cell's quality (its CSS class too) and text."""
    if path not in types:
        return "unknown", "not in this configuration"
    if path not in values:
        return "waiting", "…"
    return quality.get(path, "live"), format_for_display(values[path], types[path])


# Run by the browser each time the patch arrives (viser runs inline handlers, not
# <script>): the JSON before the image holds {path: [text, quality]} of the page.
_APPLY = (
    "var d=JSON.parse(this.previousElementSibling.textContent);"
    "document.querySelectorAll('td[data-var]').forEach(function(c){"
    "var v=d[c.dataset.var];if(!v)return;"
    "if(c.textContent!==v[0])c.textContent=v[0];"
    "if(c.dataset.quality!==v[1]){c.dataset.quality=v[1];c.className='v '+v[1];}});"
)


def render_patch(
    rows: list[str], types: dict[str, str], values: dict[str, Any], quality: dict[str, str]
) -> str:
    """The value cells of the page as an invisible patch the browser applies to the table."""
    cells = {path: _cell(path, types, values, quality) for path in rows}
    data = json.dumps({path: [text, how] for path, (how, text) in cells.items()})
    # nothing in a <script> element's text may close it
    data = data.replace("<", "\\u003c")
    return (
        f'<div style="display:none"><script type="application/json">{data}</script>'
        f'<img alt="" src="data:," onerror="{html.escape(_APPLY)}"></div>'
    )


def _range_html(text: str) -> str:
    return f'<div data-testid="olt-range" style="color:#868e96;font-size:0.85em">{text}</div>'


def _show(screen: OnlineTestScreen, page: str) -> None:
    if page != screen.shown:
        screen.table.content = page
        screen.shown = page
        screen.shown_key = ()


def _say(screen: OnlineTestScreen, text: str, error: bool = False) -> None:
    color = "#c92a2a" if error else "#495057"
    shown = f'<div data-testid="olt-note" style="color:{color}">{html.escape(text)}</div>'
    screen.note.content = shown if text else ""


def _variables_of(screen: OnlineTestScreen, name: str) -> tuple[str, ...]:
    return next((x.variables for x in screen.lists.of(screen.user) if x.name == name), ())


def _set_options(dropdown: viser.GuiDropdownHandle[str], options: list[str]) -> None:
    wanted = tuple(options)
    if tuple(dropdown.options) != wanted:
        dropdown.options = wanted


class OnlineTest(Screen):
    """The Online test with, below its table, the editor of one value (`value_edit`)."""

    name = "Online test"
    icon = viser.Icon.TABLE

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        self.screen = build(work.gui, work.user, work.context.watch_lists)
        self.value_edit = value_edit.build(work.gui, work.send_all)

    def refresh(self, now: Now) -> None:
        refresh(self.screen, now.feed)
        value_edit.refresh(self.value_edit, now.status, now.forcing, now.feed, self.work.allowed)

    def watches(self) -> list[str]:
        return wanted(self.screen) + value_edit.wanted(self.value_edit)

    def clicked(self, click: Click) -> None:
        if click.kind == "variable":  # checked as typed text by the value editor
            value_edit.choose(self.value_edit, click.name)
