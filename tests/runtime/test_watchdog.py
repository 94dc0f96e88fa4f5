"""A program that never ends cannot hang the controller: the resource watchdog ends the
cycle in ERROR STOP, the runtime keeps answering, and INIT leads back to STOP."""

from __future__ import annotations

import json
import sys
import threading
import time
from pathlib import Path

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import VirtualClock
from runtime.contract.artifact import ResourceConfig
from runtime.contract.protocol import ResourceState
from runtime.contract.refusal import Refusal
from runtime.resource import Resource
from runtime.watchdog import FIRST_BUDGET_NS, Watchdog, WatchdogExpired
from tests.support.resource_harness import harness
from tests.support.runtime_process import running_resource, store_artifact

ENDLESS = {
    "while": "WHILE TRUE DO n := n + 1; END_WHILE;",
    "repeat": "REPEAT n := n + 1; UNTIL FALSE END_REPEAT;",
    "moving for bound": "FOR i := 0 TO n DO n := n + 1; END_FOR;",
    "nested in an FB": "spin(go := TRUE);",
}
SPINNER = """
FUNCTION_BLOCK Spinner
VAR_INPUT go : BOOL; END_VAR
VAR k : DINT; END_VAR
WHILE go DO k := k + 1; END_WHILE;
END_FUNCTION_BLOCK
"""


def endless_program(body: str, autostart: str = "off") -> str:
    return (
        SPINNER + "PROGRAM Loop\nVAR n, i : DINT; spin : Spinner; kept : INT := 7; END_VAR\n"
        f"kept := 8;\n{body}\nEND_PROGRAM\n"
    )


def loaded(body: str) -> Resource:
    config = ResourceConfig(name="R", watchdog_ms=50)
    result = compile_sources([SourceFile("loop.st", endless_program(body))], resource=config)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    resource = Resource("R", VirtualClock())
    resource.load(result.artifact)
    return resource


@pytest.mark.parametrize("form", sorted(ENDLESS))
def test_endless_loops_end_in_error_stop(form: str) -> None:
    resource = loaded(ENDLESS[form])
    resource.start()
    started = time.monotonic()
    resource.cycle()  # returns: the watchdog ends the cycle
    # generous bound: the watchdog is 50 ms; a hang would never return at all
    assert time.monotonic() - started < 5
    assert resource.state == ResourceState.ERROR_STOP
    # the cause names the program, and the POU and line the loop is on
    where = "POU Spinner (loop.st:5)" if form == "nested in an FB" else "POU Loop (loop.st:10)"
    assert resource.status().error == (
        f"watchdog: the cycle took longer than 50 ms (in program Loop) in {where}"
    )
    with pytest.raises(Refusal, match="INIT first"):
        resource.start()


def test_init_leaves_error_stop_with_a_cold_start() -> None:
    resource = loaded(ENDLESS["while"])
    resource.start()
    resource.cycle()
    assert resource.variables.value("Loop.kept") == 8  # the cycle ran up to the loop
    resource.init()
    assert resource.state == ResourceState.STOP_VALID
    assert resource.variables.value("Loop.kept") == 7  # every variable back at its initial value
    with pytest.raises(Refusal):
        resource.init()  # only from ERROR STOP


def test_the_runtime_process_keeps_answering(tmp_path: Path, zenoh_endpoint: str) -> None:
    config = ResourceConfig(name="Spin", watchdog_ms=100, autostart="cold")
    result = compile_sources(
        [SourceFile("loop.st", endless_program(ENDLESS["while"]))], resource=config
    )
    assert result.artifact is not None
    store_artifact(tmp_path, result.artifact)
    with running_resource("Spin", tmp_path, zenoh_endpoint) as (_, client):
        status = client.command("status")["status"]
        assert status["state"] == "ERROR STOP", json.dumps(status)
        assert "watchdog" in status["error"]
        assert client.command("start")["error"]["code"] == "state"
        assert client.command("init")["status"]["state"] == "STOP/VALID CONFIGURATION"


