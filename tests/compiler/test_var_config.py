"""Partly specified locations (`AT %I*`, `%Q*`, `%M*`) completed per instance by the
configuration's VAR_CONFIG, and VAR_ACCESS access paths listed in the artifact; traced
through `padt sim` (100 ms cycles) and through a resource's output image."""

from __future__ import annotations

from pathlib import Path

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import VirtualClock
from runtime.contract.artifact import AccessPath, load_artifact
from runtime.resource import Resource
from tests.compiler.test_checks import diagnostics
from tests.conftest import sim_trace

DOORS = """
FUNCTION_BLOCK Door
VAR open AT %I* : BOOL; lamp AT %QX* : BOOL; END_VAR
lamp := open;
END_FUNCTION_BLOCK
PROGRAM Main
VAR front, back : Door; speed AT %IW* : INT; shown : INT; END_VAR
front(); back();
shown := speed;
END_PROGRAM
CONFIGURATION Plant
  RESOURCE Cpu ON PLC
    TASK Cyclic (INTERVAL := T#100ms, PRIORITY := 1);
    PROGRAM Main WITH Cyclic : Main;
  END_RESOURCE
  VAR_ACCESS
    FrontOpen : Cpu.Main.front.open : BOOL READ_ONLY;
    Speed : Main.speed : INT READ_WRITE;
    BackLamp : Cpu.%QX0.1 : BOOL;
  END_VAR
  VAR_CONFIG
    Cpu.Main.front.open AT %IX1.0 : BOOL;
    Cpu.Main.front.lamp AT %QX0.0 : BOOL;
    Cpu.Main.back.open AT %IX1.1 : BOOL;
    Cpu.Main.back.lamp AT %QX0.1 : BOOL;
    Cpu.Main.speed AT %IW4 : INT;
  END_VAR
END_CONFIGURATION
"""


def test_each_instance_behaves_on_its_own_configured_inputs(tmp_path: Path) -> None:
    t = sim_trace(
        tmp_path, DOORS, 4, "Main.front.open=TRUE@2", "Main.back.open=TRUE@3", "Main.speed=7@4"
    )
    assert t["Main.front.lamp"] == [False, True, True, True]
    assert t["Main.back.lamp"] == [False, False, True, True]
    assert t["Main.shown"] == [0, 0, 0, 7]


def test_the_artifact_carries_the_addresses_and_the_access_paths() -> None:
    result = compile_sources([SourceFile("doors.st", DOORS)])
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    artifact = load_artifact(result.artifact.to_json())  # as a resource reads it
    assert artifact.located == (
        ("Main.back.lamp", "%QX0.1"),
        ("Main.back.open", "%IX1.1"),
        ("Main.front.lamp", "%QX0.0"),
        ("Main.front.open", "%IX1.0"),
        ("Main.speed", "%IW4"),
    )
    assert artifact.access_paths == (
        AccessPath("BackLamp", "Main.back.lamp", "BOOL", writable=False),
        AccessPath("FrontOpen", "Main.front.open", "BOOL", writable=False),
        AccessPath("Speed", "Main.speed", "INT", writable=True),
    )


def test_completed_output_locations_are_points_of_the_output_image() -> None:
    result = compile_sources([SourceFile("doors.st", DOORS)])
    assert result.artifact is not None
    resource = Resource("Cpu", VirtualClock())
    resource.load(result.artifact)
    resource.start()
    resource.io.set_inputs({"Main.back.open": True})
    resource.cycle()
    assert resource.io.outputs == {"Main.back.lamp": True, "Main.front.lamp": False}
    locations = {b.path.path: b.path.location for b in resource.variables.bound}
    assert locations["Main.front.open"] == "%IX1.0"
    assert locations["Main.speed"] == "%IW4"


def test_a_configuration_without_them_keeps_its_crc() -> None:
    """The new artifact fields are left out of the CRC while empty."""
    source = "PROGRAM Main\nVAR n : INT; END_VAR\nn := n + 1;\nEND_PROGRAM\n"
    result = compile_sources([SourceFile("main.st", source)])
    assert result.artifact is not None
    assert '"located"' not in result.artifact.body_json()
    assert '"access_paths"' not in result.artifact.body_json()


def test_unconfigured_and_misconfigured_locations_get_codes() -> None:
    source = DOORS.replace("    Cpu.Main.back.open AT %IX1.1 : BOOL;\n", "").replace(
        "Cpu.Main.speed AT %IW4 : INT;", "Cpu.Main.speed AT %ID4 : INT;"
    )
    source = source.replace("Cpu.Main.back.lamp AT %QX0.1", "Cpu.Main.back.lamp AT %IX0.1")
    source = source.replace("    BackLamp : Cpu.%QX0.1 : BOOL;\n", "")
    source = source.replace("Cpu.Main.front.lamp", "Cpu.Main.shown")
    assert diagnostics(source) == [
        "t.st:3:5: error: 'Main.back.open' is declared AT %I*: give it its address in the"
        " configuration's VAR_CONFIG (Cpu.Main.back.open AT ... : BOOL;) [E0616]",
        "t.st:3:25: error: 'Main.front.lamp' is declared AT %QX*: give it its address in the"
        " configuration's VAR_CONFIG (Cpu.Main.front.lamp AT ... : BOOL;) [E0616]",
        "t.st:22:5: error: 'Cpu.Main.shown' has no partly specified location; VAR_CONFIG"
        " gives addresses to AT %I*, %Q*, %M* only [E0617]",
        "t.st:23:5: error: 'Cpu.Main.back.lamp': %IX0.1 is not in the area of %QX* [E0618]",
        "t.st:24:5: error: 'Cpu.Main.speed': the size of %ID4 does not fit INT [E0618]",
    ]


def test_access_paths_must_name_a_variable_of_their_type() -> None:
    source = DOORS.replace(
        "FrontOpen : Cpu.Main.front.open : BOOL", "FrontOpen : Cpu.Main.front.open : INT"
    )
    source = source.replace("Speed : Main.speed", "Speed : Main.sped")
    assert diagnostics(source) == [
        "t.st:17:5: error: 'Cpu.Main.front.open' is BOOL, not INT [E0619]",
        "t.st:18:5: error: 'Main.sped' names no variable of the resource 'Cpu' [E0619]",
    ]


def test_a_partly_specified_address_in_a_statement_is_refused() -> None:
    source = "PROGRAM Main\nVAR x : BOOL; END_VAR\nx := %I*;\nEND_PROGRAM\n"
    assert diagnostics(source) == [
        "t.st:3:6: error: %I* is a partly specified location: it only locates a declaration [E0001]"
    ]
