"""The runtime asks for a higher priority than the PADT and browsers beside it, for every
thread it has, and for its cycle thread the real-time class."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import pytest

from runtime.contract.protocol import GetValues
from runtime.runtime_priority import DEFAULT_NICE, CycleScheduling, raise_priority
from tests.conftest import free_port
from tests.support.runtime_process import running_resource, write_demo_artifact


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
