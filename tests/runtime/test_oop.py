"""Instances with methods and inherited members in the runtime's world (docs/language.md,
"Object orientation"): an inherited member is an ordinary member of the instance for the
OLT, writes, forcing and a warm start; an interface variable is a reference. A reload that
changes a method's code only carries every value over and runs the new code; one that
adds a variable to a base block changes the layout of every block derived from it, whose
values are carried by name."""

from __future__ import annotations

from pathlib import Path

from runtime.context import ContextInvalid, load_context, save_context
from runtime.resource import Resource
from runtime.restart import take_context, warm_start
from tests.support.resource_harness import compiled, harness

PLANT = """
FUNCTION_BLOCK Drive
VAR_INPUT enable : BOOL; END_VAR
VAR_OUTPUT speed : INT; END_VAR
METHOD PUBLIC Ramp : INT
VAR_INPUT step : INT; END_VAR
speed := speed + step;
Ramp := speed;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Pump EXTENDS Drive
VAR strokes : INT; END_VAR
IF enable THEN strokes := strokes + Ramp(1); END_IF;
END_FUNCTION_BLOCK
PROGRAM Main
VAR pump : Pump; on : BOOL := TRUE; END_VAR
pump(enable := on);
END_PROGRAM
"""


def test_inherited_members_are_members_for_the_olt_writes_and_forcing() -> None:
    h = harness(PLANT, programs=[{"name": "Main", "local_forcing_allowed": True}])
    h.cycle(3)
    variables = {v["path"]: v["type"] for v in h.ok("variables")["variables"]}
    assert variables["Main.pump.speed"] == "INT"  # declared by the base, Drive
    assert variables["Main.pump.strokes"] == "INT"
    assert not any(path.upper().endswith(".STEP") for path in variables)  # a method's local
    assert h.ok("values")["values"]["Main.pump.speed"] == 3
    assert h.cmd("write", variable="Main.pump.speed", value=100)["ok"]
    h.cycle()
    assert h.value("Main.pump.speed") == 101
    h.ok("force", variable="Main.pump.speed", value=7)  # an inherited output
    h.ok("start_forcing", program="Main")
    h.cycle(2)
    assert h.value("Main.pump.speed") == 7
    assert h.ok("values")["values"]["Main.pump.speed"] == 7


def test_a_reload_of_a_method_body_is_a_code_change_that_keeps_every_value() -> None:
    h = harness(PLANT)
    h.cycle(3)
    changed = PLANT.replace("speed := speed + step;", "speed := speed + 10 * step;")
    h.send(compiled(changed))
    plan = h.ok("reload_preview")["plan"]
    assert {c["action"] for c in plan["changes"]} == {"kept"}
    assert plan["programs"]["changed"] == ["Main"]  # the base block is its code too
    h.send(compiled(changed))
    assert h.cmd("reload")["ok"]
    assert (h.value("Main.pump.speed"), h.value("Main.pump.strokes")) == (3, 6)
    h.cycle()
    assert h.value("Main.pump.speed") == 13  # the new code of the method runs
    assert h.value("Main.pump.strokes") == 6 + 13


def test_a_variable_added_to_a_base_block_keeps_the_values_of_derived_instances() -> None:
    h = harness(PLANT)
    h.cycle(4)
    changed = PLANT.replace(
        "VAR_OUTPUT speed : INT; END_VAR",
        "VAR_OUTPUT speed : INT; END_VAR\nVAR limit : INT := 50; END_VAR",
    )
    h.send(compiled(changed))
    plan = h.ok("reload_preview")["plan"]
    changes = {c["path"]: c["action"] for c in plan["changes"]}
    assert changes["Main.pump.limit"] == "new"
    assert changes["Main.pump.speed"] == changes["Main.pump.strokes"] == "kept"
    h.send(compiled(changed))
    assert h.cmd("reload")["ok"]
    assert h.value("Main.pump.speed") == 4 and h.value("Main.pump.strokes") == 10
    assert h.value("Main.pump.limit") == 50
    h.cycle()
    assert h.value("Main.pump.speed") == 5 and h.value("Main.pump.strokes") == 15


