"""The Code screen: the ST source of a program or FB instance of the selected resource,
with line numbers and, next to each line, the live values of the variables it names (as
CODESYS shows values inline in online mode), read-only.

The source is taken only from a project the PADT knows that compiles to the configuration
CRC the resource runs; a page of lines is shown at a time (viser tells the server nothing
of scrolling), and only the variables of the lines in view are wanted (`wanted`)."""

from __future__ import annotations

import html
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import viser

from backend.engineering.sources import (
    ConfigurationSources,
    PouSource,
    Shown,
    find_sources,
    instances,
    line_variables,
)
from frontend.editor.live_lines import SourceLookup, value_text
from frontend.resource_feed import ResourceFeed, latest_reading
from frontend.screen_registry import Now, Screen, Work
from runtime.contract.artifact import VarInfo

PAGE_LINES = 40
NO_INSTANCE = "-"
PREVIOUS, NEXT = "Previous page", "Next page"
QUALITY_COLORS = {"forced": "#c92a2a", "stale": "#868e96"}  # as the Online test


@dataclass
class CodeScreen:
    instance: viser.GuiDropdownHandle[str]
    first: viser.GuiNumberHandle[int]
    page: viser.GuiButtonGroupHandle
    view: viser.GuiHtmlHandle
    lookup: SourceLookup
    in_view: list[str] = field(default_factory=list)  # paths of the lines shown
    shown: str = ""
    shown_instance: str = ""
    instances_of: tuple[int, str] = (0, "")  # (id of the variable table, CRC) listed
    lines: tuple[int, int] = (1, 1)  # the first and last line of the POU shown
    # the variables the lines in view name, for (CRC, instance, first line, variable table)
    layout: tuple[object, dict[int, list[Shown]]] = field(default_factory=lambda: (None, {}))


def build(gui: viser.GuiApi) -> CodeScreen:
    instance = gui.add_dropdown("Instance", (NO_INSTANCE,), hint="a program or FB instance")
    first = gui.add_number("Lines from", 1, min=1, step=1, hint="first line of the page shown")
    page = gui.add_button_group("Page", (PREVIOUS, NEXT))
    view = gui.add_html("")
    screen = CodeScreen(instance, first, page, view, SourceLookup(find_sources))

    def turn(event: Any) -> None:
        top, bottom = screen.lines
        now = int(screen.first.value)
        if event.target.value == PREVIOUS:
            first = max(top, now - PAGE_LINES)
        else:  # the next page, if there are lines after this one
            first = now + PAGE_LINES if now + PAGE_LINES <= bottom else now
        # viser defines the setter apart from the getter, which mypy reads as read-only
        screen.first.value = first  # type: ignore[misc]

    page.on_click(turn)
    return screen


def wanted(screen: CodeScreen) -> list[str]:
    """The instance paths of the variables the lines in view name: all this screen shows."""
    return list(screen.in_view)


def refresh(screen: CodeScreen, feed: ResourceFeed | None, projects: Mapping[str, Path]) -> None:
    page, paths = _page(screen, feed, projects)
    screen.in_view = paths
    if page != screen.shown:
        screen.view.content = page
        screen.shown = page
    # nothing to choose or to page through: say so by greying the controls out
    _enable(screen.instance, tuple(screen.instance.options) != (NO_INSTANCE,))
    paging = "data-code-line" in page
    _enable(screen.first, paging)
    if screen.page.visible != paging:  # viser cannot grey out a button group
        screen.page.visible = paging


def _enable(
    control: viser.GuiDropdownHandle[str] | viser.GuiNumberHandle[int], enabled: bool
) -> None:
    if control.disabled == enabled:  # only changes go to the browser
        control.disabled = not enabled


def _page(
    screen: CodeScreen, feed: ResourceFeed | None, projects: Mapping[str, Path]
) -> tuple[str, list[str]]:
    """The HTML of the screen and the variables it shows."""
    if feed is None:
        _offer(screen, ())
        return _message("Select a resource you are logged in to."), []
    status, values, types, quality = latest_reading(feed)
    if status is None or not status.crc:
        _offer(screen, ())
        return _message("Waiting for the resource's configuration."), []
    sources, why = screen.lookup.found_or_why(status.crc, projects, "no source is shown")
    if sources is None:
        _offer(screen, ())
        return _message(why), []
    if not types:
        _offer(screen, ())
        return _message(
            "No variables of the resource yet: they come once you are logged in to it."
        ), []
    if screen.instances_of != (id(types), sources.crc):
        _offer(screen, tuple(instances(sources, types)))
        screen.instances_of = (id(types), sources.crc)
    chosen = screen.instance.value
    if chosen == NO_INSTANCE:
        return _message("The resource has no program to show."), []
    source = sources.source_of(chosen)
    if source is None:
        interface = sources.interface_of(chosen)
        rows = [(v, f"{chosen}.{v.name}") for v in interface]
        shown = [(v, path) for v, path in rows if path in types]
        return render_interface(chosen, sources, shown, values, types, quality), [
            path for _, path in shown
        ]
    first = _first_line(screen, chosen, source)
    last = min(first + PAGE_LINES - 1, source.last_line)
    layout = (sources.crc, chosen, first, id(types))  # what the lines name changes with
    if screen.layout[0] != layout:
        screen.layout = (layout, line_variables(source, chosen, first, last, types))
    mentioned = screen.layout[1]
    paths = list(dict.fromkeys(shown.path for line in mentioned.values() for shown in line))
    header = _header(chosen, source, sources, first, last)
    return header + render_source(source, first, last, mentioned, values, types, quality), paths


