"""What the Online test sends the browser: the table of a page, and the patch of its value
cells that follows each new set of values; hostile strings stay text."""

from __future__ import annotations

import json
import re

from frontend.screens.online_test import render_patch, render_values

TYPES = {"P.s": "STRING", "P.t": "TIME", "P.b": "BOOL"}
HOSTILE = '</script><img src=x onerror="alert(1)">'


def test_the_patch_carries_each_cell_text_and_quality() -> None:
    values = {"P.s": HOSTILE, "P.t": 1_250_000_000, "P.b": True}
    patch = render_patch(["P.b", "P.t", "P.s", "P.gone"], TYPES, values, {"P.b": "forced"})
    data = re.search(r'<script type="application/json">(.*)</script>', patch)
    assert data is not None
    assert "</script>" not in data.group(1)  # a STRING cannot end the script element
    assert json.loads(data.group(1)) == {
        "P.b": ["TRUE", "forced"],
        "P.t": ["T#1s250ms", "live"],
        "P.s": [f"'{HOSTILE}'", "live"],
        "P.gone": ["not in this configuration", "unknown"],
    }


def test_the_table_escapes_names_and_values() -> None:
    page = render_values(["P.s"], TYPES, {"P.s": HOSTILE})
    assert HOSTILE not in page
    assert 'data-var="P.s" data-quality="live"' in page
