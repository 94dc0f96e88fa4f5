"""What a trend chart sends to the browser's uPlot: the variables that can be charted and
their values as numbers, the chart's series, scales and axes, and its data, cut to at most
so many points and with BOOLs drawn as steps. Used for the live history and for recordings.

Why the y range is chosen here and not by uPlot: uPlot ranges over the data, and one NaN
(no value yet: a variable charted later than the others) makes that range NaN and the
chart empty; a range fixed in steps also keeps the axis still while a live signal moves,
as a scope does."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

Floats = npt.NDArray[np.float64]

_INTEGERS = (
    "SINT INT DINT LINT USINT UINT UDINT ULINT BYTE WORD DWORD LWORD".split()  # noqa: SIM905
)
CHARTABLE = frozenset(("BOOL", "REAL", "LREAL", "TIME", "LTIME", *_INTEGERS))
MAX_CHARTED = 16  # variables on one chart
MAX_AXES = 4  # with an axis each, the first so many numbers have one (more crowd the chart)
COLOURS = (
    "#1971c2", "#e8590c", "#2f9e44", "#c2255c", "#7048e8", "#0c8599", "#f08c00", "#5c940d",
    "#862e9c", "#d6336c", "#1098ad", "#74b816", "#495057", "#a61e4d", "#364fc7", "#c92a2a",
)  # fmt: skip
# BOOLs are 0/1 steps in a lane of their own at the bottom of the chart, the lowest
# BOOL_LANE of its height, which the numbers' ranges leave free: 0 at 4 % of the height,
# 1 at 21 %. Without numbers they have the chart to themselves.
BOOL_LANE = 0.25
BOOL_RANGE = (-0.25, 5.6)
BOOL_ALONE_RANGE = (-0.1, 1.1)
_MS_PER_NS = 1e-6


@dataclass(frozen=True)
class Trace:
    path: str
    type: str  # IEC type
    colour: str

    @property
    def is_bool(self) -> bool:
        return self.type == "BOOL"

    @property
    def unit(self) -> str:
        return "ms" if self.type in ("TIME", "LTIME") else ""


def chartable(type_name: str) -> bool:
    return type_name.upper() in CHARTABLE


def traces(variables: Sequence[tuple[str, str]]) -> list[Trace]:
    """(path, type) of the variables to chart, each with its colour."""
    return [
        Trace(path, type_name.upper(), COLOURS[i % len(COLOURS)])
        for i, (path, type_name) in enumerate(variables)
    ]


def number(value: Any, type_name: str) -> float:
    """A value as the chart draws it: BOOL 0/1, TIME in ms; NaN (a gap) for what is no
    number and for a non-finite REAL (a recording writes those as text)."""
    if isinstance(value, bool):
        return 1.0 if value else 0.0
    if isinstance(value, int):
        return value * _MS_PER_NS if type_name.upper() in ("TIME", "LTIME") else float(value)
    if isinstance(value, float) and math.isfinite(value):
        return value
    return math.nan


def extremes(column: Floats) -> tuple[float, float] | None:
    """The lowest and highest value of a column, None when it has none."""
    finite = column[np.isfinite(column)]
    return (float(finite.min()), float(finite.max())) if finite.size else None


def shown(number: float, trace: Trace) -> str:
    """A number of the chart as the variable's type reads: TRUE/FALSE, a whole number,
    7 significant digits for REAL, ms for TIME; empty for none."""
    if not math.isfinite(number):
        return ""
    if trace.is_bool:
        return "TRUE" if number >= 0.5 else "FALSE"
    if trace.unit:
        return f"{number:.15g} ms"
    if trace.type in ("REAL", "LREAL"):
        return f"{number:.{15 if trace.type == 'LREAL' else 7}g}"
    return str(int(number))


# ---- the chart's options
_TIME_AXIS = (  # uPlot's table of time ticks with a 24-hour clock (its own is 12-hour)
    # tick step (s), format, then the prefix when the year/month/day/hour/minute/second
    # change between ticks, then mode 1: only the first tick of a change gets the prefix
    (3600, "{HH}:{mm}", "\n{YYYY}-{MM}-{DD}", None, "\n{YYYY}-{MM}-{DD}", None, None, None, 1),
    (60, "{HH}:{mm}", "\n{YYYY}-{MM}-{DD}", None, "\n{YYYY}-{MM}-{DD}", None, None, None, 1),
    (1, "{HH}:{mm}:{ss}", "\n{YYYY}-{MM}-{DD}", None, "\n{YYYY}-{MM}-{DD}", None, None, None, 1),
    (0.001, ":{ss}.{fff}", "\n{YYYY}-{MM}-{DD} {HH}:{mm}", None,
     "\n{YYYY}-{MM}-{DD} {HH}:{mm}", None, "\n{HH}:{mm}", None, 1),
)  # fmt: skip


def options(charted: Sequence[Trace], y_ranges: Sequence[tuple[float, float]]) -> dict[str, Any]:
    """add_uplot's keyword arguments but the data: a time axis; the numbers on the left, in
    one range (one item in `y_ranges`) or each in its own (an item per number, the first
    MAX_AXES with an axis in their colour); the BOOLs on their own axis on the right (0/1
    in the lower third); the cursor's values in uPlot's legend under the chart."""
    numbers = [trace for trace in charted if not trace.is_bool]
    each = len(y_ranges) > 1
    scale_of = {t.path: (f"y{k}" if each else "y") for k, t in enumerate(numbers)}
    series: list[dict[str, Any]] = [{"label": "time", "value": "{HH}:{mm}:{ss}.{fff}"}]
    for trace in charted:
        series.append(
            {
                "label": trace.path + (f" ({trace.unit})" if trace.unit else ""),
                "stroke": trace.colour,
                "width": 1.5,
                "scale": "b" if trace.is_bool else scale_of[trace.path],
                "points": {"show": False},
            }
        )
    lane = any(trace.is_bool for trace in charted) and bool(numbers)
    axes: list[dict[str, Any]] = [{"values": _TIME_AXIS, "space": 70}]
    scales: dict[str, Any] = {
        "x": {"time": True},
        "b": {"range": list(BOOL_RANGE if lane else BOOL_ALONE_RANGE)},
    }
    if each:
        for k, (trace, y_range) in enumerate(zip(numbers, y_ranges, strict=True)):
            scales[f"y{k}"] = {"range": list(_above_lane(y_range) if lane else y_range)}
            if k < MAX_AXES:
                colour = {"stroke": trace.colour, "ticks": {"stroke": trace.colour}}
                axis = {"scale": f"y{k}", "size": 56, "grid": {"show": k == 0}, **colour}
                axes.append({**axis, "splits": _ticks(y_range)} if lane else axis)
    else:
        scales["y"] = {"range": list(_above_lane(y_ranges[0]) if lane else y_ranges[0])}
        if numbers:
            axis = {"scale": "y", "size": 60}
            axes.append({**axis, "splits": _ticks(y_ranges[0])} if lane else axis)
    if any(trace.is_bool for trace in charted):
        axes.append(
            {
                "scale": "b",
                "side": 1 if numbers else 3,
                "splits": (0, 1),
                "values": ("FALSE", "TRUE"),
                "grid": {"show": not numbers},
                "size": 56,
            }
        )
    return {
        "series": tuple(series),
        "scales": scales,
        "axes": tuple(axes),
        "legend": {"live": True},
        "padding": (12, 8, 0, 0),  # room for the top label of the axes
        "cursor": {"drag": {"x": True, "y": False}, "focus": {"prox": 16}},
        "focus": {"alpha": 0.4},
    }


def _above_lane(y_range: tuple[float, float]) -> tuple[float, float]:
    """A numbers' range stretched down so that its values stay above the BOOLs' lane."""
    low, high = y_range
    return (_tidy(low - (high - low) * BOOL_LANE / (1 - BOOL_LANE)), high)


def _ticks(y_range: tuple[float, float]) -> tuple[float, ...]:
    """The numbers' ticks on round values of their own range: none in the BOOLs' lane."""
    low, high = y_range
    step = _round_step((high - low) / 5)
    return tuple(_tidy(k * step) for k in range(math.ceil(low / step), math.floor(high / step) + 1))


def y_range(columns: Sequence[Floats], shown: tuple[float, float] | None) -> tuple[float, float]:
    """The left axis' range: the values with a small margin, on round numbers; `shown` is
    kept while the values fill at least a third of it, so that the axis stays still."""
    finite = [column[np.isfinite(column)] for column in columns]
    finite = [values for values in finite if values.size]
    if not finite:
        return shown or (0.0, 1.0)
    low = float(min(values.min() for values in finite))
    high = float(max(values.max() for values in finite))
    fits = shown is not None and shown[0] <= low and high <= shown[1]
    if shown is not None and fits and high - low >= (shown[1] - shown[0]) / 3:
        return shown
    span = high - low if high > low else max(abs(high), 1.0)
    # the ticks come every `step`; the ends fall on a fifth of it, a little outside the
    # values, so that a line at 0 or at a limit does not lie on the chart's edge
    grain = _round_step(span / 4) / 5
    bottom = math.floor((low - span * 0.03) / grain) * grain
    top = math.ceil((high + span * 0.03) / grain) * grain
    return (_tidy(bottom), _tidy(top))


def _tidy(number: float) -> float:
    """4.8 rather than 4.800000000000001 (the axis shows the range's ends)."""
    return float(f"{number:.12g}")


def _round_step(rough: float) -> float:
    """1, 2 or 5 times a power of ten, at least `rough`."""
    power = 10.0 ** math.floor(math.log10(rough))
    return next(m * power for m in (1, 2, 5, 10) if m * power >= rough)


# ---- the chart's data
def data(
    times: Floats,
    columns: Sequence[Floats],
    bools: Sequence[bool],
    start_s: float | None,
    max_points: int,
) -> tuple[Floats, ...]:
    """(x, y1, y2, ...) for uPlot: from `start_s` on (an empty first point there, so that
    the whole window is drawn however little history there is), at most about
    `max_points` points (the lowest and highest value of each stretch: a short pulse
    stays visible), each BOOL change a vertical step."""
    if start_s is not None and (times.size == 0 or times[0] > start_s):
        times = np.r_[start_s, times]
        columns = [np.r_[np.nan, column] for column in columns]
    if times.size > max_points:
        times, columns = _decimate(times, columns, max_points // 2)
    if any(bools) and times.size > 1:
        times, columns = _steps(times, columns, bools)
    return (times, *columns)


def _decimate(
    times: Floats, columns: Sequence[Floats], buckets: int
) -> tuple[Floats, list[Floats]]:
    """Per stretch of samples: its first and last time, with the lowest and the highest
    value of each column (NaN only where the stretch has no value at all)."""
    size = math.ceil(times.size / buckets)
    starts = np.arange(0, times.size, size)
    ends = np.minimum(starts + size, times.size) - 1
    x = np.column_stack((times[starts], times[ends])).ravel()
    out = []
    for column in columns:
        low = np.fmin.reduceat(column, starts)
        high = np.fmax.reduceat(column, starts)
        out.append(np.column_stack((low, high)).ravel())
    return x, out


def _steps(
    times: Floats, columns: Sequence[Floats], bools: Sequence[bool]
) -> tuple[Floats, list[Floats]]:
    """A point doubled where a BOOL changes: the first copy holds the BOOLs' old values,
    the numbers' new ones (a number's line stays a line, a BOOL's becomes a step)."""
    flags = np.vstack([column for column, is_bool in zip(columns, bools, strict=True) if is_bool])
    flags = np.nan_to_num(flags, nan=-1.0)  # no value yet, then no value: no change
    changed = np.zeros(times.size, dtype=bool)
    changed[1:] = np.any(flags[:, 1:] != flags[:, :-1], axis=0)
    repeats = 1 + changed.astype(np.intp)
    firsts = (np.cumsum(repeats) - repeats)[changed]  # where each doubled point's copy 1 is
    previous = np.flatnonzero(changed) - 1
    out = []
    for column, is_bool in zip(columns, bools, strict=True):
        doubled = np.repeat(column, repeats)
        if is_bool:
            doubled[firsts] = column[previous]
        out.append(doubled)
    return np.repeat(times, repeats), out
