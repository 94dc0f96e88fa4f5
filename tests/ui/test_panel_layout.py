"""What the page reports of the panels is read as untrusted text."""

from __future__ import annotations

from backend.engineering.user_layouts import Layout
from frontend.panel_layout import PanelsSeen, kept, read


def test_what_the_page_reports_is_read_as_untrusted_text() -> None:
    assert read("300x0x784x1") == PanelsSeen(300, False, 784, True)
    for text in ("", "300x0x784", "300x2x784x0", "-1x0x784x0", "1e3x0x1x0", "999999x0x1x0"):
        assert read(text) is None, text
    # a folded panel keeps the width it had; a width no panel has is not taken
    before = Layout(navigation_width=350, work_width=700)
    assert kept(before, PanelsSeen(0, True, 10, False)) == Layout(350, 700, True, False)
