"""The Code screen without a browser: what it renders from the values a feed holds, and the
variables it wants (those of the lines in view only)."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import Any, cast

import pytest
import viser

from backend.engineering.project import compile_project, demo_project_path, load_project
from backend.engineering.sources import ConfigurationSources, Shown, find_sources
from frontend.editor.live_lines import SourceLookup
from frontend.resource_feed import Latest, ResourceFeed
from frontend.screens import code
from tests.conftest import free_port


@pytest.fixture(scope="module")
def demo_sources() -> ConfigurationSources:
    artifact = compile_project(load_project([demo_project_path()])).artifact
    assert artifact is not None
    found = find_sources(artifact.crc, {"demo": demo_project_path()})
    assert found is not None
    return found


@pytest.fixture
def gui() -> Iterator[viser.GuiApi]:
    server = viser.ViserServer(port=free_port(), verbose=False)
    try:
        yield server.gui
    finally:
        server.stop()


TYPES = {
    "TankControl.level": "INT",
    "TankControl.pump": "BOOL",
    "TankControl.highLevel": "INT",
    "TankControl.lowLevel": "INT",
    "TankControl.refillDelay.IN": "BOOL",
    "TankControl.refillDelay.PT": "TIME",
    "TankControl.refillDelay.Q": "BOOL",
    "TankControl.refillDelay.ET": "TIME",
    "TankControl.refillDelay.running": "BOOL",
    "TankControl.refillDelay.start": "TIME",
    "TankControl.restartDelay": "TIME",
    "TankControl.alarmLow": "BOOL",
    "TankControl.alarmPlant": "BOOL",
    "TankControl.pumpStarts": "DINT",
    "tankLevel": "INT",
    "pumpCommand": "BOOL",
}


def _feed(crc: str) -> ResourceFeed:
    """What a feed holds once the runtime answered: the status, the variables, values."""
    latest = Latest()
    latest.status = cast(Any, SimpleNamespace(crc=crc))
    latest.types = dict(TYPES)
    latest.values = {path: 0 for path in TYPES} | {"TankControl.level": 512}
    latest.quality = {"TankControl.pump": "forced"}
    return cast(ResourceFeed, SimpleNamespace(latest=latest))


def _refreshed(screen: code.CodeScreen, feed: ResourceFeed, projects: dict[str, Path]) -> str:
    """Refresh until the look-up of the source (in the background) is answered."""
    deadline = time.monotonic() + 20
    while True:
        code.refresh(screen, feed, projects)
        if "Looking for the source" not in screen.shown:
            return screen.shown
        assert time.monotonic() < deadline, "the source was never looked up"
        time.sleep(0.05)


def test_the_lines_in_view_and_only_their_variables_are_wanted(
    gui: viser.GuiApi, demo_sources: ConfigurationSources
) -> None:
    screen = code.build(gui)
    feed = _feed(demo_sources.crc)
    page = _refreshed(screen, feed, {"demo": demo_project_path()})
    assert screen.instance.value == "TankControl"
    assert tuple(screen.instance.options) == ("TankControl", "TankControl.refillDelay")
    assert '<span data-code-line="30">alarmLow := level &lt; 100;</span>' in page
    assert 'data-code-var="TankControl.level" data-quality="live"' in page
    assert 'data-code-var="TankControl.pump" data-quality="forced" style="color:#c92a2a"' in page
    assert set(code.wanted(screen)) == set(TYPES) - {
        "TankControl.refillDelay.ET",  # TON's own: not named in TankControl
        "TankControl.refillDelay.running",
        "TankControl.refillDelay.start",
    }
    screen.first.value = 26  # type: ignore[misc]
    code.refresh(screen, feed, {"demo": demo_project_path()})
    assert 'data-line="25"' not in screen.shown and 'data-line="26"' in screen.shown
    wanted = code.wanted(screen)
    assert "TankControl.level" in wanted
    assert "TankControl.highLevel" not in wanted  # named on lines 10 and 22 only


def test_a_configuration_of_no_known_project_shows_no_source(gui: viser.GuiApi) -> None:
    screen = code.build(gui)
    page = _refreshed(screen, _feed("1A2B3C4D"), {"demo": demo_project_path()})
    assert "The source of configuration 1A2B3C4D is not among the projects this PADT knows" in (
        page
    )
    assert "data-code-line" not in page
    assert code.wanted(screen) == []


def test_an_instance_of_a_block_without_st_source_shows_its_interface(
    gui: viser.GuiApi, demo_sources: ConfigurationSources
) -> None:
    without_ton = {name: pou for name, pou in demo_sources.pous.items() if name != "TON"}
    known = dataclasses.replace(demo_sources, pous=without_ton)
    screen = code.build(gui)
    screen.lookup = SourceLookup(lambda crc, projects: known)
    feed = _feed(demo_sources.crc)
    _refreshed(screen, feed, {})
    screen.instance.value = "TankControl.refillDelay"  # type: ignore[misc]
    code.refresh(screen, feed, {})
    assert "an instance of TON, which has no ST source here" in screen.shown
    assert 'data-code-var="TankControl.refillDelay.Q"' in screen.shown
    assert "TankControl.refillDelay.ET" in code.wanted(screen)
    assert screen.first.disabled and not screen.page.visible  # nothing to page through


def test_an_element_of_an_array_of_values_shows_that_element(
    demo_sources: ConfigurationSources,
) -> None:
    source = demo_sources.source_of("TankControl")
    assert source is not None
    shown = {18: [Shown("counts[2]", "Line.counts", "2"), Shown("gone", "Line.gone")]}
    page = code.render_source(
        source,
        18,
        18,
        shown,
        {"Line.counts": [1, 2, 30, 4]},
        {"Line.counts": "ARRAY[0..3] OF INT", "Line.gone": "INT"},
        {},
    )
    assert 'data-code-var="Line.counts[2]" data-quality="live" style="color:inherit">30<' in page
    assert 'data-code-var="Line.gone" data-quality="none"' in page  # no value (yet): "..."
