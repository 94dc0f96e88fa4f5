"""What the user does in the page that viser does not report: the tab of the work area
(viser's tabs switch in the browser alone), a row of the Online test's table, a value drawn
on the Logic screen or a place on its drawing (in the drawing's units), an entry of the
project tree and a test or a failure's place on the Tests screen (plain HTML), and the
window's size (viser does not tell the server; the workspace chooses its panels' widths by
it). A small script reports each as the value of a hidden text input (page_writer.py); the
server reads it like any input from a browser, as untrusted text.

Knowing the tab in view, the workspace redraws that screen only: ten browsers drawing
every screen ten times a second cost most of two cores."""

from __future__ import annotations

import html
import threading
from collections.abc import Callable
from dataclasses import dataclass

import viser

LABEL = "Page click"
KINDS = ("tab", "variable", "tree", "window", "layout", "drawing", "logic", "place", "test")
MAX_NAME = 1000  # longer than any tab name, variable path or tree entry
RECENT = 8  # reports a value holds: more than come between two callbacks of viser's

# Installed once per page (a later workspace after logging in again finds the new input by
# its label at each click); each report is written past viser's throttle (page_writer.py),
# which viser_lockdown's page script installs first. Reports are numbered, and the value
# holds the last RECENT of them ("kind|name|n|kind|name|n..."; the first of a new input's):
# viser runs each update's callback on a thread of its own, which reads the input's value
# as it is then, so two reports close together would be read as the second twice. The
# server handles each number once, in order.
# "|" separates: tab names, variable paths and tree entries have none. The window's size
# is said when the page starts (once the hidden input is there) and after each resize has
# settled; the panels' widths and whether they are folded after the user dragged an edge
# or folded a panel (not when the server moved them), as "<left>x<folded>x<right>x<folded>"
# (a folded panel's width 0: the width it had is kept). Whether the editor's toolbar shows
# the plant drawing is said after each press of its toggle ("on" or "off"); the toggle is in
# the editor's shadow root, where a click's target is the root's host: its path tells.
_SCRIPT = (
    "var find=function(){return Array.from(document.querySelectorAll('label')).find("
    f"function(x){{return x.textContent==='{LABEL}'}})}};"
    "if(!window.__padtClicks){window.__padtClicks=1;var n=0;"
    "document.addEventListener('click',function(e){"
    "var at=e.target.closest?e.target:e.target.parentElement;var said=null;"
    "var tab=at.closest('[role=tab]');"
    "if(tab){said='tab|'+tab.textContent.trim()}else{"
    "var tr=at.closest('table.olt tr');var cell=tr&&tr.querySelector('td[data-var]');"
    "if(cell)said='variable|'+cell.dataset.var}"
    "if(!said){var entry=at.closest('[data-tree]');if(entry)said='tree|'+entry.dataset.tree}"
    "if(!said){var tested=at.closest('[data-test-click]');"
    "if(tested)said='test|'+tested.dataset.testClick}"
    "if(!said){var drawn=at.closest('[data-logic-var]');"
    "if(drawn)said='logic|'+drawn.dataset.logicVar}"
    "if(!said){var sheet=at.closest('svg.gfx');var m=sheet&&sheet.getScreenCTM();"
    "if(m){var q=new DOMPoint(e.clientX,e.clientY).matrixTransform(m.inverse());"
    "said='place|'+Math.round(q.x)+','+Math.round(q.y)}}"
    "if(!said&&e.composedPath().some(function(x){return x.dataset&&"
    "(x.dataset.action==='drawing'||x.dataset.action==='editor')})){"
    "setTimeout(function(){var e=window.padtEditor;"
    "tell('drawing|'+(e&&e.showDrawing?'on':'off'))},0)}"
    "tell(said)},true);"
    "var wait=null;window.addEventListener('resize',function(){clearTimeout(wait);"
    "wait=setTimeout(window.__padtSized,300)});"
    "var recent=[],box=null;"
    "var tell=function(said){var label=find();if(!said||!label)return;"
    "if(!window.__padtWrite){setTimeout(function(){tell(said)},100);return}"
    "if(label.htmlFor!==box){box=label.htmlFor;recent=[]}"
    f"n+=1;recent.push(said+'|'+n);if(recent.length>{RECENT})recent.shift();"
    "window.__padtWrite(label,recent.join('|'))};"
    "window.__padtSized=function(tries){if(!find()&&(tries||0)<50){"
    "setTimeout(function(){window.__padtSized((tries||0)+1)},100);return}"
    "tell('window|'+window.innerWidth+'x'+window.innerHeight)};"
    "var grab=null;document.addEventListener('pointerdown',function(e){"
    "var t=e.target.closest?e.target:e.target.parentElement;grab=t.closest("
    "'[data-dock-region-resize],[data-dock-region-collapse],[data-dock-minimize-all]')},true);"
    "var side=function(s){var r=document.querySelector('[data-dock-region='+s+']');"
    "if(!r)return '0x0';if(r.querySelector('[data-dock-rail-root]'))return '0x1';"
    "var c=r.querySelector('[data-dock-column]')||r;"
    "return Math.round(c.getBoundingClientRect().width)+'x0'};"
    "document.addEventListener('pointerup',function(){if(!grab)return;grab=null;"
    "setTimeout(function(){tell('layout|'+side('left')+'x'+side('right'))},400)},true)}"
    "window.__padtSized(0);"
)


@dataclass(frozen=True)
class Click:
    kind: str  # one of KINDS
    name: str  # the tab's label, the variable's path, the tree entry, a size, a layout, ...


def read_reports(text: str) -> list[tuple[int, Click]] | None:
    """The numbered reports a value holds, in the page's order; None for anything else."""
    parts = text.split("|")  # "|" separates: tab names, paths and tree entries have none
    if not text or len(parts) % 3 or len(parts) > 3 * RECENT:
        return None
    reports = []
    for kind, name, number in zip(parts[::3], parts[1::3], parts[2::3], strict=True):
        if kind not in KINDS or not name or len(name) > MAX_NAME or not _number(number):
            return None
        reports.append((int(number), Click(kind, name)))
    return reports


def _number(text: str) -> bool:
    """A report's number: ASCII digits of a JavaScript integer (int() takes "²" as no
    number but isdigit() as a digit)."""
    return 0 < len(text) <= 15 and text.isascii() and text.isdigit()


def read(text: str) -> Click | None:
    """One report as the page said it, "kind|name|n"; None for anything else."""
    reports = read_reports(text)
    return reports[0][1] if reports is not None and len(reports) == 1 else None


@dataclass
class PageClicks:
    box: viser.GuiTextHandle
    script: viser.GuiHtmlHandle

    def remove(self) -> None:
        self.box.remove()
        self.script.remove()


def build(gui: viser.GuiApi, on_click: Callable[[Click], None]) -> PageClicks:
    """The hidden input and its script; `on_click` at each click the page reports, once
    and in order."""
    box = gui.add_text(LABEL, "")
    lock = threading.Lock()  # viser's callbacks run on threads of their own
    handled = [0]  # the newest number handled

    def heard(_: object) -> None:
        with lock:
            for number, click in read_reports(box.value) or ():
                if number > handled[0]:
                    handled[0] = number
                    on_click(click)

    box.on_update(heard)
    script = gui.add_html(f'<img alt="" src="data:," onerror="{html.escape(_SCRIPT)}">')
    return PageClicks(box, script)
