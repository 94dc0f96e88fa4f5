"""The source of the running configuration for the Code screen: found only in a project
that compiles to the running CRC; instance -> POU; each line -> the variables it names,
as paths the runtime really has."""

from __future__ import annotations

import shutil
from pathlib import Path

from backend.engineering.project import compile_project, demo_project_path, load_project
from backend.engineering.sources import (
    ConfigurationSources,
    find_sources,
    instances,
    line_variables,
)
from runtime.code.code_image import CodeImage
from runtime.code.intrinsics import SystemView


def _copy_demo(folder: Path) -> Path:
    shutil.copytree(demo_project_path(), folder)
    return folder


def _crc(folder: Path) -> str:
    artifact = compile_project(load_project([folder])).artifact
    assert artifact is not None
    return artifact.crc


def _paths(sources: ConfigurationSources) -> list[str]:
    """The variable paths a runtime that loaded this configuration has."""
    image = CodeImage(sources.artifact, SystemView())
    programs = sources.artifact.programs
    found = [v.path for p in programs for v in image.variable_paths(p.name, p.pou)]
    return found + [v.path for v in image.global_paths()]


def _line(sources: ConfigurationSources, instance: str, text: str) -> int:
    """The number in its file of the line of `instance`'s POU that holds `text`."""
    source = sources.source_of(instance)
    assert source is not None
    return next(source.first_line + i for i, line in enumerate(source.lines) if text in line)


def _named(
    sources: ConfigurationSources, instance: str, text: str
) -> list[tuple[str, str] | tuple[str, str, str]]:
    """(as written, path) of each variable the line holding `text` names, and the index
    of an element of an array of values."""
    source = sources.source_of(instance)
    assert source is not None
    line = _line(sources, instance, text)
    shown = line_variables(source, instance, line, line, _paths(sources)).get(line, [])
    return [(s.label, s.path, s.element) if s.element else (s.label, s.path) for s in shown]


def test_the_project_that_compiles_to_the_running_crc_is_found(tmp_path: Path) -> None:
    demo = _copy_demo(tmp_path / "demo")
    crc = _crc(demo)
    found = find_sources(crc, {"broken": tmp_path / "missing", "demo": demo})
    assert found is not None
    assert (found.project, found.crc) == ("demo", crc)
    source = found.source_of("TankControl")
    assert source is not None
    assert (source.name, source.file, source.first_line) == ("TankControl", "tank.st", 6)
    assert source.lines[0] == "PROGRAM TankControl"
    assert source.lines[-1] == "END_PROGRAM"
    assert not source.standard


def test_an_edited_project_is_not_taken_for_the_running_one(tmp_path: Path) -> None:
    demo = _copy_demo(tmp_path / "demo")
    crc = _crc(demo)
    st = demo / "tank.st"
    st.write_text(st.read_text().replace("level := tankLevel", "level := tankLevel + 1"))
    assert find_sources(crc, {"demo": demo}) is None
    assert find_sources("1A2B3C4D", {"demo": demo}) is None
    assert find_sources(crc, {}) is None


def test_instances_are_the_programs_and_fb_instances_and_map_to_their_pou(
    tmp_path: Path,
) -> None:
    demo = _copy_demo(tmp_path / "demo")
    found = find_sources(_crc(demo), {"demo": demo})
    assert found is not None
    assert instances(found, _paths(found)) == ["TankControl", "TankControl.refillDelay"]
    timer = found.pou_of("TankControl.refillDelay")
    assert timer is not None and (timer.name, timer.kind) == ("TON", "FUNCTION_BLOCK")
    assert found.pou_of("tankcontrol").name == "TankControl"  # type: ignore[union-attr]
    assert found.pou_of("TankControl.level") is None  # a value, not an instance
    assert found.pou_of("Nowhere") is None
    ton = found.source_of("TankControl.refillDelay")
    assert ton is not None and ton.standard and ton.file == "stdlib/timers.st"
    assert ton.lines[0] == "FUNCTION_BLOCK TON" and ton.lines[-1] == "END_FUNCTION_BLOCK"


def test_each_line_names_the_variables_it_mentions_in_their_order(tmp_path: Path) -> None:
    demo = _copy_demo(tmp_path / "demo")
    found = find_sources(_crc(demo), {"demo": demo})
    assert found is not None
    assert _named(found, "TankControl", "level := tankLevel") == [
        ("level", "TankControl.level"),
        ("tankLevel", "tankLevel"),  # a global: named by its own path
    ]
    # the call of an FB instance names its inputs as members of the instance
    assert _named(found, "TankControl", "refillDelay(IN") == [
        ("refillDelay.IN", "TankControl.refillDelay.IN"),
        ("pump", "TankControl.pump"),
        ("alarmPlant", "TankControl.alarmPlant"),
        ("level", "TankControl.level"),
        ("lowLevel", "TankControl.lowLevel"),
        ("refillDelay.PT", "TankControl.refillDelay.PT"),
        ("restartDelay", "TankControl.restartDelay"),
    ]
    assert _named(found, "TankControl", "IF refillDelay.Q") == [
        ("refillDelay.Q", "TankControl.refillDelay.Q")
    ]
    # a declaration names the variable declared; an FB as a whole has no value
    assert _named(found, "TankControl", "level : INT") == [("level", "TankControl.level")]
    assert _named(found, "TankControl", "refillDelay : TON") == []
    assert _named(found, "TankControl", "END_IF") == []
    # inside the standard FB, its own variables, as members of the chosen instance
    assert _named(found, "TankControl.refillDelay", "IF ET >= PT") == [
        ("ET", "TankControl.refillDelay.ET"),
        ("PT", "TankControl.refillDelay.PT"),
    ]


