"""What the user does in the page that viser does not report: the tab of the work area
(viser's tabs switch in the browser alone), a row of the Online test's table, a value drawn
on the Logic screen or a place on its drawing (in the drawing's units), an entry of the
project tree and a test or a failure's place on the Tests screen (plain HTML), and the
window's size (viser does not tell the server; the workspace chooses its panels' widths by
it). A small script reports each through a text input it hides; the server reads it like
any input from a browser, as untrusted text.

Knowing the tab in view, the workspace redraws that screen only: ten browsers drawing
every screen ten times a second cost most of two cores.

A click must not be lost: viser's page sends the values of all its inputs through one
sender that keeps, within 50 ms, only the newest value of any input (a click written just
before the editor's hidden input was written was never sent), and drops the value waiting
when the panel is drawn anew. So the page numbers its clicks and keeps those the server
has not acknowledged (the last MAX_QUEUE; a newer window size or layout replaces an older
one), writes them all at once as `{"p": page, "s": [[n, "kind|name"], ...], "w": writes}`
and again every RESEND_MS until the server acknowledges n, counting its writes in "w" so
that the same queue is a new value for the input (an input that keeps its value sends
nothing). The server takes the clicks past the last n it handled, in order, and
acknowledges the newest by a script run in the page (frontend/page_push.py). The page's
id `p`, drawn at random when the page starts, tells a page loaded anew (whose n starts at
1 again) from the one the server was counting for. The editor's messages travel the same
way (frontend/editor/messages.py)."""

from __future__ import annotations

import html
import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import viser

from frontend.page_push import run, script_json
from runtime.contract.outside_json import JsonRefused, read_json

log = logging.getLogger("padt.ui")

LABEL = "Page click"
KINDS = ("tab", "variable", "tree", "window", "layout", "drawing", "logic", "place", "test")
MAX_NAME = 1000  # longer than any tab name, variable path or tree entry
MAX_QUEUE = 20  # clicks the page keeps until they are acknowledged
MAX_PAGE = 32  # characters of a page's id
MAX_N = 2**53  # JavaScript's integers
MAX_BATCH_CHARS = 64 * 1024  # MAX_QUEUE clicks of MAX_NAME characters, and room
RESEND_MS = 400  # an unacknowledged queue is written again after this
ACK_CHANNEL = "page-clicks-ack"  # frontend/page_push.py: only the newest matters
REPLACED = ("window", "layout")  # kinds of which only the newest click matters

