"""The runtime asks for a higher priority than the PADT and browsers beside it, for every
thread it has, and for its cycle thread the real-time class."""

from __future__ import annotations

import contextlib
import os
import threading
from pathlib import Path

import pytest

from backend.engineering.project import compile_project, load_project
from backend.engineering.reload import ReloadOptions, reload
from runtime.clock import RealClock
from runtime.contract.protocol import GetValues
from runtime.contract.session import open_client, open_router
from runtime.cycle_driver import CycleDriver
from runtime.link import ResourceLink
from runtime.resource import Resource
from runtime.runtime_priority import (
    DEFAULT_CYCLE_PRIORITY,
    DEFAULT_NICE,
    CycleScheduling,
    raise_priority,
)
from tests.conftest import free_port
from tests.runtime.test_modbus_server import SOURCE, listening_port, wait_for
from tests.support.runtime_process import running_resource, store_artifact, write_demo_artifact

SETTINGS = """[resource]
name = "Mb1"
target_cycle_ms = 10
target_cycle_mode = "fixed"
autostart = "cold"
safety_operation = false
"""


def test_the_priority_is_the_calling_threads_own() -> None:
    said: list[str] = []
    nice: list[int] = []
    own = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())

    def lower() -> None:  # a higher nice value needs no privilege
        said.append(raise_priority(5))
        nice.append(os.getpriority(os.PRIO_PROCESS, threading.get_native_id()))

    worker = threading.Thread(target=lower)
    worker.start()
    worker.join()
    assert said == ["nice 5"] and nice == [5]
    assert os.getpriority(os.PRIO_PROCESS, threading.get_native_id()) == own  # this one's not
    assert raise_priority(0) == "normal priority (nice 0)"


def test_every_thread_of_a_runtime_has_the_higher_priority_when_it_may(tmp_path: Path) -> None:
    write_demo_artifact(tmp_path)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with running_resource("Tank1", tmp_path, endpoint) as (process, client):
        client.wait_until_answering()
        threads = Path(f"/proc/{process.pid}/task")
        nice = {os.getpriority(os.PRIO_PROCESS, int(task.name)) for task in threads.iterdir()}
    may = os.geteuid() == 0  # CI runs as root; elsewhere CAP_SYS_NICE is rare
    assert nice == {DEFAULT_NICE if may else 0}  # the cycle, Zenoh's threads, the savers


def test_the_real_time_class_is_the_calling_threads_own_while_it_asks_for_it() -> None:
    said: list[str] = []
    policies: list[int] = []

    def cycle_thread() -> None:
        scheduling = CycleScheduling(3)
        said.append(scheduling.begin())
        policies.append(os.sched_getscheduler(0))
        scheduling.real_time()  # waiting for a cycle, and running it
        policies.append(os.sched_getscheduler(0) & ~os.SCHED_RESET_ON_FORK)
        started: list[int] = []
        starter = threading.Thread(target=lambda: started.append(os.sched_getscheduler(0)))
        starter.start()  # a thread it starts meanwhile is not real-time
        starter.join()
        scheduling.ordinary()  # keeping house
        policies.extend([*started, os.sched_getscheduler(0)])

    worker = threading.Thread(target=cycle_thread)
    worker.start()
    worker.join()
    if os.geteuid() == 0:  # CI runs as root
        assert said == ["SCHED_FIFO priority 3 for cycles at a fixed target"]
        assert policies == [os.SCHED_OTHER, os.SCHED_FIFO, os.SCHED_OTHER, os.SCHED_OTHER]
    else:
        assert said[0].startswith("normal scheduling: real-time priority 3 was refused")
        assert set(policies) == {os.SCHED_OTHER}
    assert os.sched_getscheduler(0) == os.SCHED_OTHER  # this thread's is not touched
    assert CycleScheduling(0).begin() == "normal scheduling (real-time priority 0)"


