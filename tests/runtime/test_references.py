"""References (REF_TO) in the runtime's world (docs/language.md, "References"): the values
of the OLT show a reference as the path it refers to or NULL; writes and forcing refuse a
reference; a reload and a warm start begin every reference as NULL, and the reload plan
says so."""

from __future__ import annotations

from pathlib import Path

from runtime.context import ContextInvalid, load_context, save_context
from runtime.contract.recording import values_schema
from runtime.contract.values import format_value
from runtime.resource import Resource
from runtime.restart import take_context, warm_start
from tests.support.resource_harness import compiled, harness

PLANT = """
FUNCTION_BLOCK Follower
VAR_INPUT source : REF_TO INT; END_VAR
VAR_OUTPUT copy : INT; END_VAR
IF source <> NULL THEN copy := source^; END_IF;
END_FUNCTION_BLOCK
PROGRAM Main
VAR level : INT; r : REF_TO INT; follow : Follower; END_VAR
level := level + 1;
r := REF(level);
follow(source := r);
END_PROGRAM
"""


def test_the_values_show_a_reference_as_the_path_it_refers_to_or_null() -> None:
    h = harness(PLANT, start=False)
    assert h.value("Main.r") is None
    assert format_value(h.value("Main.r"), "REF_TO INT") == "NULL"
    h.resource.start()
    h.cycle(2)
    values = h.ok("values")["values"]
    assert values["Main.r"] == "Main.level" and values["Main.follow.source"] == "Main.level"
    assert values["Main.follow.copy"] == 2
    assert format_value(h.value("Main.r"), "REF_TO INT") == "Main.level"
    variables = {v["path"]: v["type"] for v in h.ok("variables")["variables"]}
    assert variables["Main.r"] == "REF_TO INT"


def test_writes_and_forcing_refuse_a_reference() -> None:
    h = harness(PLANT, programs=[{"name": "Main", "local_forcing_allowed": True}])
    h.cycle()
    reply = h.cmd("write", variable="Main.r", value="Main.level")
    assert not reply["ok"] and reply["error"]["code"] == "bad_value"
    assert "a reference (REF_TO INT) is set by the program only" in reply["error"]["message"]
    reply = h.cmd("force", variable="Main.follow.source", value="Main.level")
    assert not reply["ok"] and reply["error"]["code"] == "bad_value", reply
    assert "cannot be written or forced" in reply["error"]["message"]
    h.cycle()
    assert h.value("Main.r") == "Main.level"  # nothing changed


def test_a_reload_begins_references_as_null_and_its_plan_says_so() -> None:
    h = harness(PLANT)
    h.cycle(3)
    changed = PLANT.replace("level := level + 1;", "level := level + 10;")
    h.send(compiled(changed))
    plan = h.ok("reload_preview")["plan"]
    changes = {c["path"]: c for c in plan["changes"]}
    for path in ("Main.r", "Main.follow.source"):
        assert changes[path]["action"] == "initialised"
        assert changes[path]["reason"] == (
            "a reference does not carry over a reload: it starts again at its initial "
            "value (NULL unless declared := REF(x))"
        )
    assert changes["Main.level"]["action"] == "kept"
    h.send(compiled(changed))
    assert h.cmd("reload")["ok"]
    assert (h.value("Main.level"), h.value("Main.r")) == (3, None)
    h.cycle()
    assert (h.value("Main.level"), h.value("Main.r")) == (13, "Main.level")
    assert h.value("Main.follow.copy") == 13


def test_a_warm_start_begins_references_as_null(tmp_path: Path) -> None:
    h = harness(PLANT)
    h.cycle(4)
    assert h.value("Main.r") == "Main.level"
    context = take_context(h.resource)
    assert context is not None
    save_context(tmp_path / "context.json", context)

    artifact = compiled(PLANT)
    again = Resource("R", h.clock)
    again.load(artifact)
    saved = load_context(tmp_path / "context.json", artifact.crc)
    assert not isinstance(saved, ContextInvalid), saved
    warm_start(again, saved)
    assert again.status().start == "warm"
    assert again.variables.value("Main.level") == 4
    assert again.variables.value("Main.r") is None
    assert again.variables.value("Main.follow.source") is None


def test_a_recording_declares_a_reference_as_a_path_or_null() -> None:
    schema = values_schema([("Main.r", "REF_TO INT"), ("Main.p", "POINTER TO Point")])
    main = schema["properties"]["values"]["properties"]["Main"]["properties"]
    assert main["r"] == {"type": ["string", "null"], "description": "REF_TO INT"}
    assert main["p"]["type"] == ["string", "null"]


INITIAL = """
VAR_GLOBAL g : INT := 5; gr : REF_TO INT := REF(g); END_VAR
FUNCTION_BLOCK Counter
VAR mine : REF_TO INT := REF(n); none : REF_TO INT := NULL; n : INT; END_VAR
mine^ := mine^ + 1;
END_FUNCTION_BLOCK
PROGRAM Main
VAR level : INT := 3; r : REF_TO INT := REF(level); c : Counter; seen : INT; END_VAR
r^ := r^ + 1;
c();
seen := gr^ + c.n;
IF c.none = NULL THEN seen := seen + 100; END_IF;
END_PROGRAM
"""


def test_a_reference_declared_with_an_initial_value_starts_there_again_at_reload_and_warm_start(
    tmp_path: Path,
) -> None:
    h = harness(INITIAL)
    h.cycle(2)
    values = h.ok("values")["values"]
    assert values["Main.r"] == "Main.level" and values["Main.level"] == 5
    assert values["Main.c.mine"] == "Main.c.n" and values["Main.c.none"] is None
    assert values["gr"] == "g" and values["Main.seen"] == 5 + 2 + 100

    changed = INITIAL.replace("r^ := r^ + 1;", "r^ := r^ + 10;")
    h.send(compiled(changed))
    changes = {c["path"]: c for c in h.ok("reload_preview")["plan"]["changes"]}
    assert changes["Main.r"]["action"] == "initialised"
    h.send(compiled(changed))
    assert h.cmd("reload")["ok"]
    h.cycle()
    values = h.ok("values")["values"]
    assert values["Main.r"] == "Main.level" and values["Main.level"] == 15  # the new instance's
    assert values["Main.c.mine"] == "Main.c.n" and values["Main.c.n"] == 3

    context = take_context(h.resource)
    assert context is not None
    save_context(tmp_path / "context.json", context)
    artifact = compiled(changed)
    again = Resource("R", h.clock)
    again.load(artifact)
    saved = load_context(tmp_path / "context.json", artifact.crc)
    assert not isinstance(saved, ContextInvalid), saved
    warm_start(again, saved)
    assert again.status().start == "warm"
    assert again.variables.value("Main.r") == "Main.level"
    assert again.variables.value("Main.c.mine") == "Main.c.n"
    again.start()
    again.cycle()
    assert again.variables.value("Main.level") == 25 and again.variables.value("Main.c.n") == 4
