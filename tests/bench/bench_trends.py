"""The Trends screen's cost: first without a browser, what one browser's live history of 16
variables costs the UI server per sample, per redraw of a 30 s, 2 min and 10 min window
(full history: 11 minutes at 10 Hz) and in memory; then with headless Chromium against the
1,000-variable runtime of bench_ui, the CPU of the UI server and of Chromium with the 16
variables charted while another tab is in front (the history only collects), with the
Trends tab in front at 30 s, and at 10 min over a full history. Prints; asserts nothing."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np
from playwright.sync_api import Page

from frontend import trend_plot
from frontend.screens.trends import LIVE_POINTS, REDRAWS, Trends
from frontend.trend_history import CAPACITY, TrendHistory
from tests.bench.bench_ui import PASSWORD, _browser_pids, _cpu_s, _plant
from tests.support.browser import chromium
from tests.ui.browser_steps import choose, log_in, log_in_to_resource, state, wait_until

CHARTED = 16  # the most on one chart: 8 numbers, 8 BOOLs
MEASURE_S = 15.0
WINDOWS = {"30 s": 30, "2 min": 120, "10 min": 600}


def _full_history(now: float) -> tuple[TrendHistory, list[bool]]:
    """11 minutes of 16 variables at 10 Hz: random walks and BOOLs that switch now and then."""
    history = TrendHistory()
    paths = [f"v{i}" for i in range(CHARTED)]
    history.follow(paths)
    bools = [i % 2 == 1 for i in range(CHARTED)]
    rng = np.random.default_rng(1)
    level = np.zeros(CHARTED)
    for k in range(CAPACITY):
        level += rng.normal(size=CHARTED)
        sample = {
            path: float(k // 37 % 2) if is_bool else float(level[i])
            for i, (path, is_bool) in enumerate(zip(paths, bools, strict=True))
        }
        history.add(now - (CAPACITY - k) / 10, sample)
    return history, bools


def _without_browser() -> None:
    now = time.time()
    history, bools = _full_history(now)
    sample = {f"v{i}": float(i) for i in range(CHARTED)}
    collecting = TrendHistory()
    collecting.follow(sample)
    runs = 20_000
    started = time.perf_counter()
    for k in range(runs):
        collecting.add(now + k / 10, sample)
    per_sample_us = (time.perf_counter() - started) / runs * 1e6
    memory = history.times.nbytes + sum(c.nbytes for c in history.columns.values())
    print(
        f"trends: one browser's history of {CHARTED} variables: {memory / 1024:.0f} KiB, "
        f"{per_sample_us:.1f} us per sample (10 a second, the tab in view or not)"
    )
    for label, seconds in WINDOWS.items():
        rate = min(10.0, REDRAWS / seconds)  # redraws a second
        reps = 50
        started = time.perf_counter()
        for _ in range(reps):
            times, by_path = history.since(now - seconds)
            columns = list(by_path.values())
            numbers = [c for c, b in zip(columns, bools, strict=True) if not b]
            trend_plot.y_range(numbers, None)
            data = trend_plot.data(times, columns, bools, now - seconds, LIVE_POINTS)
        per_draw_ms = (time.perf_counter() - started) / reps * 1000
        sent = sum(a.nbytes for a in data)
        print(
            f"  window {label}: {times.size:,} samples -> {data[0].size:,} points a variable, "
            f"{per_draw_ms:.2f} ms and {sent / 1024:.0f} KiB per redraw, {rate:.1f} redraws/s: "
            f"{per_draw_ms * rate / 10:.1f}% of a core, {sent * rate / 1024:.0f} KiB/s"
        )


def _open(page: Page, url: str) -> None:
    page.goto(url)
    page.get_by_role("button", name="Log in", exact=True).wait_for()
    log_in(page, "admin", PASSWORD)
    log_in_to_resource(page, "admin", PASSWORD)
    wait_until("the resource runs", lambda: state(page) == "RUN", timeout_s=60)


def _chart(page: Page) -> None:
    page.get_by_role("tab", name="Trends").click()
    choose(page, "From watch list", "Trend16")
    page.get_by_role("button", name="Chart the watch list").click()
    wait_until(
        "16 variables charted",
        lambda: (
            page.evaluate(
                "() => Object.values(window.__viserTestpoints?.uplots ?? {})"
                ".map(c => c.chart.series.length)[0] ?? 0"
            )
            == CHARTED + 1
        ),
    )


def _cpu(label: str, runtime_pid: int) -> None:
    browser_pids = _browser_pids(runtime_pid)
    own, browsers = time.process_time(), _cpu_s(browser_pids)
    time.sleep(MEASURE_S)
    own = (time.process_time() - own) / MEASURE_S
    browsers = (_cpu_s(browser_pids) - browsers) / MEASURE_S
    print(f"  {label}: UI server {own:.0%} of a core, browser {browsers:.0%}")


def _with_browser() -> None:
    print(f"trends in Chromium, {CHARTED} variables of a 1,000-variable runtime (50 ms cycle):")
    with tempfile.TemporaryDirectory() as folder, _plant(Path(folder)) as (_, ui, runtime):
        paths = [f"Main.v{i:04d}" for i in range(CHARTED)]
        ui.context.watch_lists.put("admin", "Trend16", tuple(paths))
        with chromium() as browser:
            page = browser.new_context(viewport={"width": 1920, "height": 1080}).new_page()
            _open(page, ui.url)
            _cpu("nothing charted, the Resources tab in front", runtime)
            _chart(page)
            page.get_by_role("tab", name="Resources").click()
            _cpu("charted, another tab in front (the history collects)", runtime)
            page.get_by_role("tab", name="Trends").click()
            _cpu("Trends in front, window 30 s", runtime)
            session = next(iter(ui.browsers.values()))
            with session._drawing:  # the refresher's lock: no sample comes meanwhile
                assert session.workspace is not None
                screen = session.workspace.screen(Trends)
                assert screen is not None
                trends = screen.screen
                full, _ = _full_history(trends.clock())
                full.columns = dict(zip(trends.paths, full.columns.values(), strict=True))
                trends.history = full
            page.get_by_role("button", name="10 min").click()
            _cpu("Trends in front, window 10 min over 11 minutes of history", runtime)


def main() -> None:
    _without_browser()
    _with_browser()


if __name__ == "__main__":
    main()
