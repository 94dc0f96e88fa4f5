"""What the user does in the page that viser does not report: the tab of the work area
(viser's tabs switch in the browser alone), a row of the Online test's table and an entry
of the project tree (plain HTML), and the window's size (viser does not tell the server;
the workspace chooses its panels' widths by it). A small script reports each through a
text input it hides; the server reads it like any input from a browser, as untrusted text.

Knowing the tab in view, the workspace redraws that screen only: ten browsers drawing
every screen ten times a second cost most of two cores."""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass

import viser

LABEL = "Page click"
KINDS = ("tab", "variable", "tree", "window")
MAX_NAME = 1000  # longer than any tab name, variable path or tree entry

# Installed once per page (a later workspace after logging in again finds the new input by
# its label at each click). React takes a value only through the input's native setter
# followed by an input event; a counter makes a second click on the same row a change.
# "|" separates: tab names, variable paths and tree entries have none. The window's size
# is said when the page starts and after each resize has settled.
_SCRIPT = (
    "var find=function(){var l=Array.from(document.querySelectorAll('label')).find("
    f"function(x){{return x.textContent==='{LABEL}'}});"
    "return l?l.parentElement.parentElement.parentElement:null};"
    "var row=find();if(row)row.style.display='none';"
    "if(!window.__padtClicks){window.__padtClicks=1;var n=0;"
    "document.addEventListener('click',function(e){"
    "var at=e.target.closest?e.target:e.target.parentElement;var said=null;"
    "var tab=at.closest('[role=tab]');"
    "if(tab){said='tab|'+tab.textContent.trim()}else{"
    "var tr=at.closest('table.olt tr');var cell=tr&&tr.querySelector('td[data-var]');"
    "if(cell)said='variable|'+cell.dataset.var}"
    "if(!said){var entry=at.closest('[data-tree]');if(entry)said='tree|'+entry.dataset.tree}"
    "tell(said)},true);"
    "var wait=null;window.addEventListener('resize',function(){clearTimeout(wait);"
    "wait=setTimeout(window.__padtSized,300)});"
    "var tell=function(said){var box=find();if(!said||!box)return;"
    "var input=box.querySelector('input');"
    "n+=1;Object.getOwnPropertyDescriptor(HTMLInputElement.prototype,'value').set.call("
    "input,said+'|'+n);input.dispatchEvent(new Event('input',{bubbles:true}))};"
    "window.__padtSized=function(){tell('window|'+window.innerWidth+'x'+window.innerHeight)}}"
    "setTimeout(window.__padtSized,200);"
)


@dataclass(frozen=True)
class Click:
    kind: str  # one of KINDS
    name: str  # the tab's label, the variable's path, the tree entry, "<width>x<height>"


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
