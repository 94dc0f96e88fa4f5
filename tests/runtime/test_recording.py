"""Recording (spec section 15, docs/recording.md) inside one resource on virtual time: the
values of every cycle in an MCAP file, a trigger with cycles before it, a full queue that
drops and counts, and all inputs that `replay` repeats to the bit, or names the first
cycle and variable that differ."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.replay import ReplayError, replay
from runtime.clock import VirtualClock
from runtime.code.native.tier import NativeTier
from runtime.contract import protocol as p
from runtime.contract.artifact import Artifact, ProgramConfig, ResourceConfig
from runtime.contract.recording import read_recording
from runtime.contract.refusal import Refusal
from runtime.online_writes import write
from runtime.recorder import Recordings
from runtime.resource import Resource

PLANT = """
VAR_GLOBAL
  level AT %IW0 : INT;
  pump AT %QX0.0 : BOOL;
  alarms : DINT;
END_VAR
PROGRAM Control
VAR_EXTERNAL level : INT; pump : BOOL; alarms : DINT; END_VAR
VAR
  high : BOOL; t : TON; n : DINT; ratio : REAL; tick : UDINT; history : ARRAY[0..3] OF INT;
END_VAR
n := n + 1;
history[n MOD 4] := level;
IF level < 300 THEN pump := TRUE; ELSIF level > 700 THEN pump := FALSE; END_IF;
t(IN := level > 650, PT := T#120ms);
IF t.Q AND NOT high THEN alarms := alarms + 1; END_IF;
high := t.Q;
ratio := INT_TO_REAL(level) / 1000.0;
tick := SYS.SYSTEM_TICK;
END_PROGRAM
PROGRAM Other
VAR_EXTERNAL alarms : DINT; END_VAR
VAR seen : DINT; END_VAR
seen := alarms * 2;
END_PROGRAM
"""


def compiled(source: str = PLANT) -> Artifact:
    config = ResourceConfig(
        name="Plant", target_cycle_ms=10, safety_operation=False, global_forcing_allowed=True
    )
    programs = [ProgramConfig("Control", "Control", 1), ProgramConfig("Other", "Other", 2)]
    result = compile_sources([SourceFile("plant.st", source)], resource=config, programs=programs)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


def started(
    tmp_path: Path, artifact: Artifact | None = None, native: NativeTier | None = None
) -> Resource:
    """With `native`, the bodies C and the variables in native memory from the start."""
    resource = Resource(
        "Plant", VirtualClock(start_ns=5_000_000_000, epoch_ns=1_700_000_000 * 10**9)
    )
    resource.recordings = Recordings(tmp_path / "recordings")
    resource.native = native
    resource.load(artifact or compiled())
    resource.tier_up(wait=True)
    assert (resource.variables.image is not None) == (native is not None)
    resource.start()
    return resource


def run(resource: Resource, cycles: int, level: list[int]) -> None:
    """Cycles of 10 ms (some a little longer, as real ones are) with a plant that fills
    while the pump runs."""
    clock = resource.clock
    assert isinstance(clock, VirtualClock)
    for n in range(cycles):
        resource.io.set_inputs({"level": level[0]})
        resource.cycle()
        pump = resource.variables.value("pump")
        level[0] = max(0, min(1000, level[0] + (9 if pump else -4)))
        clock.advance(10_000_000 + (n % 7) * 130_000)


def recordings_of(resource: Resource) -> Recordings:
    assert isinstance(resource.recordings, Recordings)
    return resource.recordings


def finished(resource: Resource) -> None:
    recordings_of(resource).close()


def test_every_cycle_of_the_chosen_variables_is_in_the_file(tmp_path: Path) -> None:
    resource = started(tmp_path)
    recordings = recordings_of(resource)
    info = recordings.start(resource, p.RecordStart(["Control.*", "level"], cycles=40, id="r1"))
    assert info.state == "recording" and info.variables == 13  # the TON's 7 with its ENO
    run(resource, 60, [500])
    finished(resource)
    [done] = recordings.infos()
    assert (done.state, done.cycles, done.dropped) == ("done", 40, 0)
    assert [f.name for f in done.files] == ["r1-1.mcap"]
    recording = read_recording(tmp_path / "recordings" / "r1-1.mcap")
    assert recording.complete and recording.header.project and not recording.header.all_inputs
    assert len(recording.rows) == 40
    assert recording.cycles == list(range(1, 41))
    assert recording.column("Control.n") == list(range(1, 41))
    assert recording.column("Control.history")[3] == [488, 500, 496, 492]  # the level falls
    times = recording.times_ns
    assert all(b > a for a, b in itertools.pairwise(times))
    assert times[0] // 10**9 == 1_700_000_005  # calendar time of the first cycle


def test_a_trigger_keeps_the_cycles_before_it(tmp_path: Path) -> None:
    resource = started(tmp_path)
    recordings = recordings_of(resource)
    trigger = p.Trigger("level", ">", 560)
    recordings.start(
        resource, p.RecordStart(["level"], trigger=trigger, pre_cycles=5, cycles=10, id="t1")
    )
    run(resource, 25, [500])
    assert recordings.infos()[0].state == "waiting"
    run(resource, 60, [200])  # the pump fills it past 560
    finished(resource)
    [info] = recordings.infos()
    assert info.state == "done" and info.cycles == 15 and info.trigger_cycle is not None
    levels = read_recording(tmp_path / "recordings" / "t1-1.mcap").column("level")
    assert len(levels) == 15
    assert max(levels[:5]) <= 560 < levels[5]  # five before, then the trigger's cycle


def test_refusals_name_what_is_wrong(tmp_path: Path) -> None:
    resource = started(tmp_path)
    recordings = recordings_of(resource)
    cases = [
        (p.RecordStart(["nothing.here"]), "unknown_variable"),
        (p.RecordStart(["Zz*"]), "unknown_variable"),
        (p.RecordStart(["level"], pre_cycles=3), "bad_request"),
        (p.RecordStart(["level"], all_inputs=True, trigger=p.Trigger("pump")), "bad_request"),
        (p.RecordStart(["level"], trigger=p.Trigger("level", ">", "high")), "bad_value"),
    ]
    for command, code in cases:
        with pytest.raises(Refusal) as refused:
            recordings.start(resource, command)
        assert refused.value.code == code, command
    with pytest.raises(Refusal) as refused:
        recordings.reading("../../etc-1.mcap", 0, 10)
    assert refused.value.code == "unknown_recording"
    assert recordings.infos() == []


def test_a_writer_that_falls_behind_drops_and_counts(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("runtime.trace_writer.MAX_QUEUED_VALUES", 1)
    monkeypatch.setattr("runtime.trace_writer._IDLE_S", 5.0)  # the writer sleeps: it falls behind
    resource = started(tmp_path)
    recordings = recordings_of(resource)
    recordings.start(resource, p.RecordStart(["level"], cycles=400, id="d1"))
    run(resource, 400, [500])
    [info] = recordings.infos()
    assert info.dropped > 0 and info.cycles + info.dropped == 400
    finished(resource)
    rows = read_recording(tmp_path / "recordings" / "d1-1.mcap").rows
    assert len(rows) == info.cycles


def recorded_run(tmp_path: Path, native: NativeTier | None = None) -> Path:
    """300 cycles with all inputs: inputs from the plant, a write, forcing on and off."""
    resource = started(tmp_path, native=native)
    recordings = recordings_of(resource)
    level = [500]
    run(resource, 30, level)  # the recording starts in the middle of a run
    recordings.start(
        resource, p.RecordStart(["Control.*", "Other.*", "alarms"], all_inputs=True, id="all")
    )
    run(resource, 100, level)
    write(resource, "alarms", 40)
    resource.forcing.force("level", 680)  # a forced input: the plant is ignored
    resource.forcing.start()
    run(resource, 100, level)
    resource.forcing.stop()
    run(resource, 100, level)
    recordings.stop(resource, "all")
    finished(resource)
    return tmp_path / "recordings" / "all-1.mcap"


def test_all_inputs_replay_identically(tmp_path: Path) -> None:
    path = recorded_run(tmp_path)
    recording = read_recording(path)
    assert len(recording.rows) == 300 and len(recording.inputs) == 300
    assert "pump" in [v for v, _ in recording.header.variables]  # every output is recorded
    assert max(recording.column("alarms")) >= 40
    result = replay(recording, compiled())
    assert result.difference is None and result.cycles == 300, result.summary()
    assert result.summary() == "replay: 300 cycles, identical"


@pytest.mark.parametrize("replayed_on", ["native", "python"])
def test_a_recording_of_native_memory_replays_identically_on_either_tier(
    tmp_path: Path, native_tier: NativeTier, replayed_on: str
) -> None:
    """Recorded with the variables in native memory (its reader made from the image), the
    same 300 cycles replay to the bit with the variables in native memory or on objects."""
    recording = read_recording(recorded_run(tmp_path, native_tier))
    assert len(recording.rows) == 300 and max(recording.column("alarms")) >= 40
    result = replay(recording, compiled(), native_tier if replayed_on == "native" else None)
    assert result.summary() == "replay: 300 cycles, identical"
    assert read_recording(recorded_run(tmp_path / "objects")).rows == recording.rows


def test_a_changed_program_is_named_at_its_first_different_cycle(tmp_path: Path) -> None:
    recording = read_recording(recorded_run(tmp_path))
    changed = compiled(PLANT.replace("alarms := alarms + 1;", "alarms := alarms + 2;"))
    result = replay(recording, changed)
    assert result.reloaded and result.difference is not None
    alarms = recording.column("alarms")
    first_alarm = next(i for i, (a, b) in enumerate(itertools.pairwise(alarms)) if b > a)
    assert result.difference.index == first_alarm + 2
    assert result.difference.variable in ("alarms", "Other.seen")
    assert "differs in" in result.summary()


def test_a_recording_without_inputs_is_refused(tmp_path: Path) -> None:
    resource = started(tmp_path)
    recordings = recordings_of(resource)
    recordings.start(resource, p.RecordStart(["level"], cycles=3, id="v"))
    run(resource, 3, [500])
    finished(resource)
    with pytest.raises(ReplayError, match="--all-inputs"):
        replay(read_recording(tmp_path / "recordings" / "v-1.mcap"), compiled())


def test_non_finite_reals_survive_the_file(tmp_path: Path) -> None:
    source = PLANT.replace("ratio := INT_TO_REAL(level) / 1000.0;", "ratio := 1.0E38 * 1.0E38;")
    resource = started(tmp_path, compiled(source))
    recordings = recordings_of(resource)
    recordings.start(resource, p.RecordStart(["Control.ratio"], cycles=2, id="inf"))
    run(resource, 2, [500])
    finished(resource)
    ratios = read_recording(tmp_path / "recordings" / "inf-1.mcap").column("Control.ratio")
    assert ratios and all(math.isinf(float(r)) for r in ratios)


def test_the_recordings_of_an_earlier_run_are_listed_from_their_files(tmp_path: Path) -> None:
    resource = started(tmp_path)
    recordings = recordings_of(resource)
    recordings.start(resource, p.RecordStart(["Control.*"], cycles=25, rotate_s=1, id="old"))
    run(resource, 25, [500])
    finished(resource)
    before = recordings.infos()[0]
    (tmp_path / "recordings" / "cut-1.mcap").write_bytes(
        (tmp_path / "recordings" / "old-1.mcap").read_bytes()[:-300]  # cut before its end
    )
    [cut, old] = Recordings(tmp_path / "recordings").infos()  # the runtime restarted
    assert (old.id, old.state, old.cycles, old.variables) == ("old", "done", 25, 12)
    assert old.started_ns == before.started_ns and old.files == before.files
    assert cut.id == "cut" and cut.cycles == 25 and "cut short" in (cut.error or "")


def test_the_variables_recorded_at_once_are_limited_over_all_recordings(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("runtime.recorder.MAX_VARIABLES", 15)
    resource = started(tmp_path)
    recordings = recordings_of(resource)
    first = recordings.start(resource, p.RecordStart(["Control.*"], id="a"))
    assert first.variables == 12
    with pytest.raises(Refusal) as refused:  # 12 running + 5 more is over 15
        recordings.start(
            resource, p.RecordStart(["Other.*", "level", "pump", "alarms", "Control.n"])
        )
    assert refused.value.code == "too_many" and "12 by the recordings running" in str(refused.value)
    # many patterns, each found by bisection, and a prefix of any case
    patterns = [f"control.h{'i' * (n % 3)}*" for n in range(4096)]
    with pytest.raises(Refusal) as refused:
        recordings.start(resource, p.RecordStart(patterns))
    assert refused.value.code == "unknown_variable"  # control.hii*: no such variable
    hits = recordings.start(resource, p.RecordStart(["CONTROL.HI*", "other.s*"], id="b"))
    assert hits.variables == 3  # Control.high, Control.history, Other.seen
    finished(resource)


def test_a_damaged_recording_is_refused_by_replay_not_run(tmp_path: Path) -> None:
    recording = read_recording(recorded_run(tmp_path))
    recording.inputs[3].system = {"now_ns": 5}  # no system variable: a hostile file
    with pytest.raises(ReplayError, match=r"inputs of cycle .* are damaged"):
        replay(recording, compiled())
    recording = read_recording(tmp_path / "recordings" / "all-1.mcap")
    assert recording.start is not None
    recording.start.programs["Control"]["state"] = "FLYING"
    with pytest.raises(ReplayError, match="start state is damaged"):
        replay(recording, compiled())
