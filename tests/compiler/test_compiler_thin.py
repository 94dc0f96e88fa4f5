"""The compiler's thin path: ST subset to Python, diagnostics, deterministic CRCs."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.project import demo_project_path
from padt.demo_plant import START_LEVEL, tick
from runtime.clock import VirtualClock
from runtime.resource import Resource
from tests.conftest import padt

WRAP = """
PROGRAM Wrap
VAR
  i : INT := 32767;
  d : DINT;
  q : INT;
  b : BOOL;
END_VAR
i := i + 1;
d := 7;
q := -7 / 2;
b := i < 0 AND NOT FALSE;
END_PROGRAM
"""


def started(text: str) -> tuple[Resource, VirtualClock]:
    """A resource running `text`, on a virtual clock."""
    result = compile_sources([SourceFile("t.st", text)])
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    clock = VirtualClock()
    resource = Resource("R", clock)
    resource.load(result.artifact)
    resource.start()
    return resource, clock


def run_cycles(text: str, cycles: int, cycle_ms: int = 100) -> list[dict[str, Any]]:
    resource, clock = started(text)
    trace = []
    for _ in range(cycles):
        resource.cycle()
        trace.append(resource.variables.values())
        clock.advance(cycle_ms * 1_000_000)
    return trace


def test_integer_arithmetic_wraps_and_divides_toward_zero() -> None:
    values = run_cycles(WRAP, 1)[0]
    assert values["Wrap.i"] == -32768  # INT 32767 + 1 wraps in two's complement
    assert values["Wrap.q"] == -3  # IEC division truncates toward zero
    assert values["Wrap.b"] is True


def test_ton_q_goes_true_when_elapsed_time_reaches_preset() -> None:
    source = """
    PROGRAM P
    VAR t : TON; start : BOOL := TRUE; END_VAR
    t(IN := start, PT := T#300ms);
    END_PROGRAM
    """
    trace = run_cycles(source, 6)
    # cycle k runs at (k-1) x 100 ms; IN rises in cycle 1 at t=0
    assert [v["P.t.ET"] // 1_000_000 for v in trace] == [0, 100, 200, 300, 300, 300]  # ns -> ms
    assert [v["P.t.Q"] for v in trace] == [False, False, False, True, True, True]


def test_every_error_is_reported_with_file_line_col() -> None:
    source = """PROGRAM P
VAR x : INT; c : INT := 1; flag : BOOL; END_VAR
x := undefinedName;
flag := x;
x := 40000;
IF x THEN x := 1; END_IF;
END_PROGRAM
"""
    result = compile_sources([SourceFile("bad.st", source)])
    assert result.artifact is None
    rendered = [str(d) for d in result.diagnostics]
    assert rendered == [
        "bad.st:3:6: error: 'undefinedName' is not declared [E0201]",
        "bad.st:4:9: error: type mismatch: cannot assign INT to BOOL [E0209]",
        "bad.st:5:6: error: 40000 is out of range for INT [E0210]",
        "bad.st:6:4: error: condition must be BOOL, not INT [E0307]",
    ]


def test_syntax_errors_in_several_files_are_all_reported() -> None:
    result = compile_sources(
        [
            SourceFile("a.st", "PROGRAM A\nx := ;\nEND_PROGRAM\n"),
            SourceFile("b.st", "PROGRAM B\nIF TRUE THEN\nEND_PROGRAM\n"),
        ]
    )
    files = [(d.file, d.line) for d in result.diagnostics]
    assert files == [("a.st", 2), ("b.st", 3)]
    assert all("syntax error" in d.message for d in result.diagnostics)


def test_demo_project_compiles_and_runs_the_tank_in_closed_loop_with_its_plant() -> None:
    """TankControl and the demo's plant (its tank, one tick per cycle of 100 ms) for a
    minute of virtual time, the plant's level as tankLevel, pumpCommand as its pump."""
    resource, clock = started((demo_project_path() / "tank.st").read_text())
    level, running, trace = START_LEVEL, False, []
    for _ in range(600):
        resource.io.set_inputs({"tankLevel": level, "pumpRunning": running})
        resource.cycle()
        values = resource.variables.values()
        trace.append((level, values))
        running = resource.io.outputs["pumpCommand"]
        level = tick(level, running)
        clock.advance(100_000_000)
    assert all(v["TankControl.level"] == plant for plant, v in trace)  # no model of its own
    assert not any(v["TankControl.alarmPlant"] for _, v in trace)
    levels = [plant for plant, _ in trace]
    assert max(levels) <= 805 and min(levels) >= 235  # the marks, give or take the delay
    starts = [v["TankControl.pumpStarts"] for _, v in trace]
    assert starts[-1] == 2  # filled, rested, restarted after the refill delay: twice


def test_cli_compile_json_and_exit_codes(tmp_path: Path) -> None:
    good = padt("compile", "--json", str(demo_project_path()))
    assert good.returncode == 0, good.stderr
    report = json.loads(good.stdout)
    assert report["ok"] is True and len(report["crc"]["configuration"]) == 8
    bad_file = tmp_path / "bad.st"
    bad_file.write_text("PROGRAM P\nVAR x : INT; END_VAR\nx := y;\nEND_PROGRAM\n")
    bad = padt("compile", str(bad_file))
    assert bad.returncode == 1
    assert f"{bad_file}:3:6: error: 'y' is not declared [E0201]" in bad.stdout
    bad_json = padt("compile", "--json", str(bad_file))
    assert bad_json.returncode == 1
    assert json.loads(bad_json.stdout)["diagnostics"] == [
        {
            "file": str(bad_file),
            "line": 3,
            "col": 6,
            "severity": "error",
            "message": "'y' is not declared",
            "code": "E0201",
        }
    ]


def test_same_crc_in_two_processes_with_different_hash_seeds() -> None:
    crcs = []
    for seed in ("1", "4242"):
        run = padt("compile", "--json", str(demo_project_path()), env={"PYTHONHASHSEED": seed})
        assert run.returncode == 0, run.stderr
        crcs.append(json.loads(run.stdout)["crc"])
    assert crcs[0] == crcs[1]
    assert crcs[0]["configuration"] != ""