def _offer(screen: CodeScreen, options: tuple[str, ...]) -> None:
    """The instances to choose from ("-" when there are none)."""
    options = options or (NO_INSTANCE,)
    if tuple(screen.instance.options) != options:
        screen.instance.options = options  # keeps the choice when it is still there
        if options == (NO_INSTANCE,):
            screen.instances_of = (0, "")


def _first_line(screen: CodeScreen, chosen: str, source: PouSource) -> int:
    """The first line of the page: the POU's first when another instance was chosen, and
    never outside the POU."""
    wanted_first = int(screen.first.value)
    if chosen != screen.shown_instance:
        screen.shown_instance = chosen
        wanted_first = source.first_line
    screen.lines = (source.first_line, source.last_line)
    first = min(max(wanted_first, source.first_line), source.last_line)
    if first != screen.first.value:
        screen.first.value = first  # type: ignore[misc]
    return first


# ---- HTML

_MUTED = "#868e96"
_LINE_NUMBER = (
    f"color:{_MUTED};text-align:right;padding:0 8px;user-select:none;position:sticky;left:0;"
    "border-right:1px solid #dee2e6;background:#f8f9fa;vertical-align:top"
)
_CODE = "white-space:pre;padding:0 12px 0 8px;vertical-align:top;tab-size:4"
_CHIP = "background:#e7f5ff;border-radius:3px;padding:0 5px;margin-right:6px"
_GAP = "margin-left:3ch"


def _message(text: str) -> str:
    return f'<p data-testid="code-message">{html.escape(text)}</p>'


def _header(
    instance: str, source: PouSource, sources: ConfigurationSources, first: int, last: int
) -> str:
    origin = (
        f"{source.file} of the PADT's standard library"
        if source.standard
        else f"{source.file} of project {sources.project}"
    )
    kind = source.kind.replace("_", " ").lower()
    return (
        f'<div data-testid="code-header" style="margin:0 0 6px 0">'
        f"<b>{html.escape(instance)}</b>: {kind} <b>{html.escape(source.name)}</b>, "
        f"{html.escape(origin)}, configuration {html.escape(sources.crc)}<br>"
        f'<span style="color:{_MUTED}">lines {first}-{last} of {source.first_line}-'
        f"{source.last_line}, read-only</span></div>"
    )


def render_source(
    source: PouSource,
    first: int,
    last: int,
    mentioned: dict[int, list[Shown]],
    values: dict[str, Any],
    types: dict[str, str],
    quality: dict[str, str],
) -> str:
    """Lines `first` to `last` of the file with their numbers, each followed on the same
    line by the values of what it names (as a debugger shows values inline). A long line
    never wraps: the work panel scrolls sideways, its line number staying in view. The
    block has no scroll bar of its own: viser replaces it with every new value, which
    would throw the reader back to its left edge ten times a second."""
    rows = []
    for number in range(first, last + 1):
        text = source.lines[number - source.first_line]
        chips = "".join(_chip(shown, values, types, quality) for shown in mentioned.get(number, []))
        after = f'<span style="{_GAP}">{chips}</span>' if chips else ""
        rows.append(
            f'<tr data-line="{number}"><td style="{_LINE_NUMBER}">{number}</td>'
            f'<td style="{_CODE}"><span data-code-line="{number}">{html.escape(text)}</span>'
            f"{after}</td></tr>"
        )
    return (
        '<div style="display:inline-block;min-width:100%;border:1px solid #dee2e6;'
        'border-radius:4px">'
        '<table style="border-collapse:collapse;min-width:100%;font-family:monospace;'
        f'font-size:12px;line-height:1.5">{"".join(rows)}</table></div>'
    )


def _chip(
    shown: Shown, values: dict[str, Any], types: dict[str, str], quality: dict[str, str]
) -> str:
    """`level = 512`, the value coloured by its quality."""
    how = quality.get(shown.path, "live")
    text = value_text(shown, values, types)
    color = QUALITY_COLORS.get(how, "inherit")
    if text is None:  # not (yet) delivered
        text, color, how = "...", _MUTED, "none"
    name = html.escape(shown.path + (f"[{shown.element}]" if shown.element else ""))
    return (
        f'<span style="{_CHIP}"><span style="color:{_MUTED}">{html.escape(shown.label)} ='
        f'</span> <b data-code-var="{name}" data-quality="{html.escape(how)}" '
        f'style="color:{color}">{html.escape(text)}</b></span>'
    )


def render_interface(
    instance: str,
    sources: ConfigurationSources,
    shown: list[tuple[VarInfo, str]],
    values: dict[str, Any],
    types: dict[str, str],
    quality: dict[str, str],
) -> str:
    """An instance of a POU without ST source here: its interface with the live values."""
    unit = sources.pou_of(instance)
    name = unit.name if unit is not None else "?"
    cell = "padding:2px 8px;border-bottom:1px solid #e5e5e5"
    rows = "".join(
        f'<tr><td style="{cell}">{html.escape(v.kind)}</td><td style="{cell}">'
        f'{html.escape(v.name)}</td><td style="{cell};color:{_MUTED}">{html.escape(v.type)}'
        f'</td><td style="{cell}">{_chip(Shown(v.name, path), values, types, quality)}</td></tr>'
        for v, path in shown
    )
    note = (
        f"{html.escape(instance)} is an instance of {html.escape(name)}, which has no ST "
        "source here (it is built into the runtime): its interface only."
    )
    return f'<p data-testid="code-message">{note}</p><table style="font-size:0.9em">{rows}</table>'


class Code(Screen):
    name = "Code"
    icon = viser.Icon.CODE

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        self.screen = build(work.gui)

    def refresh(self, now: Now) -> None:
        refresh(self.screen, now.feed, self.work.context.projects)

    def watches(self) -> list[str]:
        return wanted(self.screen)
