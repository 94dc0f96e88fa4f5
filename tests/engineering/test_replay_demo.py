"""The demo recorded with all inputs by its real runtime process (the plant over Modbus TCP,
a write and a force on the way) and replayed by `padt replay`: identical, cycle for cycle;
and a deliberate change of the program reported at the cycle and variable it shows in."""

from __future__ import annotations

import shutil
import subprocess
import sys
import time
from contextlib import closing
from pathlib import Path

import pytest

from backend.engineering.project import compile_project, load_project
from padt.demo import demo_project_with_accounts
from padt.demo_plant import DemoPlant
from runtime.contract import protocol as p
from runtime.contract.recording import Recording, read_recording
from runtime.contract.state_folder import recordings_path
from tests.conftest import REPO, padt
from tests.support.runtime_process import running_resource, store_artifact


def padt_replay(*args: Path) -> subprocess.CompletedProcess[str]:
    command = [sys.executable, "-m", "padt.cli", "replay", *map(str, args)]
    return subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=300)


def test_the_demo_replays_identically_and_a_change_is_named(
    tmp_path: Path, zenoh_endpoint: str
) -> None:
    record_and_replay(tmp_path, zenoh_endpoint, 2.0)


@pytest.mark.slow
@pytest.mark.timeout(1500)
def test_ten_minutes_of_the_demo_replay_identically(tmp_path: Path, zenoh_endpoint: str) -> None:
    record_and_replay(tmp_path, zenoh_endpoint, 600.0)


def record_and_replay(tmp_path: Path, zenoh_endpoint: str, last_s: float) -> None:
    """Record the demo for about 7 s plus `last_s`, replay it, replay a changed version."""
    tank = DemoPlant()
    folder = demo_project_with_accounts(tmp_path, [], tank.start())
    result = compile_project(load_project([folder]))
    assert result.artifact is not None
    store_artifact(tmp_path, result.artifact)
    with (
        closing(tank),
        running_resource("Tank1", tmp_path, zenoh_endpoint, "--modbus-port", "0") as (_, client),
    ):
        client.ask(p.Start())
        time.sleep(1.0)  # the recording begins in the middle of a run
        started = client.ask(p.RecordStart(["TankControl.*"], all_inputs=True, id="demo"))
        assert started.recording.all_inputs and started.recording.state == "recording"
        time.sleep(2.0)
        client.ask(p.Write("TankControl.restartDelay", 1_000_000_000))
        client.ask(p.Force("TankControl.highLevel", 560))
        client.ask(p.StartForcing("TankControl"))
        time.sleep(3.0)
        client.ask(p.StopForcing("TankControl"))
        time.sleep(last_s)
        stopped = client.ask(p.RecordStop("demo")).recording
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:  # the writer finishes the file on its thread
            [info] = [r for r in client.ask(p.RecordList()).recordings if r.id == "demo"]
            if info.files and _finished(recordings_path(tmp_path) / info.files[0].name):
                break
            time.sleep(0.2)
    assert stopped.cycles > 50 and stopped.dropped == 0  # the demo cycles every 100 ms
    path = recordings_path(tmp_path) / "demo-1.mcap"
    recording = read_recording(path)
    assert recording.complete and len(recording.rows) == stopped.cycles
    assert "pumpCommand" in [v for v, _ in recording.header.variables]  # the outputs too
    assert 560 in recording.column("TankControl.highLevel")  # the force is in the recording

    same = padt_replay(path, folder)
    assert same.returncode == 0, same.stderr
    assert same.stdout.strip() == f"replay: {stopped.cycles} cycles, identical"
    replayed_by_a_unit_test(folder, path, recording)

    changed = tmp_path / "changed"
    changed.mkdir()
    for source in (f for f in folder.iterdir() if f.is_file()):  # not its tests
        text = source.read_text(encoding="utf-8")
        changed.joinpath(source.name).write_text(
            text.replace("alarmLow := level < 100;", "alarmLow := level < 1000;")
        )
    differs = padt_replay(path, changed)
    assert differs.returncode == 1, differs.stderr
    first = recording.cycles[0]
    assert differs.stdout.strip().startswith(
        f"replay: cycle {first} (the 1st recorded) differs in TankControl.alarmLow: "
        "recorded False, replayed True"
    ), differs.stdout
    assert "values carried over as by a reload" in differs.stderr


def replayed_by_a_unit_test(folder: Path, path: Path, recording: Recording) -> None:
    """The recording as a regression test (docs/testing.md, REPLAY): from a cold start,
    its cycles with their inputs; the level the program ends with is the plant's last."""
    (folder / "test").mkdir(exist_ok=True)
    shutil.copy(path, folder / "test" / "plant.mcap")
    last_level = recording.column("TankControl.level")[-1]
    (folder / "test" / "replay_test.st").write_text(
        "FUNCTION_BLOCK PlantReplay\n"
        "METHOD TestTheRecordedRun\n"
        "REPLAY('test/plant.mcap');\n"
        f"ASSERT_EQUAL(UDINT#{len(recording.inputs)}, TEST_CYCLES(), 'every recorded cycle');\n"
        f"ASSERT_EQUAL({last_level}, TankControl.level, 'the plant$'s last level');\n"
        "ASSERT_FALSE(TankControl.alarmPlant);\n"
        "END_METHOD\n"
        "END_FUNCTION_BLOCK\n"
    )
    run = padt("test", str(folder), "-k", "PlantReplay", "--tier", "python")
    assert run.returncode == 0, run.stdout + run.stderr
    assert "PASS PlantReplay.TestTheRecordedRun" in run.stdout


def _finished(path: Path) -> bool:
    """An MCAP file ends with its magic once the writer finished it."""
    try:
        return path.read_bytes()[-8:] == b"\x89MCAP0\r\n"
    except OSError:
        return False
