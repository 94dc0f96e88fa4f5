"""What every live drawing shares: the qualities' colours (those of the Online test), a
value as text, the attributes that make a drawn value clickable (the page reports a click
on an element with `data-logic-var`, frontend/page_clicks.py), and the live parts of a
drawing (`Live`).

A drawing is sent to the browser whole only when it changes (another instance, a field
placed); new values travel as a patch of its live parts, which the browser applies to the
drawing it has: a third of the bytes (2 kB against 6-8 kB for the test bodies), and the
drawing under the user's pointer stays (a drawing replaced ten times a second loses the
clicks that fall between two of them)."""

from __future__ import annotations

import html
import json
from typing import Any

from runtime.contract.values import format_for_display

ACTIVE = "#2f9e44"  # TRUE, an active step, power flow
ACTIVE_FILL = "#d3f9d8"
IDLE = "#495057"
MUTED = "#adb5bd"
FORCED = "#c92a2a"  # as the Online test marks a forced value


def escape(text: str) -> str:
    return html.escape(text, quote=True)


def shown(
    path: str, values: dict[str, Any], types: dict[str, str], quality: dict[str, str]
) -> tuple[str, str]:
    """(text, quality) of a variable's value: "…"/"waiting" before its first value."""
    if path not in values or path not in types:
        return "…", "waiting"
    return format_for_display(values[path], types[path]), quality.get(path, "live")


def clickable(path: str) -> str:
    """The attributes of a drawn value that a click chooses for writing or forcing."""
    return f'data-logic-var="{escape(path)}" style="cursor:pointer"'


def value_color(text: str, how: str) -> str:
    if how == "forced":
        return FORCED
    if how in ("stale", "waiting", "deleted", "bad"):
        return MUTED
    return ACTIVE if text == "TRUE" else IDLE


class Live:
    """The live parts of one drawing, in the order it is drawn (so that each part has the
    same key in every drawing of the same body): each an element whose text and
    attributes follow the values."""

    def __init__(self) -> None:
        self.parts: dict[str, tuple[str | None, dict[str, str]]] = {}

    def node(self, attributes: dict[str, str], text: str | None = None) -> str:
        """The attributes of a live element, its key among them; `text`: its text too."""
        key = str(len(self.parts))
        self.parts[key] = (text, attributes)
        shown = "".join(f' {name}="{escape(value)}"' for name, value in attributes.items())
        return f'data-k="{key}"{shown}'

    def text(self, text: str) -> str:
        """A live text (a tspan: the element around it keeps its title)."""
        return f"<tspan {self.node({}, text)}>{escape(text)}</tspan>"

    def patch(self, drawing: str) -> str:
        """The live parts as an invisible patch the browser applies to the drawing whose
        element has data-testid `drawing`."""
        data = json.dumps({k: [text, attrs] for k, (text, attrs) in self.parts.items()})
        data = data.replace("<", "\\u003c")  # nothing in a <script> element's text may close it
        apply = (
            "var d=JSON.parse(this.previousElementSibling.textContent);"
            f"var r=document.querySelector('[data-testid={drawing}]');if(!r)return;"
            "r.querySelectorAll('[data-k]').forEach(function(n){var v=d[n.dataset.k];"
            "if(!v)return;if(v[0]!==null&&n.textContent!==v[0])n.textContent=v[0];"
            "for(var a in v[1]){if(n.getAttribute(a)!==v[1][a])n.setAttribute(a,v[1][a])}});"
        )
        return (
            f'<div style="display:none"><script type="application/json">{data}</script>'
            f'<img alt="" src="data:," onerror="{escape(apply)}"></div>'
        )
