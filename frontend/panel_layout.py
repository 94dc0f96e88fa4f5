"""The workspace's layout as each user leaves it: the panels' widths and folds the page
reports after the user dragged an edge or folded a panel (frontend/page_clicks.py), kept
by `backend/engineering/user_layouts.py` and put back at the next login."""

from __future__ import annotations

from dataclasses import dataclass, replace

import viser

from backend.engineering.user_layouts import MAX_WIDTH, MIN_WIDTH, Layout


@dataclass(frozen=True)
class PanelsSeen:
    navigation: int  # 0 while folded
    navigation_folded: bool
    work: int
    work_folded: bool


def read(text: str) -> PanelsSeen | None:
    """ "<left>x<folded>x<right>x<folded>" as the page reported it; None for anything else."""
    parts = text.split("x")
    if len(parts) != 4 or not all(part.isdigit() and len(part) <= 5 for part in parts):
        return None
    left, left_folded, right, right_folded = (int(part) for part in parts)
    if left_folded > 1 or right_folded > 1:
        return None
    return PanelsSeen(left, left_folded == 1, right, right_folded == 1)


def kept(layout: Layout, seen: PanelsSeen) -> Layout:
    """`layout` with what the page saw: a folded panel keeps the width it had, a width
    outside what a panel can be is not taken."""
    return replace(
        layout,
        navigation_width=_width(seen.navigation, layout.navigation_width),
        work_width=_width(seen.work, layout.work_width),
        navigation_folded=seen.navigation_folded,
        work_folded=seen.work_folded,
    )


def _width(seen: int, before: int | None) -> int | None:
    return seen if MIN_WIDTH <= seen <= MAX_WIDTH else before


def put_back(gui: viser.GuiApi, work_panel: viser.PanelHandle, layout: Layout) -> None:
    """The navigation's width and both folds as the user left them (the work panel's
    width is the workspace's to choose within the window: `Layout.work_width` is what
    it prefers)."""
    if layout.navigation_width is not None:
        gui.main_panel.set_width(layout.navigation_width)
    if layout.navigation_folded:
        gui.main_panel.minimize()
    if layout.work_folded:
        work_panel.minimize()