DISPATCH = """
INTERFACE ISource
METHOD Level : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK Tank IMPLEMENTS ISource
VAR fill : INT := 40; END_VAR
METHOD PUBLIC Level : INT
Level := fill;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR tank : Tank; source : ISource; seen : INT; END_VAR
source := tank;
seen := source.Level();
END_PROGRAM
"""


def test_an_interface_variable_reads_as_its_instance_and_only_the_program_sets_it() -> None:
    h = harness(DISPATCH, programs=[{"name": "Main", "local_forcing_allowed": True}])
    variables = {v["path"]: v["type"] for v in h.ok("variables")["variables"]}
    assert variables["Main.source"] == "INTERFACE ISource"
    assert h.ok("values")["values"]["Main.source"] is None
    h.cycle()
    assert h.ok("values")["values"]["Main.source"] == "Main.tank"
    reply = h.cmd("write", variable="Main.source", value="Main.tank")
    assert not reply["ok"] and reply["error"]["code"] == "bad_value"
    assert h.cmd("write", variable="Main.tank.fill", value=7)["ok"]
    h.cycle()
    assert h.value("Main.seen") == 7


def test_a_reload_begins_an_interface_as_null_and_the_program_sets_it_again() -> None:
    h = harness(DISPATCH)
    h.cycle(2)
    changed = DISPATCH.replace("Level := fill;", "Level := fill + 1;")
    h.send(compiled(changed))
    plan = h.ok("reload_preview")["plan"]
    changes = {c["path"]: c for c in plan["changes"]}
    assert changes["Main.source"]["action"] == "initialised"
    assert changes["Main.tank.fill"]["action"] == "kept"
    h.send(compiled(changed))
    assert h.cmd("reload")["ok"]
    assert h.value("Main.source") is None
    h.cycle()
    assert (h.value("Main.source"), h.value("Main.seen")) == ("Main.tank", 41)


def test_a_warm_start_keeps_inherited_members_and_begins_interfaces_as_null(
    tmp_path: Path,
) -> None:
    plant = PLANT + DISPATCH.replace("PROGRAM Main", "PROGRAM Other")
    h = harness(plant)
    h.cycle(3)
    assert h.value("Other.source") == "Other.tank"
    context = take_context(h.resource)
    assert context is not None
    save_context(tmp_path / "context.json", context)
    artifact = compiled(plant)
    again = Resource("R", h.clock)
    again.load(artifact)
    saved = load_context(tmp_path / "context.json", artifact.crc)
    assert not isinstance(saved, ContextInvalid), saved
    warm_start(again, saved)
    assert again.variables.value("Main.pump.speed") == 3  # declared by the base block
    assert again.variables.value("Main.pump.strokes") == 6
    assert again.variables.value("Other.source") is None


def test_an_array_of_interfaces_holds_references_that_a_reload_begins_as_null() -> None:
    plant = DISPATCH.replace(
        "VAR tank : Tank; source : ISource; seen : INT; END_VAR",
        "VAR tank : Tank; source : ISource; seen : INT; all : ARRAY[1..2] OF ISource; END_VAR",
    ).replace("seen := source.Level();", "seen := source.Level();\nall[2] := tank;")
    h = harness(plant)
    variables = {v["path"]: v["type"] for v in h.ok("variables")["variables"]}
    assert variables["Main.all"] == "ARRAY[1..2] OF INTERFACE ISource"
    h.cycle()
    assert h.ok("values")["values"]["Main.all"] == [None, "Main.tank"]
    changed = plant.replace("Level := fill;", "Level := fill + 1;")
    h.send(compiled(changed))
    changes = {c["path"]: c for c in h.ok("reload_preview")["plan"]["changes"]}
    assert changes["Main.all"]["action"] == "initialised"
    assert "starts again at its initial value" in changes["Main.all"]["reason"]
    h.send(compiled(changed))
    assert h.cmd("reload")["ok"]
    assert h.value("Main.all") == [None, None]
    h.cycle()
    assert h.value("Main.all") == [None, "Main.tank"]
