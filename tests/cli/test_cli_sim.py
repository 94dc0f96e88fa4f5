"""`padt sim` as a user runs it: a real process on ST files, JSON lines on stdout."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from tests.conftest import padt

TIMER = """
PROGRAM Blink
VAR
  start : BOOL;
  delay : TON;
  done : BOOL;
END_VAR
delay(IN := start, PT := T#30ms);
done := delay.Q;
END_PROGRAM
"""

GLOBALS = """
VAR_GLOBAL
  gTotal : DINT := 100;
  gLimit : INT := 3;
END_VAR

FUNCTION_BLOCK Counter
VAR_INPUT step : INT; END_VAR
VAR_OUTPUT count : INT; END_VAR
count := count + step;
END_FUNCTION_BLOCK

PROGRAM Main
VAR_EXTERNAL gTotal : DINT; gLimit : INT; END_VAR
VAR
  c : Counter;
  over : BOOL;
END_VAR
c(step := 2);
gTotal := gTotal + c.count;
over := c.count > gLimit;
END_PROGRAM
"""

SFC = """
PROGRAM Seq
VAR go : BOOL; END_VAR
INITIAL_STEP Idle :
END_STEP
STEP Fill :
END_STEP
TRANSITION FROM Idle TO Fill := go;
END_TRANSITION
TRANSITION FROM Fill TO Idle := Fill.T >= T#20ms;
END_TRANSITION
END_PROGRAM
"""

DIVISION = """
PROGRAM Divide
VAR a : INT := 12; b : INT := 2; q : INT; END_VAR
b := b - 1;
q := a / b;
END_PROGRAM

PROGRAM Tick
VAR n : INT; END_VAR
n := n + 1;
END_PROGRAM
"""


def write(tmp_path: Path, text: str, name: str = "prog.st") -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def lines(stdout: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in stdout.splitlines()]


def column(records: list[dict[str, Any]], name: str) -> list[Any]:
    return [record["values"][name] for record in records]


def test_ton_traced_cycle_by_cycle_with_a_later_set(tmp_path: Path) -> None:
    result = padt(
        "sim", write(tmp_path, TIMER), "--cycles", "7", "--cycle-ms", "10",
        "--set", "Blink.start=TRUE@2", "--trace", "Blink.delay.ET,Blink.delay.Q",
        "--trace", "Blink.done",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    records = lines(result.stdout)
    assert [r["cycle"] for r in records] == [1, 2, 3, 4, 5, 6, 7]
    assert [r["t_ms"] for r in records] == [0, 10, 20, 30, 40, 50, 60]  # (k-1) x MS
    assert list(records[0]["values"]) == ["Blink.delay.ET", "Blink.delay.Q", "Blink.done"]
    # IN rises in cycle 2 at t = 10 ms: ET counts in ms (TIME), Q once ET reaches PT
    assert column(records, "Blink.delay.ET") == [0, 0, 10, 20, 30, 30, 30]
    assert column(records, "Blink.delay.Q") == [False, False, False, False, True, True, True]
    assert column(records, "Blink.done") == column(records, "Blink.delay.Q")


def test_default_cycle_is_the_resources_and_every_value_is_printed(tmp_path: Path) -> None:
    result = padt("sim", write(tmp_path, TIMER), "--cycles", "3")
    assert result.returncode == 0, result.stderr
    records = lines(result.stdout)
    assert [r["t_ms"] for r in records] == [0, 100, 200]  # the default resource: 100 ms
    assert {"Blink.start", "Blink.done", "Blink.delay.PT", "Blink.delay.ET"} <= set(
        records[0]["values"]
    )
    assert records[0]["values"]["Blink.delay.PT"] == 30  # TIME in milliseconds


def test_globals_and_fb_members(tmp_path: Path) -> None:
    result = padt(
        "sim", write(tmp_path, GLOBALS), "--cycles", "3",
        "--set", "gLimit=5@2", "--trace", "gTotal,Main.c.count,Main.over,gLimit",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    records = lines(result.stdout)
    assert column(records, "Main.c.count") == [2, 4, 6]
    assert column(records, "gTotal") == [102, 106, 112]
    assert column(records, "gLimit") == [3, 5, 5]
    assert column(records, "Main.over") == [False, False, True]


def test_an_instance_name_traces_everything_below_it(tmp_path: Path) -> None:
    result = padt("sim", write(tmp_path, GLOBALS), "--cycles", "1", "--trace", "main.C")
    assert result.returncode == 0, result.stderr
    found = lines(result.stdout)[0]["values"]
    assert found == {"Main.c.step": 2, "Main.c.count": 2, "Main.c.ENO": True}


def test_sfc_steps_are_traced_with_x_and_t(tmp_path: Path) -> None:
    result = padt(
        "sim", write(tmp_path, SFC), "--cycles", "6", "--cycle-ms", "10",
        "--set", "Seq.go=TRUE@2", "--set", "Seq.go=FALSE@3",
        "--trace", "Seq.Idle.X,Seq.Fill.X,Seq.Fill.T",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    records = lines(result.stdout)
    assert column(records, "Seq.Idle.X") == [True, False, False, False, True, True]
    assert column(records, "Seq.Fill.X") == [False, True, True, True, False, False]
    # Fill is entered at the end of cycle 2; T is 0 in its first active cycle, then counts
    # virtual time, and keeps its last value once the step is left
    assert column(records, "Seq.Fill.T") == [0, 0, 0, 10, 20, 20]


def test_time_values_are_milliseconds(tmp_path: Path) -> None:
    source = """
    PROGRAM T
    VAR whole : TIME := T#2s; part : TIME := T#1.5ms; long : LTIME := LTIME#3ms; END_VAR
    END_PROGRAM
    """
    result = padt("sim", write(tmp_path, source), "--cycles", "2", "--set", "T.whole=T#-20ms@2")
    assert result.returncode == 0, result.stderr
    first, second = (r["values"] for r in lines(result.stdout))
    assert first == {"T.whole": 2000, "T.part": 1.5, "T.long": 3}
    assert second["T.whole"] == -20


def test_compile_errors_exit_1_with_file_line_col(tmp_path: Path) -> None:
    path = write(tmp_path, "PROGRAM P\nVAR x : INT; END_VAR\nx := nothing;\nEND_PROGRAM\n")
    result = padt("sim", path)
    assert result.returncode == 1
    assert result.stdout == ""
    assert f"{path}:3:6: error: 'nothing' is not declared [E0201]" in result.stderr


def test_unknown_names_exit_2_before_running(tmp_path: Path) -> None:
    path = write(tmp_path, TIMER)
    traced = padt("sim", path, "--trace", "Blink.done,Blink.nothing")
    assert traced.returncode == 2
    assert traced.stdout == ""
    assert "Blink.nothing" in traced.stderr
    written = padt("sim", path, "--set", "Blink.nope=TRUE")
    assert written.returncode == 2 and written.stdout == ""
    assert "Blink.nope" in written.stderr


def test_a_long_name_is_cut_in_the_message(tmp_path: Path) -> None:
    path = write(tmp_path, TIMER)
    name = "Blink." + "x" * 50_000
    for option in (("--trace", name), ("--set", f"{name}=TRUE"), ("--set", name)):
        result = padt("sim", path, *option)
        assert result.returncode == 2 and result.stdout == "", option[0]
        assert "Blink.xxx" in result.stderr and "[...]" in result.stderr
        assert len(result.stderr) < 1_000


def test_bad_values_exit_2(tmp_path: Path) -> None:
    path = write(tmp_path, GLOBALS)
    for setting, message in (
        ("gLimit=40000", "outside the range of INT"),
        ("gLimit=TRUE", "not an ST literal of type INT"),
        ("gLimit=1@99", "after the last cycle"),
    ):
        result = padt("sim", path, "--set", setting)
        assert result.returncode == 2, setting
        assert message in result.stderr and result.stdout == ""


def test_division_by_zero_puts_the_program_in_error_and_the_run_goes_on(
    tmp_path: Path,
) -> None:
    result = padt("sim", write(tmp_path, DIVISION), "--cycles", "4")
    assert result.returncode == 3, result.stderr  # all cycles ran, but a program failed
    records = lines(result.stdout)
    assert len(records) == 4
    assert column(records, "Tick.n") == [1, 2, 3, 4]  # the other program runs on
    assert column(records, "Divide.q") == [12, 12, 12, 12]  # no store after the fault
    assert column(records, "Divide.b") == [1, 0, 0, 0]  # in ERROR: no more cycles
    # the fault names the POU and the ST line where it happened
    source = tmp_path / "prog.st"
    assert result.stderr.splitlines() == [
        f"padt sim: cycle 2: program Divide: integer division by zero in POU Divide ({source}:5)"
    ]


ENDLESS = """
PROGRAM Spin
VAR n : INT; END_VAR
n := n + 1;
IF n = 3 THEN
  WHILE TRUE DO n := n; END_WHILE;
END_IF;
END_PROGRAM

PROGRAM Tick
VAR n : INT; END_VAR
n := n + 1;
END_PROGRAM
"""


def test_an_endless_loop_ends_the_run_in_error_stop_with_its_place(tmp_path: Path) -> None:
    """The resource watchdog (200 ms of real time by default) ends the cycle that never
    ends: the resource goes to ERROR STOP, as on the controller, and nothing runs after."""
    result = padt("sim", write(tmp_path, ENDLESS), "--cycles", "6")
    assert result.returncode == 4, result.stderr
    records = lines(result.stdout)
    assert [r["cycle"] for r in records] == [1, 2, 3]  # the cycle of the loop is the last
    assert column(records, "Spin.n") == [1, 2, 3]
    assert column(records, "Tick.n") == [1, 2, 2]  # Tick runs after Spin: not in cycle 3
    source = tmp_path / "prog.st"
    assert result.stderr.splitlines() == [
        "padt sim: cycle 3: resource Resource1: ERROR STOP, watchdog: the cycle took longer "
        f"than 200 ms (in program Spin) in POU Spin ({source}:6)"
    ]


def test_literals_of_several_types(tmp_path: Path) -> None:
    source = """
    PROGRAM L
    VAR w : WORD; r : REAL; lr : LREAL; s : STRING; b : BOOL; i : SINT; END_VAR
    END_PROGRAM
    """
    result = padt(
        "sim", write(tmp_path, source), "--cycles", "1",
        "--set", "L.w=16#FF", "--set", "L.r=-3.5", "--set", "L.lr=1.0E3",
        "--set", "L.s='it$'s@home'", "--set", "L.b=true", "--set", "L.i=-128",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    values = lines(result.stdout)[0]["values"]
    assert values == {
        "L.w": 255, "L.r": -3.5, "L.lr": 1000.0, "L.s": "it's@home", "L.b": True, "L.i": -128,
    }  # fmt: skip


def test_two_runs_give_identical_output(tmp_path: Path) -> None:
    path = write(tmp_path, TIMER + GLOBALS + SFC, "all.st")
    args = ("sim", path, "--cycles", "25", "--cycle-ms", "7", "--set", "Seq.go=TRUE@3")
    first = padt(*args, env={"PYTHONHASHSEED": "1"})
    second = padt(*args, env={"PYTHONHASHSEED": "2"})
    assert first.returncode == 0, first.stderr
    assert first.stdout == second.stdout
    assert len(first.stdout.splitlines()) == 25


def test_arrays_and_a_program_called_from_another(tmp_path: Path) -> None:
    source = """
    TYPE Pt : STRUCT x : INT; END_STRUCT; END_TYPE
    PROGRAM Helper
    VAR calls : INT; END_VAR
    calls := calls + 1;
    END_PROGRAM
    PROGRAM Main
    VAR pts : ARRAY[1..2] OF Pt; laps : ARRAY[0..2] OF TIME; seen : INT; END_VAR
    Helper();
    seen := Helper.calls;
    pts[2].x := pts[2].x + 10;
    laps[1] := T#1.5ms;
    END_PROGRAM
    """
    # Helper runs as a user program and is called by Main: one instance, two calls a cycle
    result = padt("sim", write(tmp_path, source), "--cycles", "2", "--trace", "Main,Helper")
    assert result.returncode == 0, result.stderr
    second = lines(result.stdout)[1]["values"]
    assert second == {
        "Main.pts[1].x": 0, "Main.pts[2].x": 20, "Main.laps": [0, 1.5, 0], "Main.seen": 4,
        "Helper.calls": 4,
    }  # fmt: skip


SLICED_PROJECT = """
[resource]
name = "Sliced"
target_cycle_ms = 10
multitasking_mode = 1

[[resource.program]]
name = "Worker"
id = 1
max_duration_us = 4
max_cycles = 5

[[resource.program]]
name = "Watcher"
id = 2
priority = 1
"""
SLICED_SOURCE = """
VAR_GLOBAL done : DINT; END_VAR
PROGRAM Worker
VAR_EXTERNAL done : DINT; END_VAR
VAR i, k : DINT; END_VAR
FOR i := 1 TO 10 DO k := k + 1; END_FOR;
done := done + 1;
END_PROGRAM
PROGRAM Watcher
VAR_EXTERNAL done : DINT; END_VAR
VAR seen : DINT; END_VAR
seen := done;
END_PROGRAM
"""


def test_sim_runs_time_slices_on_virtual_time(tmp_path: Path) -> None:
    """A program with a 4 us slice needs three CPU cycles for its ten loop passes (1 us
    each on virtual time); its writes show in the other program one cycle later."""
    (tmp_path / "padt.toml").write_text(SLICED_PROJECT)
    (tmp_path / "main.st").write_text(SLICED_SOURCE)
    result = padt("sim", str(tmp_path), "--cycles", "7", "--trace", "Worker.k,done,Watcher.seen")
    assert result.returncode == 0, result.stderr
    records = lines(result.stdout)
    assert column(records, "Worker.k") == [4, 8, 10, 14, 18, 20, 24]
    assert column(records, "done") == [0, 0, 1, 1, 1, 2, 2]
    assert column(records, "Watcher.seen") == [0, 0, 0, 1, 1, 1, 2]
    again = padt("sim", str(tmp_path), "--cycles", "7", "--trace", "Worker.k,done,Watcher.seen")
    assert again.stdout == result.stdout  # reproducible to the byte


GRID = """
TYPE Cell : STRUCT x : INT; END_STRUCT; END_TYPE
PROGRAM M
VAR g : ARRAY[0..1, 0..1] OF Cell; n : INT; END_VAR
n := n + 1;
g[1, 0].x := n * 10;
END_PROGRAM
"""


def test_an_element_of_a_two_dimensional_array_is_traced_by_its_name(tmp_path: Path) -> None:
    """The comma between the brackets is the name's, not a separator of names."""
    result = padt(
        "sim", write(tmp_path, GRID), "--cycles", "2", "--trace", "M.g[1,0].x,M.n"
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert [line["values"] for line in lines(result.stdout)] == [
        {"M.g[1,0].x": 10, "M.n": 1},
        {"M.g[1,0].x": 20, "M.n": 2},
    ]


SHARED = """
FUNCTION_BLOCK Share
VAR_INPUT total : DINT; parts : INT; END_VAR
VAR_OUTPUT each : DINT; calls : INT; END_VAR
calls := calls + 1;
each := total / parts;
END_FUNCTION_BLOCK

PROGRAM Main
VAR
  n : INT := 3;
  total : DINT := 100;
  mean : REAL;
  split : Share;
END_VAR
n := n - 1;
total := total * 3 + n;
split(total := total, parts := n);
mean := DINT_TO_REAL(split.each) / 3.0;
END_PROGRAM
"""


@pytest.mark.usefixtures("native_tier")
def test_both_tiers_give_the_same_output_and_fault(tmp_path: Path) -> None:
    """The default is the tier `padt runtime` runs by default: the bodies built as C (into
    the cache), where `--tier python` builds nothing; both print the same values and the
    same fault, at the same ST line of the function block."""
    path = write(tmp_path, SHARED)
    cache = tmp_path / "native"
    env = {"PADT_NATIVE_CACHE": str(cache)}
    python = padt("sim", path, "--cycles", "4", "--tier", "python", env=env)
    assert not list(cache.rglob("*.so"))
    native = padt("sim", path, "--cycles", "4", env=env)
    assert list(cache.rglob("*.so")), native.stderr  # Main and Share, compiled
    named = padt("sim", path, "--cycles", "4", "--tier", "native", env=env)
    assert python.returncode == native.returncode == named.returncode == 3, python.stderr
    assert python.stdout == native.stdout == named.stdout
    assert python.stderr == native.stderr == named.stderr
    records = lines(python.stdout)
    assert column(records, "Main.total") == [302, 907, 2721, 2721]
    assert column(records, "Main.split.each") == [151, 907, 907, 907]
    # REAL: the 32-bit float of each quotient
    assert column(records, "Main.mean") == [50.33333206176758] + [302.3333435058594] * 3
    assert python.stderr.splitlines() == [
        f"padt sim: cycle 3: program Main: integer division by zero in POU Share ({path}:6)"
    ]


LABELLED = """
FUNCTION_BLOCK Animal
VAR_OUTPUT legs : INT; END_VAR
legs := 4;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Bird EXTENDS Animal
legs := 2;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Label
VAR_INPUT n : INT; END_VAR
VAR_IN_OUT animal : Animal; END_VAR
VAR_OUTPUT text : STRING[20]; END_VAR
animal();
text := CONCAT('legs=', INT_TO_STRING(animal.legs * n));
END_FUNCTION_BLOCK

PROGRAM Main
VAR n : INT; bird : Bird; label : Label; END_VAR
n := n + 1;
label(n := n, animal := bird);
END_PROGRAM
"""


@pytest.mark.usefixtures("native_tier")
def test_native_says_which_bodies_run_as_python_and_why(tmp_path: Path) -> None:
    """An in-out of a block that another block extends is not C yet (it may hold the derived
    block, whose members the tier reads by name): on the native tier `padt sim` says, once
    per body, that the block (and the program that binds it) runs as Python and why, as the
    runtime's event does; the values are those of Python."""
    path = write(tmp_path, LABELLED)
    env = {"PADT_NATIVE_CACHE": str(tmp_path / "native")}
    native = padt("sim", path, "--cycles", "2", "--tier", "native", env=env)
    python = padt("sim", path, "--cycles", "2", "--tier", "python", env=env)
    assert native.returncode == python.returncode == 0, native.stderr
    assert native.stdout == python.stdout
    assert column(lines(native.stdout), "Main.label.text") == ["legs=2", "legs=4"]
    said = native.stderr.splitlines()
    assert [line.partition(" runs as Python: ")[0] for line in said] == [
        "padt sim: Label",
        "padt sim: Main",
    ], said
    assert "the variable animal" in said[0], said
    assert python.stderr == ""
