"""ACTIONs of programs and function blocks: declared inside the POU or in an ACTIONS block
after it, called as `act();`, `inst.act();` and `Prog.act();`, and named by SFC steps;
traced through `padt sim` (100 ms cycles)."""

from __future__ import annotations

from pathlib import Path

from tests.compiler.test_checks import diagnostics
from tests.conftest import sim_trace

COUNTER = """
FUNCTION_BLOCK Counter
VAR_INPUT step : INT := 1; END_VAR
VAR_OUTPUT n : INT; END_VAR
n := n + step;
ACTION Reset:
  n := 0;
END_ACTION
END_FUNCTION_BLOCK
"""


def test_an_instance_action_runs_on_the_instance_without_its_body(tmp_path: Path) -> None:
    source = (
        COUNTER
        + """
PROGRAM Main
VAR c : Counter; clear : BOOL; END_VAR
c(step := 2);
IF clear THEN c.Reset(); END_IF;
END_PROGRAM
"""
    )
    t = sim_trace(tmp_path, source, 5, "Main.clear=TRUE@3", "Main.clear=FALSE@4")
    # the body adds 2 each cycle; Reset after the body of cycle 3 clears n there
    assert t["Main.c.n"] == [2, 4, 0, 2, 4]


def test_actions_block_after_the_pou_sees_its_variables_and_loop_counter(
    tmp_path: Path,
) -> None:
    source = """
PROGRAM Main
VAR acc : DINT; i : INT; calls : INT; END_VAR
FOR i := 1 TO 3 DO
  Add();
END_FOR;
Count();
END_PROGRAM

ACTIONS
  ACTION Add
    acc := acc + i;  (* reads the counter of the loop that calls it *)
  END_ACTION
  ACTION Count:
    calls := calls + 1;
  END_ACTION
END_ACTIONS
"""
    t = sim_trace(tmp_path, source, 3)
    assert t["Main.acc"] == [6, 12, 18]
    assert t["Main.calls"] == [1, 2, 3]


def test_a_program_action_called_from_another_program(tmp_path: Path) -> None:
    source = """
PROGRAM Pump
VAR runs : INT; END_VAR
runs := runs + 1;
ACTION Stop: runs := 0; END_ACTION
END_PROGRAM
PROGRAM Main
VAR k : INT; END_VAR
k := k + 1;
IF k = 3 THEN Pump.Stop(); END_IF;
END_PROGRAM
CONFIGURATION C
  RESOURCE R ON PLC
    TASK T (INTERVAL := T#100ms, PRIORITY := 1);
    PROGRAM Pump WITH T : Pump;
    PROGRAM Main WITH T : Main;
  END_RESOURCE
END_CONFIGURATION
"""
    t = sim_trace(tmp_path, source, 5)
    assert t["Main.k"] == [1, 2, 3, 4, 5]
    assert t["Pump.runs"] == [1, 2, 0, 1, 2]


def test_a_step_runs_an_action_of_an_actions_block_and_the_body_calls_another(
    tmp_path: Path,
) -> None:
    source = """
PROGRAM Main
VAR go : BOOL; filled : INT; log : INT; END_VAR
Note();
INITIAL_STEP Idle: END_STEP
STEP Fill: Pour(N); END_STEP
TRANSITION FROM Idle TO Fill := go; END_TRANSITION
TRANSITION FROM Fill TO Idle := filled >= 2; END_TRANSITION
END_PROGRAM
ACTIONS Main
  ACTION Pour: filled := filled + 1; END_ACTION
  ACTION Note: log := log + 1; END_ACTION
END_ACTIONS
"""
    t = sim_trace(tmp_path, source, 6, "Main.go=TRUE@2", "Main.go=FALSE@3")
    assert t["Main.Fill.X"] == [False, True, True, False, False, False]
    # Pour runs while Fill is active, and once more (its final scan) in the cycle after
    assert t["Main.filled"] == [0, 0, 1, 2, 3, 3]
    assert t["Main.log"] == [1, 2, 3, 4, 5, 6]


def test_temporaries_start_afresh_in_an_action(tmp_path: Path) -> None:
    source = """
PROGRAM Main
VAR_TEMP t : INT := 5; END_VAR
VAR seen : INT; END_VAR
t := 9;
Look();
ACTION Look: seen := t; END_ACTION
END_PROGRAM
"""
    assert sim_trace(tmp_path, source, 1)["Main.seen"] == [5]


def test_misused_actions_get_their_codes() -> None:
    source = (
        COUNTER
        + """
PROGRAM Main
VAR c : Counter; x : INT; Tick : BOOL; END_VAR
c.Reset(1);
x := c.Reset();
ACTION Tick: x := 1; END_ACTION
END_PROGRAM
"""
    )
    assert diagnostics(source) == [
        "t.st:13:9: error: action 'Reset' of 'Counter' takes no arguments [E0512]",
        "t.st:14:8: error: action 'Reset' has no value; call it as a statement [E0514]",
        "t.st:15:8: error: action 'Tick' has the name of the variable declared at t.st:12:27"
        " [E0513]",
    ]


def test_an_actions_block_needs_its_pou_before_it_in_the_file() -> None:
    source = "ACTIONS Main\nACTION A: ; END_ACTION\nEND_ACTIONS\nPROGRAM Main\nEND_PROGRAM\n"
    assert diagnostics(source) == [
        "t.st:1:1: error: these ACTIONS of 'Main' follow no PROGRAM or FUNCTION_BLOCK of this"
        " file [E0511]"
    ]
