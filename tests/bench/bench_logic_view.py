"""The Logic screen's cost: a program whose body is an FBD drawing of 200 elements (50
chains of two inputs, a block and an output, laid on a grid as an editor places them),
every value on it changing every 100 ms cycle, in a real runtime process, drawn live in one
headless Chromium. Measures the drawing (from the click that chooses the instance to the
drawing in the page, and what the UI server spends making it), the latency from a write in
the runtime to the new value in the page, the updates the page receives a second, and the
CPU of the UI server (this process), of the runtime and of the browser with the drawing in
front and with another tab in front. Prints; asserts nothing."""

from __future__ import annotations

import itertools
import os
import statistics
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

from playwright.sync_api import Page

from backend.engineering.logic_view import LiveGraphic, LogicBodies
from backend.engineering.padt_accounts import PadtAccounts, write_accounts
from backend.engineering.project import PROJECT_FILE, compile_project, load_project, user_entry
from backend.engineering.resource_client import ResourceClient
from backend.engineering.resource_directory import ResourceDirectory
from backend.engineering.sources import find_sources
from backend.engineering.watch_lists import WatchLists
from frontend.app import PadtUi
from frontend.logic_view import fbd_ld
from frontend.logic_view.svg import Live
from frontend.resource_feed import latest_reading
from frontend.screens.logic import DRAWING
from frontend.ui_context import UiContext
from runtime.contract import protocol as p
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from tests.bench.bench_ui import _browser_pids, _cpu_s, _descendants
from tests.conftest import free_port
from tests.support.browser import chromium
from tests.support.runtime_process import running_resource, store_artifact
from tests.ui.browser_steps import PASSWORD, choose, log_in, log_in_to_resource, state, wait_until

CHAINS = 50  # of 4 elements each: 200
CYCLE_MS = 100
RESOURCE = "Bench"
BIG, SMALL = "Main", "Small"  # the 200-element instance; a 4-element one to switch to
MARKER = "mark"  # a global both drawings read (an IN) and no program writes: the bench does
DRAWS = 5  # times the big drawing is chosen
MEASURE_S = 20.0
MARKS = 40
MARK_GAP_S = 0.4
SERVER_REPS = 20
KNOWN_RESOURCES = "PADT_KNOWN_RESOURCES"
T = TypeVar("T")

# When a click was last, and when each new drawing came into the page (whose: the instance
# its values belong to) and the frame after it (laid out and painted). A drawing is replaced
# whole only when another is chosen; new values change its attributes.
OBSERVE_DRAWING = """() => {
  window.__clicked = 0; window.__draws = []; window.__painted = [];
  document.addEventListener('click', () => { window.__clicked = Date.now(); }, true);
  let last = null;
  new MutationObserver(() => {
    const svg = document.querySelector('[data-testid=drawing]');
    if (!svg || svg === last) return;
    last = svg;
    const who = svg.querySelector('[data-value-of^="Small."]') ? 'Small' : 'Main';
    const at = window.__clicked;
    window.__draws.push([who, at, Date.now()]);
    requestAnimationFrame(() => setTimeout(() => window.__painted.push([who, at, Date.now()])));
  }).observe(document.body, {childList: true, subtree: true});
}"""

# Each new value of the count and of the marker as the drawing in the page shows it, with the
# time (again for each drawing); once, the patches of values that came (their number and the
# characters of their data) and the page's long tasks.
OBSERVE_VALUES = """() => {
  window.__counts = []; window.__marks = [];
  const drawing = document.querySelector('[data-testid=drawing]');
  let count = null, mark = null;
  new MutationObserver(() => {
    const c = drawing.querySelector('[data-value-of="Main.count"]')?.getAttribute('data-value');
    const m = drawing.querySelector('[data-value-of="mark"]')?.getAttribute('data-value');
    const now = Date.now();
    if (c !== count) { count = c; window.__counts.push([Number(c), now]); }
    if (m !== mark) { mark = m; window.__marks.push([Number(m), now]); }
  }).observe(drawing, {subtree: true, attributes: true, attributeFilter: ['data-value']});
  if (window.__patches) return;
  window.__patches = {count: 0, chars: 0};
  new MutationObserver((changes) => {
    for (const change of changes) for (const node of change.addedNodes) {
      const data = node.querySelectorAll?.('script[type="application/json"]') ?? [];
      for (const script of data) {
        window.__patches.count += 1; window.__patches.chars += script.textContent.length;
      }
    }
  }).observe(document.body, {childList: true, subtree: true});
  window.__long = {count: 0, ms: 0};  // the page's main thread busy 50 ms or more at once
  new PerformanceObserver((list) => {
    for (const task of list.getEntries()) {
      window.__long.count += 1; window.__long.ms += task.duration;
    }
  }).observe({type: 'longtask'});
}"""


