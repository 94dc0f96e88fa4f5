"""The runtime asks for a higher priority than the PADT and browsers beside it, for every
thread it has."""

from __future__ import annotations

import os
import threading
from pathlib import Path

from runtime.runtime_priority import DEFAULT_NICE, raise_priority
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
