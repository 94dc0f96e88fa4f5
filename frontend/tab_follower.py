"""Which tab of the work area a browser shows. viser's tabs switch in the browser alone and
tell the server nothing, so the server would have to keep every screen of every browser
up to date; ten browsers then cost the UI server and Chromium most of two cores. A small
script in the page reports each tab click through a text input it hides, and the
workspace refreshes (and watches values for) the screen that is seen only."""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass

import viser

LABEL = "Screen shown"

# Installed once per page (a later workspace after logging in again finds the new input by
# its label at each click). React takes a value only through the input's native setter
# followed by an input event; the input's row is hidden since nobody types there.
_SCRIPT = (
    "var find=function(){var l=Array.from(document.querySelectorAll('label')).find("
    f"function(x){{return x.textContent==='{LABEL}'}});"
    "return l?l.parentElement.parentElement.parentElement:null};"
    "var row=find();if(row)row.style.display='none';"
    "if(!window.__padtTabs){window.__padtTabs=1;"
    "document.addEventListener('click',function(e){"
    "var tab=e.target.closest&&e.target.closest('[role=tab]');var row=find();"
    "if(!tab||!row)return;var input=row.querySelector('input');"
    "Object.getOwnPropertyDescriptor(HTMLInputElement.prototype,'value').set.call("
    "input,tab.textContent.trim());"
    "input.dispatchEvent(new Event('input',{bubbles:true}))},true)}"
)


@dataclass
class TabFollower:
    box: viser.GuiTextHandle
    script: viser.GuiHtmlHandle

    def remove(self) -> None:
        self.box.remove()
        self.script.remove()


def build(gui: viser.GuiApi, first: str, on_shown: Callable[[str], None]) -> TabFollower:
    """The hidden input and its script; `on_shown(name)` at each tab the user opens."""
    box = gui.add_text(LABEL, first)
    box.on_update(lambda _: on_shown(box.value))
    script = gui.add_html(f'<img alt="" src="data:," onerror="{html.escape(_SCRIPT)}">')
    return TabFollower(box, script)
