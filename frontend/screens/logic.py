"""The Logic screen: the body of a program or FB instance of the selected resource drawn with
its live values, as the runtime publishes them: an SFC chart with its active steps lit, each
step's time and each transition condition's value; an FBD or LD body with the value on each
connection and LD's power flow. It follows the program wherever it stands (running, frozen
and stepped, at a breakpoint): what it shows is what the resource last published. A click
on a value puts it into the Write or force editor below, with the Online test's checks and
confirmations; online test fields (a variable and its value) are placed on a drawing per
user.

As on the Code screen, the body is taken only from a project the PADT knows that compiles
to the configuration CRC the resource runs."""

from __future__ import annotations

import html
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import viser

from backend.engineering.logic_fields import LogicFields
from backend.engineering.logic_view import LiveChart, LiveGraphic, LogicBodies
from backend.engineering.sources import ConfigurationSources, find_sources, instances
from frontend.editor.live_lines import SourceLookup
from frontend.logic_view import fbd_ld, field_panel, sfc
from frontend.logic_view.svg import Live
from frontend.page_clicks import Click
from frontend.resource_feed import ResourceFeed, latest_reading
from frontend.screen_registry import Now, Screen, Work
from frontend.screens import value_edit
from frontend.state_rules import state_words
from runtime.contract import protocol as p

NO_INSTANCE = "-"
DRAWING = "drawing"  # the data-testid of the drawing's SVG, which the patch finds it by


@dataclass(frozen=True)
class Page:
    """What one refresh shows: the line above the drawing (or a message), the drawing with
    the values now and what it was drawn from (`key`), and its live parts."""

    head: str
    drawing: str = ""
    key: tuple[object, ...] = ()
    live: Live | None = None


@dataclass
class LogicScreen:
    instance: viser.GuiDropdownHandle[str]
    head: viser.GuiHtmlHandle
    view: viser.GuiHtmlHandle
    patch: viser.GuiHtmlHandle  # new values, as a patch of the drawing's live parts
    fields: field_panel.FieldPanel
    lookup: SourceLookup
    bodies: LogicBodies | None = None
    offered_for: tuple[int, str] = (0, "")  # (id of the variable table, CRC) offered
    drawn: LiveChart | LiveGraphic | None = None  # the drawing in view
    drawn_for: tuple[object, ...] = ()  # (CRC, instance, variable table) it was made for
    shown: tuple[str, tuple[object, ...], str] = ("", (), "")  # head, drawing's key, patch


def build(gui: viser.GuiApi, fields: LogicFields, user: str) -> LogicScreen:
    instance = gui.add_dropdown(
        "Instance", (NO_INSTANCE,), hint="a program or FB instance with a chart or drawing"
    )
    head = gui.add_html("")
    view = gui.add_html("")
    patch = gui.add_html("")
    panel = field_panel.build(gui, fields, user)
    return LogicScreen(instance, head, view, patch, panel, SourceLookup(find_sources))


def wanted(screen: LogicScreen) -> list[str]:
    """The variables the drawing in view shows, its online test fields' among them."""
    drawn = screen.drawn.watched() if screen.drawn is not None else []
    return drawn + field_panel.wanted(screen.fields)


def refresh(screen: LogicScreen, feed: ResourceFeed | None, projects: Mapping[str, Path]) -> None:
    page = _page(screen, feed, projects)
    if screen.drawn is None:  # no fields to show or place
        field_panel.refresh(screen.fields, None, "", {})
    head, key, patch = screen.shown
    if page.head != head:
        screen.head.content = page.head
    # the drawing whole when it is another; else only its values
    if page.key != key:
        screen.view.content = page.drawing
        patch = ""
    elif page.live is not None and page.live.patch(DRAWING) != patch:
        patch = page.live.patch(DRAWING)
        screen.patch.content = patch
    screen.shown = (page.head, page.key, patch)
    offered = tuple(screen.instance.options) != (NO_INSTANCE,)
    if screen.instance.disabled == offered:
        screen.instance.disabled = not offered