def _chain(n: int) -> tuple[list[str], list[str]]:
    """Chain `n` of the drawing (4 elements, ids 4n+1..4n+4) at its place on a grid of 5
    columns: its element lines and its variables' declarations."""
    x, y = 20 + n // 10 * 460, 20 + n % 10 * 100
    first, second, block, out = (4 * n + k for k in (1, 2, 3, 4))
    at_in1, at_in2 = f"at {x} {y + 8} size 90 26", f"at {x} {y + 48} size 90 26"
    at_block, at_out = f"at {x + 150} {y} size 80 80 order {n + 1}", f"at {x + 300} {y + 28}"
    kind = ("ADD", "MUL", "GT", "TON")[n % 4]
    if n == 0:  # the counter, +1 every cycle: every other chain reads it
        inputs, kind, target, declared = ("count", "1"), "ADD", "count", []
    elif n == 1:  # its parity, to switch the comparisons every cycle
        inputs, kind, target, declared = ("count", "2"), "MOD", "par", ["par : DINT;"]
    elif n == 2:  # the marker, which the bench writes
        inputs, kind, target, declared = ("count", "mark"), "ADD", "r2", ["r2 : DINT;"]
    elif kind == "GT":
        inputs, target, declared = ("par", "0"), f"b{n}", [f"b{n} : BOOL;"]
    elif kind == "TON":  # restarts when it ends: its ET runs every cycle
        inputs, target = (f"t{n}.Q", f"T#{300 + 100 * (n % 5)}ms"), f"q{n}"
        declared = [f"t{n} : TON;", f"q{n} : BOOL;"]
    else:
        inputs, target = ("count", f"v{n}"), f"r{n}"
        declared = [f"v{n} : DINT := {n};", f"r{n} : DINT;"]
    if kind == "TON":
        call = f"BLOCK TON t{n} (IN := NOT {first}, PT := {second}) -> (Q, ET)"
        result = f"{block}.Q"
    else:
        call = f"BLOCK {kind} (IN1 := {first}, IN2 := {second}) -> (OUT)"
        result = f"{block}.OUT"
    lines = [
        f"  {first}: IN {inputs[0]} {{{at_in1}}}",
        f"  {second}: IN {inputs[1]} {{{at_in2}}}",
        f"  {block}: {call} {{{at_block}}}",
        f"  {out}: OUT {target} := {result} {{{at_out} size 90 26}}",
    ]
    return lines, declared


def _sources() -> str:
    chains = [_chain(n) for n in range(CHAINS)]
    declared = "".join(f"  {d}\n" for _, names in chains for d in names)
    body = "".join(f"{line}\n" for lines, _ in chains for line in lines)
    return (
        "VAR_GLOBAL\n  mark : DINT;\nEND_VAR\n\n"
        "PROGRAM Drawn200\nVAR_EXTERNAL\n  mark : DINT;\nEND_VAR\n"
        f"VAR\n  count : DINT;\n{declared}END_VAR\nFBD\n{body}END_FBD\n"
        "END_PROGRAM\n\n"
        "PROGRAM Tiny\nVAR_EXTERNAL\n  mark : DINT;\nEND_VAR\nVAR\n  n : DINT;\nEND_VAR\nFBD\n"
        "  1: IN mark {at 20 20 size 70 26}\n  2: IN 1 {at 20 60 size 70 26}\n"
        "  3: BLOCK ADD (IN1 := 1, IN2 := 2) -> (OUT) {at 150 10 size 70 70}\n"
        "  4: OUT n := 3.OUT {at 290 30 size 70 26}\nEND_FBD\nEND_PROGRAM\n"
    )