PLANT = """\
TYPE Point : STRUCT x : INT; y : INT; END_STRUCT; END_TYPE
VAR_GLOBAL
  gTotal : DINT;
  gHorn : BOOL;
END_VAR
FUNCTION_BLOCK Valve
VAR_INPUT open : BOOL; END_VAR
VAR_OUTPUT opened : BOOL; END_VAR
opened := open;
END_FUNCTION_BLOCK
PROGRAM Line
VAR_EXTERNAL gTotal : DINT; END_VAR
VAR
  valves : ARRAY[1..2] OF Valve;
  points : ARRAY[0..1] OF Point;
  counts : ARRAY[0..3] OF INT;
  i : INT;
END_VAR
VAR_TEMP scratch : INT; END_VAR
FOR i := 0 TO 3 DO
  counts[i] := counts[i] + 1; scratch := i;
END_FOR;
points[1].x := counts[2];
valves[2].open := TRUE;
valves[1](open := counts[0] > 0);
valves[i - 2](open := TRUE);  (* i is 4 after the loop *)
gTotal := gTotal + BOOL_TO_DINT(valves[1].opened);
END_PROGRAM
PROGRAM Chart
VAR_EXTERNAL gHorn : BOOL; END_VAR
VAR go, lamp : BOOL; END_VAR
INITIAL_STEP Idle: END_STEP
STEP Busy: lamp(N); gHorn(P); END_STEP
TRANSITION FROM Idle TO Busy := go; END_TRANSITION
END_PROGRAM
"""


def test_arrays_structs_globals_temporaries_and_steps(tmp_path: Path) -> None:
    folder = tmp_path / "plant"
    folder.mkdir()
    (folder / "plant.st").write_text(PLANT)
    found = find_sources(_crc(folder), {"plant": folder})
    assert found is not None
    assert instances(found, _paths(found)) == [
        "Line",
        "Line.valves[1]",
        "Line.valves[2]",
        "Chart",
    ]
    assert found.pou_of("Line.valves[2]").name == "Valve"  # type: ignore[union-attr]
    assert found.pou_of("Line.points[1]") is None  # a structure
    # a variable index names the whole array (one variable) and the index; the counter of
    # FOR is named; a temporary has no value to show
    assert _named(found, "Line", "FOR i") == [("i", "Line.i")]
    assert _named(found, "Line", "counts[i] :=") == [("counts", "Line.counts"), ("i", "Line.i")]
    assert _named(found, "Line", "points[1].x") == [
        ("points[1].x", "Line.points[1].x"),
        ("counts[2]", "Line.counts", "2"),  # an element of an array of values
    ]
    # an instance called as an element names its inputs as members; `valves[i - 2]` is any one
    assert _named(found, "Line", "valves[1](open") == [
        ("valves[1].open", "Line.valves[1].open"),
        ("counts[0]", "Line.counts", "0"),
    ]
    assert _named(found, "Line", "valves[i - 2](open") == [("i", "Line.i")]
    # a global through VAR_EXTERNAL is named by its bare path
    assert _named(found, "Line", "gTotal := gTotal") == [
        ("gTotal", "gTotal"),
        ("valves[1].opened", "Line.valves[1].opened"),
    ]
    assert _named(found, "Line.valves[2]", "opened := open") == [
        ("opened", "Line.valves[2].opened"),
        ("open", "Line.valves[2].open"),
    ]
    # an SFC step shows its flag and its time, and the BOOL variables it sets as actions
    assert _named(found, "Chart", "STEP Busy") == [
        ("Busy.X", "Chart.Busy.X"),
        ("Busy.T", "Chart.Busy.T"),
        ("lamp", "Chart.lamp"),
        ("gHorn", "gHorn"),
    ]
    assert _named(found, "Chart", "TRANSITION") == [("go", "Chart.go")]


PUMPS = """\
FUNCTION_BLOCK Pump
VAR target : INT; lvl : INT; END_VAR
METHOD PUBLIC Start : BOOL
VAR_INPUT speed : INT; END_VAR
target := speed;
Start := target > 0;
END_METHOD
PROPERTY PUBLIC Level : INT
GET
  Level := lvl;
END_GET
END_PROPERTY
lvl := lvl + target;
END_FUNCTION_BLOCK
PROGRAM Main
VAR pump : Pump; ok : BOOL; END_VAR
ok := pump.Start(speed := 5);
END_PROGRAM
"""


def test_a_method_and_a_property_name_the_instance_variables_not_their_own(
    tmp_path: Path,
) -> None:
    folder = tmp_path / "pumps"
    folder.mkdir()
    (folder / "pumps.st").write_text(PUMPS)
    found = find_sources(_crc(folder), {"pumps": folder})
    assert found is not None
    # the parameter `speed` and the result `Start` live only during a call
    assert _named(found, "Main.pump", "target := speed") == [("target", "Main.pump.target")]
    assert _named(found, "Main.pump", "Start := target") == [("target", "Main.pump.target")]
    # the property's own name is its result
    assert _named(found, "Main.pump", "Level := lvl") == [("lvl", "Main.pump.lvl")]
