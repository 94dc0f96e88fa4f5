"""Online change and download as the engineering services prepare them for the browser,
the REST API and `padt reload`: against a real runtime process over real Zenoh, the source
diff since the running configuration (from the backup of what was loaded), an online
`target_cycle_ms` of 50 that the reload would put back to the project's 100 (and kept
when the user says so), the download's preconditions, and why a change cannot be made
online, in words."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import pytest

from backend.engineering.compile_gate import compile_checked
from backend.engineering.download import download_checked, plan_download
from backend.engineering.online_change import (
    chosen_resets,
    online_change,
    parameter_resets,
    preview_online_change,
    source_diff,
    why_not_online,
)
from backend.engineering.reload import ReloadOptions, parse_renames, rename_pair
from backend.engineering.resource_client import ResourceClient
from runtime.contract.artifact import ResourceConfig
from runtime.contract.protocol import GetParameters, GetStatus, SetParameter, Start, Stop
from runtime.contract.refusal import Refusal
from runtime.contract.setup_secret import SETUP_USER
from tests.support.runtime_process import (
    KNOWN_SETUP_SECRET,
    know_setup_secret,
    running_resource,
)

RESOURCE = "ChangeRes"

PADT_TOML = """\
[project]
name = "Online change test"
version = "1"

[resource]
name = "ChangeRes"
target_cycle_ms = 100
safety_operation = false
{extra}
[[resource.program]]
name = "Main"
pou = "Main"
id = 1
"""

COUNTER_ST = """\
PROGRAM Main
VAR
  counter : INT := 0;
  limit : INT := 30000;
END_VAR
IF counter < limit THEN
  counter := counter + 1;