PROJECT_TOML = f"""\
[project]
name = "LogicBench"
version = "0.1"

[resource]
name = "{RESOURCE}"
target_cycle_ms = {CYCLE_MS}
target_cycle_mode = "fixed"
autostart = "cold"
safety_operation = false

[[resource.program]]
name = "{BIG}"
pou = "Drawn200"
id = 1
priority = 0

[[resource.program]]
name = "{SMALL}"
pou = "Tiny"
id = 2
priority = 1
"""


@contextmanager
def _plant(folder: Path) -> Iterator[tuple[ResourceClient, PadtUi, int, Path]]:
    """The project compiled and running in a runtime process, an administrator on it and on
    the PADT, and a UI that knows the project; yields a client of the resource, the UI,
    the runtime's process id and the project's folder."""
    project = folder / "project"
    project.mkdir()
    admin = UserAccount("admin", "administrator", hash_password(PASSWORD))
    (project / PROJECT_FILE).write_text(PROJECT_TOML + "\n" + user_entry(admin))
    (project / "drawn.st").write_text(_sources())
    result = compile_project(load_project([project]))
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    store_artifact(folder, result.artifact)
    accounts_file = folder / "padt-accounts.json"
    padt_admin = UserAccount("admin", "security-administrator", admin.password_hash)
    write_accounts(accounts_file, (padt_admin,))
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    # the runtime's new signing key pinned here, apart from the user's own resources
    pinned = os.environ.get(KNOWN_RESOURCES)
    os.environ[KNOWN_RESOURCES] = str(folder / "known_resources")
    try:
        with running_resource(RESOURCE, folder, endpoint) as (runtime, client):
            client.login("admin", PASSWORD)
            context = UiContext(
                ResourceDirectory(client.session),
                PadtAccounts(accounts_file, time.monotonic_ns),
                endpoint,
                WatchLists(folder / "watch-lists.json"),
                {"project": project},
                folder / "bak",
            )
            ui = PadtUi(context, port=free_port())
            try:
                yield client, ui, runtime.pid, project
            finally:
                ui.close()
    finally:
        if pinned is None:
            del os.environ[KNOWN_RESOURCES]
        else:
            os.environ[KNOWN_RESOURCES] = pinned


def _server_side(ui: PadtUi, project: Path) -> None:
    """What the UI server spends on the drawing: finding the sources of the running
    configuration (once per configuration), parsing and laying out the body (once per
    instance chosen), and, as the screen does at every refresh, the drawing with the values
    now and its patch (only the patch is sent while the drawing stays). Timed with the
    browser's refreshes held (the refresher's lock), the median of SERVER_REPS calls."""
    session = next(iter(ui.browsers.values()))
    status, values, types, quality = latest_reading(session.feed_of(RESOURCE))
    assert status is not None and status.crc is not None
    crc = status.crc
    with session._drawing:
        found_ms, found = _timed(lambda: find_sources(crc, {"project": project}), 1)
        assert found is not None
        sources = found
        bodies = LogicBodies(sources)
        cold_ms, graphic = _timed(lambda: bodies.graphic(BIG, types), 1)
        warm_ms, _ = _timed(lambda: bodies.graphic(BIG, types), SERVER_REPS)
        assert graphic is not None
        drawn = graphic
        svg_ms, (svg, live) = _timed(lambda: _drawing(drawn, values, types, quality), SERVER_REPS)
        patch_ms, patch = _timed(lambda: live.patch(DRAWING), SERVER_REPS)
    print(
        f"  server side: the project's sources found in {found_ms:.0f} ms (once per "
        f"configuration); the body parsed and laid out in {cold_ms:.0f} ms, {warm_ms:.1f} ms "
        f"parsed already (once per instance chosen): {len(drawn.parts)} parts, "
        f"{len(drawn.values)} values drawn, {len(drawn.watched())} variables watched"
    )
    print(
        f"  every refresh: the drawing with its values made in {svg_ms:.1f} ms "
        f"({len(svg) / 1024:.0f} KiB, sent only when the instance changes), its patch in "
        f"{patch_ms:.1f} ms ({len(patch) / 1024:.1f} KiB: every value and wire state, sent "
        "when one changed)"
    )