# Installed once per page (a later workspace after logging in again finds the new input by
# its label at each write). React takes a value only through the input's native setter
# followed by an input event. "|" separates: tab names, variable paths and tree entries
# have none. The window's size is said when the page starts (once the hidden input is
# there) and after each resize has settled; the panels' widths and whether they are folded
# after the user dragged an edge or folded a panel (not when the server moved them), as
# "<left>x<folded>x<right>x<folded>" (a folded panel's width 0: the width it had is kept).
# Whether the editor's toolbar shows the plant drawing is said after each press of its
# toggle ("on" or "off"); the toggle is in the editor's shadow root, where a click's target
# is the root's host: its path tells. `tell` queues a click, `flush` writes the queue (and
# again after RESEND_MS while it is not empty), `__padtClickAck` drops what the server
# acknowledged; `__padtClicksWaiting` says how many clicks wait for it (the server answers
# a click before it acknowledges it: none waiting, the page has the answers).
_SCRIPT = (
    "var find=function(){var l=Array.from(document.querySelectorAll('label')).find("
    f"function(x){{return x.textContent==='{LABEL}'}});"
    "return l?l.parentElement.parentElement.parentElement:null};"
    "var row=find();if(row)row.style.display='none';"
    "if(!window.__padtClicks){window.__padtClicks=1;"
    "var n=0,queue=[],w=0,resend=null,page=Math.floor(Math.random()*1e15).toString(36);"
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
    "var tell=function(said){if(!said)return;n+=1;var kind=said.split('|')[0];"
    f"if({script_json(list(REPLACED))}.indexOf(kind)>=0)queue=queue.filter(function(e){{"
    "return e[1].split('|')[0]!==kind});"
    f"queue.push([n,said]);if(queue.length>{MAX_QUEUE})queue=queue.slice(-{MAX_QUEUE});flush()}};"
    "var flush=function(){clearTimeout(resend);resend=null;if(!queue.length)return;"
    "var box=find();var input=box&&box.querySelector('input');if(input){w+=1;"
    "Object.getOwnPropertyDescriptor(HTMLInputElement.prototype,'value').set.call("
    "input,JSON.stringify({p:page,s:queue,w:w}));"
    "input.dispatchEvent(new Event('input',{bubbles:true}))}"
    f"resend=setTimeout(flush,{RESEND_MS})}};"
    "window.__padtClickAck=function(p,k){if(p!==page)return;"
    "queue=queue.filter(function(e){return e[0]>k});"
    "if(!queue.length){clearTimeout(resend);resend=null}};"
    "window.__padtClicksWaiting=function(){return queue.length};"
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


@dataclass(frozen=True)
class Batch:
    """The clicks a page has not seen acknowledged."""

    page: str  # the page's id
    clicks: tuple[tuple[int, Click | None], ...]  # (n, click), n ascending; None: unread


def read_click(said: str) -> Click | None:
    """A click as the page said it, "kind|name"; None for anything else."""
    kind, _, name = said.partition("|")
    if kind not in KINDS or not name or len(name) > MAX_NAME or "|" in name:
        return None
    return Click(kind, name)


def read_batch(text: str) -> Batch | None:
    """The page's queue of clicks; None for anything that is not one."""
    try:
        data = read_json(text, "a page's clicks", MAX_BATCH_CHARS, max_depth=3)
    except JsonRefused as exc:
        log.warning("page clicks refused: %s", exc)
        return None
    if not (
        isinstance(data, dict)
        and set(data) == {"p", "s", "w"}
        and _is_page(data["p"])
        and _is_int(data["w"])
        and isinstance(data["s"], list)
        and len(data["s"]) <= MAX_QUEUE
    ):
        log.warning("page clicks refused: not a queue of clicks")
        return None
    clicks: list[tuple[int, Click | None]] = []
    for entry in data["s"]:
        if not (
            isinstance(entry, list)
            and len(entry) == 2
            and _is_int(entry[0])
            and isinstance(entry[1], str)
            and (not clicks or entry[0] > clicks[-1][0])
        ):
            log.warning("page clicks refused: an entry is not [n, click] with n ascending")
            return None
        clicks.append((entry[0], read_click(entry[1])))
    return Batch(data["p"], tuple(clicks))


def _is_int(value: Any) -> bool:
    return type(value) is int and 1 <= value <= MAX_N


def _is_page(value: Any) -> bool:
    return (
        isinstance(value, str)
        and 0 < len(value) <= MAX_PAGE
        and value.isascii()
        and value.isalnum()
    )


@dataclass
class Handled:
    """What of one page's clicks the server handled: the page's id and its newest n."""

    page: str = ""
    last: int = 0

    def take(self, batch: Batch) -> list[Click]:
        """The batch's clicks past the last handled, in order; its newest n is handled
        then (an unreadable click too: it is not sent again). A page loaded anew counts
        from 1 again."""
        if batch.page != self.page:
            self.page, self.last = batch.page, 0
        new = [(n, click) for n, click in batch.clicks if n > self.last]
        if new:
            self.last = new[-1][0]
        if any(click is None for _, click in new):
            log.warning("a page click was not read")
        return [click for _, click in new if click is not None]


class PageClicks:
    """The hidden input and its script in one page."""

    def __init__(self, client: viser.ClientHandle, on_click: Callable[[Click], None]) -> None:
        self.client = client
        self.on_click = on_click
        self.handled = Handled()
        self._lock = threading.Lock()  # a batch at a time, its clicks in order
        gui = client.gui
        self.box = gui.add_text(LABEL, "")
        self.box.on_update(lambda _: self.heard(self.box.value))
        self.script = gui.add_html(f'<img alt="" src="data:," onerror="{html.escape(_SCRIPT)}">')

    def heard(self, text: str) -> None:
        """The page's queue: its new clicks handled, its newest n acknowledged."""
        batch = read_batch(text)
        if batch is None:
            return
        with self._lock:
            for click in self.handled.take(batch):
                try:
                    self.on_click(click)
                except Exception:  # not into viser's thread: the next clicks still count
                    log.exception("a page click failed: %s", click)
            page, last = script_json(self.handled.page), self.handled.last
            run(
                self.client,
                ACK_CHANNEL,
                f"window.__padtClickAck&&window.__padtClickAck({page},{last})",
            )

    def remove(self) -> None:
        self.box.remove()
        self.script.remove()


def build(client: viser.ClientHandle, on_click: Callable[[Click], None]) -> PageClicks:
    """The hidden input and its script; `on_click` at each click the page reports."""
    return PageClicks(client, on_click)
