"""SFC networks of PLCopen files as textual SFC: the shapes the import follows, and the
ones it refuses with a reason (the POU is then named as not imported)."""

from __future__ import annotations

from pathlib import Path

import pytest

from backend.engineering.plcopen.importer import import_plcopen
from backend.engineering.project import compile_project, load_project

HEAD = """<?xml version="1.0" encoding="utf-8"?>
<project xmlns="http://www.plcopen.org/xml/tc6_0201">
  <types><dataTypes/><pous>
    <pou name="Chart" pouType="program">
      <interface><localVars>
        <variable name="go"><type><BOOL/></type></variable>
        <variable name="n"><type><INT/></type></variable>
      </localVars></interface>
"""
TAIL = "</pou></pous></types></project>\n"


def step(local: int, name: str, after: int | None = None, initial: bool = False) -> str:
    link = f'<connectionPointIn><connection refLocalId="{after}"/></connectionPointIn>'
    flag = ' initialStep="true"' if initial else ""
    return f'<step localId="{local}" name="{name}"{flag}>{link if after else ""}</step>'


def transition(local: int, after: int, condition: str = "go", extra: str = "") -> str:
    return (
        f'<transition localId="{local}"{extra}><connectionPointIn><connection '
        f'refLocalId="{after}"/></connectionPointIn><condition><inline name=""><ST>'
        f"{condition}</ST></inline></condition></transition>"
    )


def chart(tmp_path: Path, network: str, extra: str = "") -> tuple[str, list[str]]:
    """The Chart POU's text (or '') and the reasons of what was not imported."""
    xml = tmp_path / "chart.xml"
    xml.write_text(f"{HEAD}{extra}<body><SFC>{network}</SFC></body>{TAIL}")
    folder = tmp_path / "out"
    result = import_plcopen(xml, folder)
    path = folder / "Chart.st"
    return (path.read_text() if path.exists() else ""), [m.reason for m in result.not_imported]


def compiles(tmp_path: Path) -> bool:
    compiled = compile_project(load_project([tmp_path / "out"]))
    return not [d for d in compiled.diagnostics if d.severity == "error"]


def test_a_selection_with_priorities_and_a_jump(tmp_path: Path) -> None:
    network = (
        step(1, "Idle", None, initial=True)
        + '<selectionDivergence localId="2"><connectionPointIn><connection refLocalId="1"/>'
        "</connectionPointIn></selectionDivergence>"
        + transition(3, 2, "go", ' priority="2"')
        + transition(4, 2, "n > 5", ' priority="1"')
        + step(5, "Left", 3)
        + step(6, "Right", 4)
        + transition(7, 5, "NOT go")
        + transition(8, 6, "n = 0")
        + '<selectionConvergence localId="9"><connectionPointIn><connection refLocalId="7"/>'
        '</connectionPointIn><connectionPointIn><connection refLocalId="8"/>'
        "</connectionPointIn></selectionConvergence>"
        + '<jumpStep localId="10" targetName="Idle"><connectionPointIn><connection '
        'refLocalId="9"/></connectionPointIn></jumpStep>'
    )
    text, refused = chart(tmp_path, network)
    assert refused == []
    assert "TRANSITION (PRIORITY := 2) FROM Idle TO Left := go;" in text
    assert "TRANSITION (PRIORITY := 1) FROM Idle TO Right := n > 5;" in text
    assert "TRANSITION FROM Left TO Idle := NOT go;" in text
    assert "TRANSITION FROM Right TO Idle := n = 0;" in text
    assert compiles(tmp_path)


def test_a_connector_and_its_continuation(tmp_path: Path) -> None:
    network = (
        step(1, "First", None, initial=True)
        + transition(2, 1)
        + '<connector localId="3" name="Later"><connectionPointIn><connection refLocalId="2"/>'
        "</connectionPointIn></connector>"
        + '<continuation localId="4" name="Later"/>'
        + step(5, "Second", 4)
        + transition(6, 5, "NOT go")
        + '<jumpStep localId="7" targetName="First"><connectionPointIn><connection '
        'refLocalId="6"/></connectionPointIn></jumpStep>'
    )
    text, refused = chart(tmp_path, network)
    assert refused == []
    assert "TRANSITION FROM First TO Second := go;" in text
    assert compiles(tmp_path)


def test_timed_and_stored_qualifiers(tmp_path: Path) -> None:
    blocks = (
        '<actionBlock localId="9"><connectionPointIn><connection refLocalId="1"/>'
        '</connectionPointIn><action localId="0" qualifier="L" duration="T#5s"><inline><ST>'
        'n := n + 1;</ST></inline></action><action localId="0" qualifier="S"><reference '
        'name="Count"/></action></actionBlock>'
    )
    actions = '<actions><action name="Count"><body><ST>n := 0;</ST></body></action></actions>'
    network = step(1, "Run", None, initial=True) + transition(2, 1) + step(3, "Stop", 2) + blocks
    text, refused = chart(tmp_path, network + transition(4, 3, "NOT go") + _jump(5, 4), actions)
    assert refused == []
    assert "STEP Run:\n    Run_INLINE1(L, T#5s);\n    Count(S);\nEND_STEP" in text
    assert compiles(tmp_path)


def _jump(local: int, after: int, target: str = "Run") -> str:
    return (
        f'<jumpStep localId="{local}" targetName="{target}"><connectionPointIn><connection '
        f'refLocalId="{after}"/></connectionPointIn></jumpStep>'
    )


@pytest.mark.parametrize(
    ("network", "extra", "reason"),
    [
        (
            step(1, "A", None, True) + '<macroStep localId="2" name="M"/>',
            "",
            "SFC: a macro step at line 9",
        ),
        (
            step(1, "A", None, True) + transition(2, 1),
            "",
            "SFC: the transition at line 9 joins no step to a step",
        ),
        (
            step(1, "A", None, True)
            + '<transition localId="2"><connectionPointIn><connection refLocalId="1"/>'
            '</connectionPointIn><condition><reference name="Ready"/></condition></transition>'
            + _jump(3, 2, "A"),
            "",
            "SFC: the transition at line 9 names transition 'Ready', which the POU does not have",
        ),
        (
            step(1, "A", None, True)
            + '<transition localId="2"><connectionPointIn><connection refLocalId="1"/>'
            '</connectionPointIn><condition><reference name="Ready"/></condition></transition>'
            + _jump(3, 2, "A"),
            '<transitions><transition name="Ready"><body><ST>IF go THEN Ready := TRUE; END_IF;'
            "</ST></body></transition></transitions>",
            "transition Ready: a body of statements (padt takes an expression)",
        ),
        (
            step(1, "A", None, True)
            + '<actionBlock localId="3"><connectionPointIn><connection refLocalId="1"/>'
            '</connectionPointIn><action localId="0" qualifier="D"><reference name="X"/>'
            "</action></actionBlock>",
            "",
            "SFC: the D action at line 9 needs a time",
        ),
        (
            step(1, "A", None, True) + transition(2, 7) + _jump(3, 2, "A"),
            "",
            "SFC: a connection to localId 7, which is no element",
        ),
        (
            step(1, "A", None, True)
            + transition(2, 1)
            + '<step localId="3"><connectionPointIn><connection refLocalId="2"/>'
            "</connectionPointIn></step>",
            "",
            "SFC: the step at line 9 has no valid name",
        ),
    ],
)
def test_networks_without_a_textual_form(
    tmp_path: Path, network: str, extra: str, reason: str
) -> None:
    text, refused = chart(tmp_path, network, extra)
    assert text == ""
    assert refused == [reason]