def test_no_thread_but_the_cycle_thread_of_a_runtime_runs_in_the_real_time_class(
    tmp_path: Path,
) -> None:
    write_demo_artifact(tmp_path)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with running_resource("Tank1", tmp_path, endpoint) as (process, client):
        client.wait_until_answering()
        client.ask(GetValues())  # answered on the files thread, started by the cycle thread
        tasks = [int(task.name) for task in Path(f"/proc/{process.pid}/task").iterdir()]
        policies = {t: os.sched_getscheduler(t) & ~os.SCHED_RESET_ON_FORK for t in tasks}
    # the cycle runs on the process's main thread, real-time while it waits for a cycle at
    # a fixed target; the threads it started, and the others, are ordinary
    others = {p for t, p in policies.items() if t != process.pid}
    assert others == {os.SCHED_OTHER}


def test_a_real_time_class_taken_away_later_leaves_the_cycle_thread_ordinary(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    scheduling = CycleScheduling(3)
    scheduling.begin()

    def refused(*args: object) -> None:
        raise PermissionError(1, "Operation not permitted")

    monkeypatch.setattr(os, "sched_setscheduler", refused)
    scheduling.real_time()  # never raises into the cycle loop
    scheduling.ordinary()
    assert scheduling.priority == 0


def test_a_modbus_thread_that_a_reload_starts_has_the_higher_priority_too(tmp_path: Path) -> None:
    """At a fixed target the cycle thread waits for its next cycle, and starts it, in the
    real-time class; a thread started from there would get the default nice value
    (SCHED_RESET_ON_FORK). The Modbus thread starts when a configuration first serves: here
    one that a reload brings, after one without located variables."""
    folder = tmp_path / "project"
    folder.mkdir()
    (folder / "padt.toml").write_text(SETTINGS)
    (folder / "main.st").write_text(
        "PROGRAM Main\nVAR n : INT; END_VAR\nn := n + 1;\nEND_PROGRAM\n"
    )
    plain = compile_project(load_project([folder])).artifact
    (folder / "main.st").write_text(SOURCE)  # located variables: served
    serving = compile_project(load_project([folder])).artifact
    assert plain is not None and serving is not None
    state = tmp_path / "state"
    store_artifact(state, plain)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    port = free_port()
    with running_resource("Mb1", state, endpoint, "--modbus-port", str(port)) as (process, client):
        threads = Path(f"/proc/{process.pid}/task")
        before = {task.name for task in threads.iterdir()}
        reload(client, serving, ReloadOptions({}))
        wait_for(lambda: listening_port(client) == port)
        started = {task.name for task in threads.iterdir()} - before
        nice = {os.getpriority(os.PRIO_PROCESS, int(task.name)) for task in threads.iterdir()}
    assert started  # the Modbus thread among them
    may = os.geteuid() == 0
    assert nice == {DEFAULT_NICE if may else 0}


@pytest.mark.skipif(os.geteuid() != 0, reason="the real-time class needs CAP_SYS_NICE")
def test_woken_for_its_next_cycle_the_cycle_thread_stays_real_time_into_it() -> None:
    """Dropping to the ordinary class just as the cycle was due handed the CPU to whatever
    else ran: with a busy loop per CPU beside the runtime, 14 to 19 periods in 2,500 were
    more than 1 ms late (make bench: bench_jitter_loaded)."""
    clock = RealClock()
    resource = Resource("R", clock)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with open_router(endpoint), contextlib.closing(open_client(endpoint)) as session:
        link = ResourceLink(session, resource.name, resource.identity)
        try:
            driver = CycleDriver(resource, clock, link, cycle_priority=DEFAULT_CYCLE_PRIORITY)
            policies: list[int] = []

            def wait_for_the_next_cycle() -> None:
                driver._scheduling.begin()
                due = clock.now_ns() + 20_000_000
                driver._housekeeping(due, threading.Event(), wait=True, paced=True)
                policies.append(os.sched_getscheduler(0) & ~os.SCHED_RESET_ON_FORK)
                driver._scheduling.ordinary()

            waiting = threading.Thread(target=wait_for_the_next_cycle)
            waiting.start()
            waiting.join()
        finally:
            link.close()
    assert policies == [os.SCHED_FIFO]
