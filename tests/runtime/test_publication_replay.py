"""A resource's signed publications put again later by someone else (a replay) are not
taken for news: not by a client of the resource (status, events), not by the REST API's
list of resources, and not after the runtime restarted (a new boot is news, the old one
replayed is not). A real router, real runtime processes; the rogue is a Zenoh session of
the test that captures what the resource published and puts it again."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable
from pathlib import Path

import zenoh

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.resource_client import ResourceClient
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import ProgramConfig, ResourceConfig, UserAccount
from runtime.contract.keyspace import events_key, status_key
from runtime.contract.protocol import Event, GetStatus, ResetStats, Status
from runtime.contract.wire import decode
from tests.conftest import free_port
from tests.runtime.test_hostile_clients import PASSWORD, RESOURCE, SOURCE, TARGET_MS, target
from tests.support.rest_plant import plant
from tests.support.runtime_process import (
    client_session,
    router,
    runtime_process,
    store_artifact,
)

Captured = list[tuple[bytes, bytes | None]]


def capture(session: zenoh.Session, key: str) -> tuple[Captured, zenoh.Subscriber[None]]:
    """Everything put on `key` from now on, with its attachment, as a listener has it."""
    got: Captured = []

    def keep(sample: zenoh.Sample) -> None:
        attachment = sample.attachment.to_bytes() if sample.attachment is not None else None
        got.append((sample.payload.to_bytes(), attachment))

    return got, session.declare_subscriber(key, keep)


def wait_for(condition: Callable[[], bool], what: str, timeout_s: float = 20) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, what
        time.sleep(0.05)


def replay(session: zenoh.Session, key: str, message: tuple[bytes, bytes | None]) -> None:
    for _ in range(20):
        session.put(key, message[0], attachment=message[1])
        time.sleep(0.02)


def status_of(payload: bytes) -> Status:
    return decode(Status, json.loads(payload))


def test_a_replayed_status_or_event_is_not_taken(tmp_path: Path, zenoh_endpoint: str) -> None:
    with target(tmp_path, zenoh_endpoint) as client, client_session(zenoh_endpoint) as rogue:
        statuses, status_listener = capture(rogue, status_key(RESOURCE))
        events, event_listener = capture(rogue, events_key(RESOURCE))
        seen: list[Status] = []
        delivered: list[Event] = []
        client.on_status(seen.append)
        client.on_events(delivered.append)
        admin = ResourceClient(client.session, RESOURCE)
        admin.login("admin", PASSWORD)
        admin.ask(ResetStats())  # an event
        wait_for(lambda: bool(events) and bool(delivered), "the event is published")
        wait_for(lambda: len(statuses) >= 2, "statuses are published")
        old = statuses[-1]
        old_cycle = status_of(old[0]).cycle
        wait_for(lambda: bool(seen) and seen[-1].cycle > old_cycle, "a newer status arrives")
        seen.clear()
        replay(rogue, status_key(RESOURCE), old)
        replay(rogue, events_key(RESOURCE), events[-1])
        wait_for(lambda: len(seen) >= 2, "the resource's statuses still arrive")
        assert all(status.cycle > old_cycle for status in seen), [s.cycle for s in seen]
        numbers = [event.seq for event in delivered]
        assert len(numbers) == len(set(numbers)), f"an event was delivered twice: {numbers}"
        status_listener.undeclare()
        event_listener.undeclare()


def test_a_new_boot_is_news_and_the_old_one_replayed_is_not(tmp_path: Path) -> None:
    config = ResourceConfig(RESOURCE, target_cycle_ms=TARGET_MS, autostart="cold")
    users = [UserAccount("admin", "administrator", hash_password(PASSWORD))]
    result = compile_sources(
        [SourceFile("main.st", SOURCE)],
        resource=config,
        programs=[ProgramConfig("Main", "Main", 1)],
        users=users,
    )
    assert result.artifact is not None
    store_artifact(tmp_path, result.artifact)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with router(endpoint), client_session(endpoint) as session, client_session(endpoint) as rogue:
        client = ResourceClient(session, RESOURCE)
        seen: list[Status] = []
        lock = threading.Lock()

        def keep(status: Status) -> None:
            with lock:
                seen.append(status)

        statuses, listener = capture(rogue, status_key(RESOURCE))
        with runtime_process(RESOURCE, tmp_path, endpoint):
            client.wait_until_answering()
            client.login("admin", PASSWORD)
            client.use_credentials("admin", PASSWORD)
            client.on_status(keep)
            wait_for(lambda: len(statuses) >= 2 and bool(seen), "statuses of the first boot")
        first_boot = statuses[-1]
        with runtime_process(RESOURCE, tmp_path, endpoint):
            client.wait_until_answering()
            client.ask(GetStatus())  # logs in again: the session ended with the process
            before = len(seen)
            wait_for(lambda: len(seen) > before + 1, "statuses of the second boot are taken")
            with lock:
                seen.clear()
            replay(rogue, status_key(RESOURCE), first_boot)
            wait_for(lambda: len(seen) >= 2, "statuses of the second boot still arrive")
            # the first boot's last status had cycles the second boot has not yet counted
            first = status_of(first_boot[0])
            assert all(status != first for status in seen)
        listener.undeclare()


def test_the_rest_api_lists_no_replayed_status(tmp_path: Path) -> None:
    with plant(tmp_path) as site, client_session(site.endpoint) as rogue:
        token = site.session("reader", "viewer")  # a login to Plant: its key is trusted
        statuses, listener = capture(rogue, status_key("Plant"))

        def shown() -> int | None:
            listed = site.call("GET", "/api/resources", token).json()
            status = next(r["status"] for r in listed if r["resource"] == "Plant")
            return int(status["cycle"]) if status is not None else None

        wait_for(lambda: len(statuses) >= 2, "statuses are published")
        old = statuses[-1]
        old_cycle = status_of(old[0]).cycle
        wait_for(lambda: (shown() or 0) > old_cycle, "a newer status is listed")
        putting = threading.Thread(target=replay, args=(rogue, status_key("Plant"), old))
        putting.start()
        cycles = []
        for _ in range(20):
            cycles.append(shown())
            time.sleep(0.02)
        putting.join()
        assert old_cycle not in cycles, cycles
        listener.undeclare()