def _page(screen: LogicScreen, feed: ResourceFeed | None, projects: Mapping[str, Path]) -> Page:
    if feed is None:
        _offer(screen, ())
        return _message("Select a resource you are logged in to.")
    status, values, types, quality = latest_reading(feed)
    if status is None or not status.crc:
        _offer(screen, ())
        return _message("Waiting for the resource's configuration.")
    sources, why = screen.lookup.found_or_why(status.crc, projects, "no logic is drawn")
    if sources is None:
        _offer(screen, ())
        return _message(why)
    if not types:
        _offer(screen, ())
        return _message("No variables of the resource yet: they come once you are logged in to it.")
    if screen.bodies is None or screen.bodies.sources is not sources:
        screen.bodies = LogicBodies(sources)
    if screen.offered_for != (id(types), sources.crc):
        _offer(screen, tuple(screen.bodies.drawable(instances(sources, types))))
        screen.offered_for = (id(types), sources.crc)
    chosen = screen.instance.value
    if chosen == NO_INSTANCE:
        return _message(
            "No program or FB instance of this resource has a chart or a drawn body: an ST "
            "body is shown on the Code screen."
        )
    key = (sources.crc, chosen, id(types))
    if key != screen.drawn_for:  # made once, then only the values change
        screen.drawn_for = key
        screen.drawn = (
            screen.bodies.chart(chosen)
            if screen.bodies.kind(chosen) == "SFC"
            else screen.bodies.graphic(chosen, types)
        )
    drawn = screen.drawn
    field_panel.refresh(screen.fields, drawn, chosen, types)
    fields = screen.fields.placed
    live = Live()
    if isinstance(drawn, LiveChart):
        head = _header(chosen, f"SFC chart of {drawn.pou}", drawn.file, sources, status)
        svg = sfc.chart_svg(drawn, values, types, quality, live)
        return Page(head, sfc.legend() + svg, key, live)
    if isinstance(drawn, LiveGraphic):
        what = f"{drawn.language} body of {drawn.pou}"
        head = _header(chosen, what, drawn.file, sources, status)
        svg = fbd_ld.graphic_svg(drawn, values, types, quality, fields, live)
        return Page(head, fbd_ld.legend() + svg, (*key, tuple(fields)), live)
    return _message(f"{chosen} has nothing drawn.")


def _header(
    instance: str, what: str, file: str, sources: ConfigurationSources, status: p.Status
) -> str:
    program = instance.split(".")[0].upper()
    running = next((x for x in status.programs if x.name.upper() == program), None)
    where = (
        f" · program {html.escape(running.name)} {html.escape(state_words(running.state))}, "
        f"cycle {running.cycles}"
        if running is not None
        else ""
    )
    return (
        f'<div data-testid="logic-header" style="font-size:0.85em;color:#495057;'
        f'margin-bottom:4px"><b>{html.escape(instance)}</b>: {html.escape(what)} '
        f"({html.escape(file)} of project {html.escape(sources.project)}, configuration "
        f'{html.escape(sources.crc)})<span data-testid="logic-program">{where}</span></div>'
    )


def _offer(screen: LogicScreen, options: tuple[str, ...]) -> None:
    if not options:  # offered again once there is something to offer; nothing drawn
        screen.offered_for = (0, "")
        screen.drawn, screen.drawn_for = None, ()
    options = options or (NO_INSTANCE,)
    if tuple(screen.instance.options) != options:
        screen.instance.options = options


def _message(text: str) -> Page:
    return Page(f'<p data-testid="logic-message">{html.escape(text)}</p>')


class Logic(Screen):
    """The drawing with, below it, the editor of one value (`value_edit`)."""

    name = "Logic"
    icon = viser.Icon.SITEMAP
    width = 1000  # a drawing wants room: the plant drawing gives way while Logic is in front

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        self.screen = build(work.gui, work.context.fields, work.user)
        self.value_edit = value_edit.build(work.gui, work.send_all)

    def refresh(self, now: Now) -> None:
        refresh(self.screen, now.feed, self.work.context.projects)
        value_edit.refresh(self.value_edit, now.status, now.forcing, now.feed, self.work.allowed)

    def watches(self) -> list[str]:
        return wanted(self.screen) + value_edit.wanted(self.value_edit)

    def clicked(self, click: Click) -> None:
        if click.kind == "logic":  # checked as typed text by the value editor
            value_edit.choose(self.value_edit, click.name)
        elif click.kind == "place":  # where the next field goes
            field_panel.place(self.screen.fields, click.name)