def _drawing(
    graphic: LiveGraphic, values: dict[str, Any], types: dict[str, str], quality: dict[str, str]
) -> tuple[str, Live]:
    live = Live()
    return fbd_ld.graphic_svg(graphic, values, types, quality, [], live), live


def _timed(call: Callable[[], T], reps: int) -> tuple[float, T]:
    """The median milliseconds of `reps` calls, and the last call's result."""
    took = []
    for _ in range(reps):
        started = time.perf_counter()
        result = call()
        took.append((time.perf_counter() - started) * 1000)
    return statistics.median(took), result


def _open(page: Page, url: str) -> None:
    page.goto(url)
    page.get_by_role("button", name="Log in", exact=True).wait_for()
    log_in(page, "admin", PASSWORD)
    log_in_to_resource(page, "admin", PASSWORD)
    wait_until("the resource runs", lambda: state(page) == "RUN", timeout_s=60)
    page.get_by_role("tab", name="Logic").click()
    page.evaluate(OBSERVE_DRAWING)


def _draws(page: Page) -> None:
    """Choose the small and the big instance in turn; the time from the click on the big one
    to its drawing in the page, and to the frame after (laid out and painted)."""
    first = 0
    for _ in range(DRAWS):
        for who in (SMALL, BIG):
            choose(page, "Instance", who)
            wait_until(f"{who}'s drawing is in the page", _drawn(page, who), timeout_s=60)
            first = first or page.evaluate("window.__clicked")
    wait_until(
        "the last drawing is painted",
        lambda: len(page.evaluate("window.__painted")) == len(page.evaluate("window.__draws")),
    )
    draws = page.evaluate("window.__draws")
    painted = page.evaluate("window.__painted")
    big = [done - at for who, at, done in draws if who == BIG and at >= first]
    shown = [done - at for who, at, done in painted if who == BIG and at >= first]
    small = [done - at for who, at, done in draws if who == SMALL and at >= first]
    print(
        f"  drawing in Chromium, click on the instance -> drawing in the page: "
        f"{CHAINS * 4} elements median {statistics.median(big):.0f} ms "
        f"(max {max(big):.0f}), painted {statistics.median(shown):.0f} ms; "
        f"4 elements {statistics.median(small):.0f} ms ({len(big)} draws each)"
    )


def _drawn(page: Page, who: str) -> Callable[[], bool]:
    """Whether the last drawing that came into the page is `who`'s, after the last click."""
    script = (
        "(() => { const d = window.__draws.at(-1);"
        " return d && d[0] + ':' + (d[1] === window.__clicked); })()"
    )
    return lambda: page.evaluate(script) == f"{who}:true"


def _cpu(label: str, runtime: list[int], browser: list[int], page: Page | None) -> dict[str, float]:
    """CPU seconds a wall second over MEASURE_S: the UI server (this process: the viser
    server, the router and the resource clients), the runtime, the browser; with `page`,
    what its websocket received and the count's new values it drew."""
    if page is not None:
        page.evaluate("window.__counts = []")
        patches = page.evaluate("window.__patches")
        long = page.evaluate("window.__long")
    own, run, view = _cpu_s([os.getpid()]), _cpu_s(runtime), _cpu_s(browser)
    started = time.monotonic()
    time.sleep(MEASURE_S)
    wall = time.monotonic() - started
    figures = {
        "ui": (_cpu_s([os.getpid()]) - own) / wall,
        "runtime": (_cpu_s(runtime) - run) / wall,
        "browser": (_cpu_s(browser) - view) / wall,
    }
    line = f"  {label}: UI server {figures['ui']:.1%} of a core, runtime {figures['runtime']:.1%}"
    if browser:
        line += f", browser {figures['browser']:.0%}"
    if page is not None:
        now = page.evaluate("window.__patches")
        counts = page.evaluate("window.__counts")
        figures["patches"] = (now["count"] - patches["count"]) / wall
        figures["kib"] = (now["chars"] - patches["chars"]) / 1024 / wall
        busy = page.evaluate("window.__long")
        figures["long_tasks"] = (busy["count"] - long["count"]) / wall
        figures["long_ms"] = (busy["ms"] - long["ms"]) / wall
        figures["updates"] = len(counts) / wall
        steps = [b[0] - a[0] for a, b in itertools.pairwise(counts)]
        if figures["patches"]:
            line += (
                f"; the page received {figures['patches']:.1f} patches of values/s "
                f"({figures['kib']:.0f} KiB/s of data) and drew {figures['updates']:.1f} "
                "new counts/s"
            )
        if steps:
            line += f" (count +{statistics.median(steps):.0f} per update, median)"
        line += (
            f"; its main thread in long tasks (50 ms or more) {figures['long_tasks']:.1f}/s, "
            f"{figures['long_ms']:.0f} ms/s"
        )
    print(line)
    return figures


