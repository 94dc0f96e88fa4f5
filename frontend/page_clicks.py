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
from collections.abc import Callable
from dataclasses import dataclass

import viser

LABEL = "Page click"
KINDS = ("tab", "variable", "tree", "window", "layout", "drawing", "logic", "place", "test")
MAX_NAME = 1000  # longer than any tab name, variable path or tree entry

# Installed once per page (a later workspace after logging in again finds the new input by
# its label at each click); each report is written past viser's throttle (page_writer.py),
# which viser_lockdown's page script installs first. A counter makes a second click on the
# same row a change.
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
    "var tell=function(said){var label=find();if(!said||!label)return;"
    "if(!window.__padtWrite){setTimeout(function(){tell(said)},100);return}"
    "n+=1;window.__padtWrite(label,said+'|'+n)};"
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


def read(text: str) -> Click | None:
    """A click as the page reported it; None for anything else."""
    parts = text.split("|")  # an input's value cannot hold a line break
    if len(parts) != 3 or parts[0] not in KINDS or not parts[2].isdigit():
        return None
    if not parts[1] or len(parts[1]) > MAX_NAME:
        return None
    return Click(parts[0], parts[1])


@dataclass
class PageClicks:
    box: viser.GuiTextHandle
    script: viser.GuiHtmlHandle

    def remove(self) -> None:
        self.box.remove()
        self.script.remove()


def build(gui: viser.GuiApi, on_click: Callable[[Click], None]) -> PageClicks:
    """The hidden input and its script; `on_click` at each click the page reports."""
    box = gui.add_text(LABEL, "")

    def heard(_: object) -> None:
        click = read(box.value)
        if click is not None:
            on_click(click)

    box.on_update(heard)
    script = gui.add_html(f'<img alt="" src="data:," onerror="{html.escape(_SCRIPT)}">')
    return PageClicks(box, script)