def test_endless_recursion_is_a_program_error_and_the_resource_runs_on() -> None:
    text = """
    FUNCTION Deeper : DINT
    VAR_INPUT n : DINT; END_VAR
    Deeper := Deeper(n + 1);
    END_FUNCTION
    PROGRAM Recurse VAR r : DINT; END_VAR r := Deeper(0); END_PROGRAM
    PROGRAM Tick VAR n : DINT; END_VAR n := n + 1; END_PROGRAM
    """
    # in this process the compiler has raised Python's recursion limit to 20,000 frames:
    # reaching it takes over 100 ms, too close to a 200 ms watchdog on a busy machine
    programs = [{"name": "Recurse"}, {"name": "Tick"}]
    h = harness(text, programs, watchdog_ms=5_000, safety_time_ms=10_000)
    h.cycle(2)
    assert h.state("Recurse") == "ERROR"
    assert h.state() == "RUN" and h.value("Tick.n") == 2
    error = next(p for p in h.resource.status().programs if p.name == "Recurse").error
    assert str(error).startswith("calls nested too deep (recursion) in POU Deeper (test.st:4)")


FOREIGN = 1  # a thread id no thread has: raising into it does nothing


def test_a_deadline_is_claimed_by_the_disarm_in_time_or_by_the_watchdog_never_both() -> None:
    watchdog = Watchdog()
    watchdog.arm(10_000_000_000)
    assert watchdog.disarm() is False  # in time: claimed without the lock
    watchdog.deadlines[FOREIGN] = time.monotonic_ns() - 1  # a thread that overran
    watchdog.deadlines[FOREIGN + 1] = time.monotonic_ns() + 10_000_000_000  # one in time
    with watchdog._lock:
        watchdog._fire_expired()
    assert watchdog._fired == {FOREIGN}  # fired once, its deadline claimed
    assert list(watchdog.deadlines) == [FOREIGN + 1]


def _wakeups(thread: threading.Thread) -> int:
    status = Path(f"/proc/self/task/{thread.native_id}/status").read_text()
    counts = [line.split()[1] for line in status.splitlines() if "ctxt_switches" in line]
    return sum(int(count) for count in counts)


def test_the_watching_thread_sleeps_until_the_deadline() -> None:
    # it looked every millisecond once, taking the interpreter lock each time: 300 looks
    watchdog = Watchdog()
    watchdog.arm(10_000_000_000)
    before = _wakeups(watchdog._thread)
    time.sleep(0.3)
    woken = _wakeups(watchdog._thread) - before
    watchdog.disarm()
    assert woken <= 3


def test_a_shorter_budget_wakes_the_watchdog_sleeping_to_a_longer_one() -> None:
    watchdog = Watchdog()
    watchdog.arm(10_000_000_000)  # this thread: the watching thread sleeps to its deadline
    time.sleep(FIRST_BUDGET_NS / 1e9 + 0.1)  # once it looked after its first sleep
    ended: list[str] = []

    def spin() -> None:
        watchdog.arm(50_000_000)
        try:
            while True:
                pass
        except WatchdogExpired:
            watchdog.disarm()
            ended.append("expired")

    spinner = threading.Thread(target=spin)
    spinner.start()
    spinner.join(timeout=5)  # long before the 10 s: only waking for the 50 ms ends it
    watchdog.disarm()
    assert ended == ["expired"]


def test_once_it_struck_a_function_called_under_a_trace_function_runs() -> None:
    # taken back by clearing it, the exception left CPython's "pending exception" signal
    # on: a function called under a trace function then spun at its entry, never running
    watchdog = Watchdog()
    watchdog.arm(50_000_000)
    try:
        while True:
            pass
    except WatchdogExpired:
        assert watchdog.disarm() is True
    ran: list[str] = []
    watchdog.arm(5_000_000_000)  # what ends the spin if it comes back: this test fails
    sys.settrace(lambda frame, event, arg: None)
    try:
        _called(ran)
    finally:
        sys.settrace(None)
        watchdog.disarm()
    assert ran == ["called"]


def _called(ran: list[str]) -> None:
    ran.append("called")