def _latency(client: ResourceClient, page: Page, label: str, first: int) -> tuple[float, float]:
    """Write the marker MARKS times; from each write to the page showing its value: the
    median and the 95th percentile."""
    written: dict[int, float] = {}
    for mark in range(first, first + MARKS):
        written[mark] = time.time() * 1000
        client.ask(p.Write(MARKER, mark))
        time.sleep(MARK_GAP_S)
    time.sleep(1.0)
    seen = {int(value): at for value, at in page.evaluate("window.__marks") if value is not None}
    latencies = sorted(seen[mark] - at for mark, at in written.items() if mark in seen)
    median, p95 = statistics.median(latencies), latencies[int(0.95 * (len(latencies) - 1))]
    print(
        f"  write of {MARKER} in the runtime -> its value in the {label}: "
        f"median {median:.0f} ms, p95 {p95:.0f} ms, max {latencies[-1]:.0f} ms "
        f"({len(latencies)} of {MARKS} writes seen)"
    )
    return median, p95


def main() -> None:
    print(
        f"logic view: an FBD body of {CHAINS * 4} elements, every value changing every "
        f"{CYCLE_MS} ms cycle, live in one Chromium"
    )
    with tempfile.TemporaryDirectory() as folder, _plant(Path(folder)) as plant:
        client, ui, runtime_pid, project = plant
        runtime = [runtime_pid, *_descendants(runtime_pid)]
        quiet = _cpu("no browser", runtime, [], None)
        with chromium() as browser:
            context = browser.new_context(viewport={"width": 1920, "height": 1080})
            page = context.new_page()
            _open(page, ui.url)
            _draws(page)
            wait_until(
                "the count is drawn",
                lambda: (
                    page.locator('[data-value-of="Main.count"]').first.get_attribute("data-value")
                    or ""
                ).isdigit(),
            )
            page.evaluate(OBSERVE_VALUES)
            _server_side(ui, project)
            viewers = _browser_pids(runtime_pid)
            shown = _cpu("the drawing in front", runtime, viewers, page)
            big = _latency(client, page, f"drawing of {CHAINS * 4} elements", 1000)
            choose(page, "Instance", SMALL)
            wait_until("the small drawing is in the page", _drawn(page, SMALL))
            page.evaluate(OBSERVE_VALUES)
            small = _latency(client, page, "drawing of 4 elements", 2000)
            page.get_by_role("tab", name="Resources").click()
            behind = _cpu("another tab in front (Resources)", runtime, viewers, page)
        print(
            f"  ratios: UI server with the drawing in front / another tab "
            f"{shown['ui'] / max(behind['ui'], 1e-9):.1f}, / no browser "
            f"{shown['ui'] / max(quiet['ui'], 1e-9):.1f}; browser with the drawing in front / "
            f"another tab {shown['browser'] / max(behind['browser'], 1e-9):.2f}; latency with "
            f"{CHAINS * 4} elements / with 4: median {big[0] / small[0]:.2f}, "
            f"p95 {big[1] / small[1]:.2f}"
        )


if __name__ == "__main__":
    main()
