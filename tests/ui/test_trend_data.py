"""The Trends screen's data without a browser: the live history keeps the newest samples
in order in fixed memory, the chart's data shows a BOOL change as a vertical step and a
one-sample pulse after cutting 10 minutes to a few points, and the y axis stays still
while a signal moves inside it."""

from __future__ import annotations

import numpy as np
import pytest

from frontend import trend_plot
from frontend.trend_history import CAPACITY, TrendHistory


def test_the_history_keeps_the_newest_samples_in_order_in_fixed_memory() -> None:
    history = TrendHistory(capacity=100)
    history.follow(["a"])
    for i in range(250):
        history.add(1000.0 + i / 10, {"a": float(i)})
    times, columns = history.since(0.0)
    assert list(columns["a"]) == [float(i) for i in range(150, 250)]
    assert np.all(np.diff(times) > 0)
    assert abs(history.span_s() - 9.9) < 1e-9
    assert history.columns["a"].nbytes == 800  # no growth however long it runs

    # a variable added later has no past: NaN there, and only the window asked for
    history.follow(["a", "b"])
    history.add(1025.0, {"a": 1.0, "b": 2.0})
    times, columns = history.since(1024.85)
    assert list(columns["a"]) == [249.0, 1.0]
    assert np.isnan(columns["b"][0]) and columns["b"][1] == 2.0
    assert CAPACITY >= 600 * 10  # ten minutes at the feed's 10 Hz


def test_a_bool_change_is_a_step_and_a_number_stays_a_line() -> None:
    times = np.array([1.0, 2.0, 3.0])
    level = np.array([10.0, 20.0, 30.0])
    pump = np.array([0.0, 1.0, 1.0])
    x, y_level, y_pump = trend_plot.data(times, [level, pump], [False, True], None, 1000)
    assert list(x) == [1.0, 2.0, 2.0, 3.0]  # the change doubled at its time
    assert list(y_pump) == [0.0, 0.0, 1.0, 1.0]  # vertical at t=2
    assert list(y_level) == [10.0, 20.0, 20.0, 30.0]  # the same line


def test_ten_minutes_cut_to_few_points_keep_a_one_sample_pulse() -> None:
    times = np.arange(6000) / 10.0
    pulse = np.zeros(6000)
    pulse[3333] = 1.0
    x, y = trend_plot.data(times, [pulse], [False], None, 2000)
    assert x.size <= 2000 and y.max() == 1.0
    assert np.all(np.diff(x) >= 0)  # in time order, as uPlot needs


def test_the_window_is_drawn_whole_from_its_start() -> None:
    x, y = trend_plot.data(np.array([100.0]), [np.array([5.0])], [False], 70.0, 1000)
    assert list(x) == [70.0, 100.0] and np.isnan(y[0])


def test_the_y_axis_stays_still_while_the_signal_moves_inside_it() -> None:
    first = trend_plot.y_range([np.array([300.0, 800.0])], None)
    assert first == (280.0, 840.0)  # a margin, on round numbers
    assert trend_plot.y_range([np.array([0.0, 2000.0])], None) == (-100.0, 2100.0)
    assert trend_plot.y_range([np.array([5.0])], None) == (4.8, 5.2)  # a constant
    assert trend_plot.y_range([np.array([350.0, 700.0])], first) == first
    # far smaller: a new range that shows it
    small = trend_plot.y_range([np.array([500.0, 510.0])], first)
    assert small != first and small[0] <= 500 and small[1] >= 510
    assert trend_plot.y_range([np.array([np.nan])], None) == (0.0, 1.0)


def test_each_number_on_an_axis_of_its_own_or_all_on_one() -> None:
    charted = trend_plot.traces([("a", "INT"), ("b", "REAL"), ("c", "BOOL")])
    one = trend_plot.options(charted, [(0.0, 10.0)])
    assert [s.get("scale") for s in one["series"][1:]] == ["y", "y", "b"]
    # the BOOLs' lane at the bottom: the numbers' range reaches down below it, their
    # ticks stay in their own range
    low, high = one["scales"]["y"]["range"]
    assert high == 10.0 and (0.0 - low) / (high - low) == pytest.approx(trend_plot.BOOL_LANE)
    assert one["axes"][1]["splits"] == (0.0, 2.0, 4.0, 6.0, 8.0, 10.0)
    alone = trend_plot.options(charted[:2], [(0.0, 10.0)])  # no BOOL: no lane
    assert alone["scales"]["y"] == {"range": [0.0, 10.0]}
    each = trend_plot.options(charted, [(0.0, 10.0), (-1.0, 1.0)])
    assert [s.get("scale") for s in each["series"][1:]] == ["y0", "y1", "b"]
    assert each["scales"]["y1"]["range"][1] == 1.0
    # an axis each, in the variable's colour, and the BOOLs' on the right
    assert [a.get("scale") for a in each["axes"]] == [None, "y0", "y1", "b"]
    assert each["axes"][2]["stroke"] == charted[1].colour
