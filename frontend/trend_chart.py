"""One uPlot chart of the Trends screen in the browser: in its place in a tab, under a note
that stands in for it while nothing is charted. New data replaces the chart's data; other
variables or another y range make the chart anew (see `draw`)."""

from __future__ import annotations

import html
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import viser

from frontend import trend_plot
from frontend.trend_plot import Floats, Trace

HEIGHT = 430  # px: most of a 900-pixel window under the tab bar and the scope's bar
AXIS_EACH, AXIS_ONE = "Axis per variable", "One axis"  # the button that switches between


@dataclass
class TrendChart:
    gui: viser.GuiApi
    container: viser.GuiTabHandle
    placeholder: viser.GuiHtmlHandle  # shown instead of the chart while nothing is charted
    plot: viser.GuiUplotHandle | None = None
    charted: tuple[Trace, ...] = ()  # what `plot` was made for
    y_ranges: tuple[tuple[float, float], ...] = ()  # one for all numbers, or one each
    extremes: dict[str, tuple[float, float] | None] = field(default_factory=dict)  # drawn
    drawn_at: float = -math.inf  # when (the screen's clock) it was last drawn

    def draw(
        self,
        charted: Sequence[Trace],
        times: Floats,
        columns: Sequence[Floats],
        start_s: float | None,
        max_points: int,
        own_axes: bool = False,
    ) -> None:
        """Show these variables' values at these times (Unix seconds), from `start_s` on
        when given, in at most about `max_points` points; the numbers in one range, or
        with `own_axes` each in its own."""
        charted = tuple(charted)
        if not charted:
            self.clear()
            return
        numbers = [c for c, t in zip(columns, charted, strict=True) if not t.is_bool]
        if own_axes and len(numbers) > 1:
            before = self.y_ranges if len(self.y_ranges) == len(numbers) else (None,) * len(numbers)
            y_ranges = tuple(
                trend_plot.y_range([c], shown) for c, shown in zip(numbers, before, strict=True)
            )
        else:
            shared = self.y_ranges[0] if len(self.y_ranges) == 1 else None
            y_ranges = (trend_plot.y_range(numbers, shared),)
        bools = [t.is_bool for t in charted]
        data = trend_plot.data(times, columns, bools, start_s, max_points)
        # Other variables or another y range: a chart made anew rather than changed.
        # viser carries the x zoom over a rebuild of its uPlot as a fraction of the data's
        # span, and the rebuild that new scales cause left the time axis at 1970.
        if self.plot is None or charted != self.charted or y_ranges != self.y_ranges:
            if self.plot is not None:
                self.plot.remove()
            with self.container:  # in the chart's place, right under the placeholder
                self.plot = self.gui.add_uplot(
                    data,
                    height=HEIGHT,
                    order=self.placeholder.order + 0.001,
                    **trend_plot.options(charted, y_ranges),
                )
            self.charted, self.y_ranges = charted, y_ranges
            self.placeholder.visible = False
        else:
            self.plot.data = data
        self.extremes = {
            t.path: trend_plot.extremes(c) for t, c in zip(charted, columns, strict=True)
        }

    def clear(self) -> None:
        if self.plot is not None:
            self.plot.remove()
            self.plot = None
        self.charted, self.y_ranges, self.extremes = (), (), {}
        self.placeholder.visible = True


# ---- the table under a chart
# uPlot's legend (the values under the cursor) is small and pale in viser: read at a glance
LEGEND_STYLE = (
    "<style>.uplot .u-legend{font-size:0.8em}.uplot .u-legend .u-value{color:#212529;"
    "font-family:monospace}</style>"
)
_TABLE_STYLE = (
    "<style>.trv{width:calc(100% - 24px);margin:0 14px 0 10px;font-size:0.85em;"
    "border-collapse:collapse}.trv td,.trv th{padding:1px 6px;border-bottom:1px solid #f1f3f5}"
    ".trv th{color:#868e96;font-weight:500;text-align:left}.trv .t{color:#868e96}"
    ".trv .v{text-align:right;font-family:monospace;white-space:nowrap}"
    ".trv .sw{display:inline-block;width:18px;height:3px;vertical-align:middle}</style>"
)


def table_row(trace: Trace, extremes: tuple[float, float] | None, now: str | None) -> str:
    """A variable's row: its colour, path, type, current value (when there is one) and
    the lowest and highest value in the chart."""
    name = html.escape(trace.path)
    low, high = extremes or (math.nan, math.nan)
    current = "" if now is None else f'<td class="v" data-trend="{name}">{html.escape(now)}</td>'
    return (
        f'<tr><td><span class="sw" style="background:{trace.colour}"></span></td>'
        f'<td>{name}</td><td class="t">{html.escape(trace.type)}</td>{current}'
        f'<td class="v">{trend_plot.shown(low, trace)}</td>'
        f'<td class="v">{trend_plot.shown(high, trace)}</td></tr>'
    )


def table(rows: Sequence[str], with_now: bool, testid: str) -> str:
    now = '<th style="text-align:right">Now</th>' if with_now else ""
    return (
        f'{_TABLE_STYLE}<table class="trv" data-testid="{testid}"><tr><th style="width:22px">'
        f"</th><th>Variable</th><th>Type</th>{now}"
        '<th style="text-align:right">Min in chart</th>'
        '<th style="text-align:right">Max in chart</th></tr>' + "".join(rows) + "</table>"
    )