END_IF;
END_PROGRAM
"""

# the limit becomes a DINT it cannot carry over (initialised), a variable is added (new)
CHANGED_ST = COUNTER_ST.replace("  limit : INT := 30000;", "  limit : SINT := 100;").replace(
    "END_VAR", "  step : INT := 1;\nEND_VAR"
)


def write_project(folder: Path, source: str = COUNTER_ST, extra: str = "") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "padt.toml").write_text(PADT_TOML.format(extra=extra))
    (folder / "main.st").write_text(source)
    return folder


def wait_for(what: str, condition: Callable[[], bool], timeout_s: float = 30) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, f"never: {what}"
        time.sleep(0.05)


def counter(client: ResourceClient) -> int:
    reply = client.command("values")
    assert reply["ok"], reply
    return int(reply["values"]["Main.counter"])


def target_cycle(client: ResourceClient) -> int:
    return client.ask(GetParameters()).resource.target_cycle_ms


def test_download_then_online_change_with_diff_and_parameter_reset(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    project = write_project(tmp_path / "project")
    backups = tmp_path / "backups"
    know_setup_secret(tmp_path / "state")
    with running_resource(RESOURCE, tmp_path / "state", zenoh_endpoint) as (_, client):
        client.login(SETUP_USER, KNOWN_SETUP_SECRET)
        checked = compile_checked([project])
        first, second = checked.check_crcs
        assert first == second == checked.artifact.crc

        # Download: the resource has no configuration yet and is in STOP
        plan = plan_download(checked, client.ask(GetStatus()).status, None)
        assert plan.possible, plan.refusals
        assert plan.running_crc is None and plan.new_crc == checked.artifact.crc
        assert any("initial value" in effect for effect in plan.effects)
        download_checked(client, checked, backups, "test: load")
        client.ask(Start())
        wait_for("the counter runs", lambda: counter(client) > 2)

        # running, a download is refused before anything is sent, with the reason
        running = plan_download(checked, client.ask(GetStatus()).status, None)
        assert not running.possible
        assert "needs it in STOP" in running.refusals[0]
        assert running.running_crc == checked.artifact.crc
        refused = plan_download(checked, client.ask(GetStatus()).status, None, "a reason")
        assert refused.refusals[0] == "a reason"

        # the engineer speeds the resource up online; then changes the code
        client.ask(SetParameter("target_cycle_ms", 50))
        assert target_cycle(client) == 50
        write_project(project, CHANGED_ST)
        changed = compile_checked([project])
        preview = preview_online_change(client, changed, "demo", {}, backups, {})
        assert preview.possible and not preview.why_not
        assert preview.running_from.startswith("backup ")
        assert [(d.name, d.change) for d in preview.diff] == [("main.st", "changed")]
        diff = preview.diff[0].lines
        assert "-  limit : INT := 30000;" in diff and "+  limit : SINT := 100;" in diff
        assert "+  step : INT := 1;" in diff
        assert diff[0].startswith("@@ ")
        fates = {change.path: change.action for change in preview.plan.changes}
        assert fates == {
            "Main.counter": "kept",
            "Main.limit": "initialised",
            "Main.step": "new",
        }
        assert [risk.title for risk in preview.risks] == ["1 value initialised"]
        assert [(r.name, r.online, r.project, r.keepable) for r in preview.resets] == [
            ("target_cycle_ms", 50, 100, "")
        ]

        # confirmed, keeping the online 50: the value carried over, the cycle stays fast
        before = counter(client)
        keep = chosen_resets(client, changed, ["target_cycle_ms"])
        options = ReloadOptions({}, preview.plan.old_crc)
        done = online_change(client, changed, options, keep, backups, "test: reload")
        assert done.kept == ("target_cycle_ms 50",) and not done.not_kept
        assert done.reloaded.reply.reload.new_crc == changed.artifact.crc
        assert counter(client) >= before  # went on from where it was, not from 0
        assert target_cycle(client) == 50

        # the next change, without keeping it: the project's 100 is back
        write_project(project, CHANGED_ST.replace("step : INT := 1", "step : INT := 2"))
        again = compile_checked([project])
        preview = preview_online_change(client, again, "demo", {}, backups, {})
        assert preview.running_from.startswith("backup ")  # the reload's own backup
        assert [d.change for d in preview.diff] == ["changed"]
        assert any(line == "+  step : INT := 2;" for line in preview.diff[0].lines)
        online_change(client, again, ReloadOptions({}, preview.plan.old_crc), [], backups, "t")
        assert target_cycle(client) == 100
        with pytest.raises(Refusal, match="does not reset it"):
            chosen_resets(client, again, ["target_cycle_ms"])

        # a parameter fixed while running: not possible online, and why, in words
        write_project(project, CHANGED_ST, extra="safety_time_ms = 900")
        fixed = compile_checked([project])
        preview = preview_online_change(client, fixed, "demo", {}, backups, {})
        assert not preview.possible
        assert preview.why_not == (
            "safety_time_ms changes from 600 to 900: it is fixed while the resource runs, "
            "only a download in STOP changes it. Keep 600 in the project for an online "
            "change.",
        )
        assert any(d.name == "padt.toml" for d in preview.diff)
        client.ask(Stop())


def test_the_source_diff_is_sorted_and_names_added_and_removed_files() -> None:
    running = {"b.st": "x\ny\n", "a.st": "one\n", "gone.st": "old\n"}
    new = {"b.st": "x\nz\n", "a.st": "one\n", "c.st": "new\n"}
    diffs = source_diff(running, new)
    assert [(d.name, d.change) for d in diffs] == [
        ("b.st", "changed"),
        ("c.st", "added"),
        ("gone.st", "removed"),
    ]
    assert diffs[0].lines == ("@@ -1,2 +1,2 @@", " x", "-y", "+z")
    assert diffs[1].lines[-1] == "+new"


def test_parameter_resets_are_the_online_ones_that_differ() -> None:
    project = ResourceConfig("R", target_cycle_ms=100, watchdog_ms=200)
    online = ResourceConfig("R", target_cycle_ms=50, watchdog_ms=200, safety_time_ms=700)
    resets = parameter_resets(online, project)
    # safety_time_ms is not online: the plan refuses the reload for it instead
    assert [(r.name, r.online, r.project) for r in resets] == [("target_cycle_ms", 50, 100)]
    locked = ResourceConfig("R", target_cycle_ms=100, allow_online_settings=False)
    online_locked = ResourceConfig("R", target_cycle_ms=50, allow_online_settings=False)
    assert "Allow Online Settings is OFF" in parameter_resets(online_locked, locked)[0].keepable


def test_why_not_online_in_words() -> None:
    said = why_not_online(
        [
            "the resource identity changes (A -> B)",
            "no user program would remain",
            "Reload Allowed of the resource is OFF",
            "Reload Allowed of program Main is OFF",
            "something new the runtime says",
        ]
    )
    assert said[0].startswith("The project is for resource B, this resource is A")
    assert "at least one program" in said[1]
    assert "accepts no online change" in said[2]
    assert said[3].startswith("Program Main changes or goes")
    assert said[4] == "Something new the runtime says."


def test_renames_are_written_old_equals_new_everywhere() -> None:
    assert rename_pair("Main.count=Main.total") == ("Main.total", "Main.count")
    text = "# carried over\nMain.level = Main.measured\n\nMain.fb=Main.valve\n"
    assert parse_renames(text) == ({"Main.measured": "Main.level", "Main.valve": "Main.fb"}, [])
    renames, errors = parse_renames("Main.a -> Main.b\nMain.x=main.X\nMain.c=Main.b\nP.d=main.B")
    assert renames == {}
    assert errors == [
        "line 1: 'Main.a -> Main.b' is not OLD=NEW",
        "line 2: Main.x is renamed to itself",
        "the rename map gives main.B twice",
    ]
