"""Drives a resource in real time: a CPU cycle, then housekeeping (commands, publishing,
context saving) until the next cycle is due. In STOP the loop goes on: it still serves
communication.

When the next cycle starts depends on the target cycle time and its mode: `fixed` and
`fixed-tolerant` stretch short cycles to the target, and the time up to the next cycle is
free for commands; `dynamic` and `dynamic-tolerant` (and a target of 0) start the next
cycle as soon as the commands already waiting are answered, spending at most the
communication time slice on them.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import queue
import sys
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import zenoh

from runtime.clock import Clock
from runtime.collector import COLLECTOR
from runtime.commands import (
    LATER_HANDLERS,
    answer,
    authorize,
    begin_reload,
    finish_reload,
    internal_failure,
    respond,
)
from runtime.contract.protocol import (
    IoStatus,
    Reload,
    ReloadPreview,
    Request,
    Status,
    encode_refusal,
    encode_reply,
)
from runtime.contract.refusal import Refusal
from runtime.cycle_stats import CycleStats
from runtime.disposal import DISPOSAL
from runtime.link import ResourceLink
from runtime.reload_switch import ReloadJob
from runtime.request_intake import Received
from runtime.resource import Resource
from runtime.runtime_priority import CycleScheduling

log = logging.getLogger(__name__)

STATUS_PERIOD_NS = 1_000_000_000
SWITCH_INTERVAL_S = 0.0005
_UNCOUNTED = CycleStats().info()  # statistics and cycle count alone are no change
# how long a watch set may wait for its client's liveliness token to show
WATCHER_GRACE_NS = 2_000_000_000


class CycleDriver:
    def __init__(
        self,
        resource: Resource,
        clock: Clock,
        link: ResourceLink,
        save_context: Callable[[], None] | None = None,
        context_period_ns: int = 1_000_000_000,
        cycle_priority: int = 0,
    ) -> None:
        self.resource = resource
        self._scheduling = CycleScheduling(cycle_priority)
        self.clock = clock
        self.link = link
        self._save_context = save_context
        self._context_period_ns = context_period_ns
        self._last_context_ns = clock.now_ns()
        self._last_status: Status | None = None
        self._last_status_ns = 0
        self._reload: tuple[zenoh.Query, ReloadJob, threading.Thread] | None = None
        self._unplanned: set[str] = set()  # watch sets not sent: their plan was not made
        # reads files for the commands that need them (LATER_HANDLERS), off the cycle
        self._files = ThreadPoolExecutor(1, thread_name_prefix="padt-files")
        # events before the driver started (power-up: warm or cold start) go out too
        self._events_sent = 0

    def run(self, stop: threading.Event) -> None:
        # the cycle thread must get the interpreter back promptly after its wait for the
        # next cycle, not up to 5 ms (Python's default) later while another thread has it
        sys.setswitchinterval(SWITCH_INTERVAL_S)
        if self._scheduling.priority:
            log.info("cycle thread: %s", self._scheduling.begin())
        DISPOSAL.deferred = True  # what a reload replaces is freed in slices (_after_cycle)
        try:
            self._cycles(stop)
        finally:
            self._scheduling.ordinary()  # stopped while waiting for a cycle: shut down ordinary
            DISPOSAL.let_go_at_once()

    def _cycles(self, stop: threading.Event) -> None:
        planned = self.clock.now_ns()
        paced = False  # the cycle was waited for (a fixed target): real-time through it
        while not stop.is_set():
            start = self.clock.now_ns()
            cycle_before = self.resource.cycle_count
            field_io = self.resource.field_io
            try:
                if field_io is not None:
                    field_io.before_cycle()
                if paced:  # two system calls (4 us): only where a wait came before
                    self._scheduling.real_time()
                try:
                    self.resource.cycle()
                finally:
                    self._scheduling.ordinary()
                if field_io is not None:
                    field_io.after_cycle()
            except Exception as exc:  # a defect of the runtime itself, never of a program
                log.exception("internal fault")
                self.resource.error_stop(f"internal fault: {type(exc).__name__}: {exc}")
            cycled = self.resource.cycle_count != cycle_before
            self._safely(functools.partial(self._after_cycle, cycled))
            params = self.resource.params
            running = self.resource.running()
            com_slice = params.com_slice_ms * 1_000_000
            target = params.target_cycle_ms * 1_000_000
            paced = bool(running and target and params.target_cycle_mode.startswith("fixed"))
            if paced:
                planned += target
                if planned < start:  # an overrun: start afresh instead of racing to catch up
                    planned = start + target
                # the time up to the next cycle is free for communication
                self._housekeeping(planned, stop, wait=True, paced=True)
                self.clock.sleep_until(planned)
            elif running:  # only what is waiting, for at most the com slice
                self._housekeeping(self.clock.now_ns() + com_slice, stop)
                time.sleep(0)  # let the Zenoh threads deliver
                planned = self.clock.now_ns()
            else:  # STOP: nothing to run; wait for commands, read inputs now and then
                self._housekeeping(self.clock.now_ns() + com_slice, stop, wait=True)
                planned = self.clock.now_ns()

    def _after_cycle(self, cycled: bool) -> None:
        COLLECTOR.between_cycles(self.resource.running())
        if cycled:
            self._publish_values()
        elif self._unplanned:  # in STOP: what a command left waiting for its reading plan
            self._publish_values(at_once=True, only=self._unplanned)
        self._publish_status()
        self._finish_reload()  # between two cycles
        self.resource.tier_up()
        self._follow_field_io()
        DISPOSAL.step()
        self._save_if_due()

    def _follow_field_io(self) -> None:
        """After what may have changed the configuration (a reload, a command), in the
        ordinary class: the field I/O thread it starts gets the runtime's nice value, where one
        started from the real-time class would get the default (SCHED_RESET_ON_FORK)."""
        if self.resource.field_io is not None:
            self.resource.field_io.follow_configuration()

    @staticmethod
    def _safely(work: Callable[[], None]) -> None:
        """Housekeeping that meets a defect of the runtime logs it; the cycles go on."""
        try:
            work()
        except Exception:
            log.exception("internal fault in housekeeping")

    def close(self) -> None:
        """An orderly shutdown saves the context one last time."""
        self._files.shutdown(wait=True, cancel_futures=True)
        if self._save_context is not None:
            self._save_context()

    def _save_if_due(self) -> None:
        now = self.clock.now_ns()
        if (
            self._save_context is not None
            and now - self._last_context_ns >= self._context_period_ns
        ):
            self._save_context()
            self._last_context_ns = now

    def _housekeeping(
        self, deadline_ns: int, stop: threading.Event, wait: bool = False, paced: bool = False
    ) -> None:
        """Answer commands until the deadline; without `wait`, only those already queued.
        `paced`: the deadline is the next cycle's, waited for in the real-time class."""
        while not stop.is_set():
            remaining = deadline_ns - self.clock.now_ns()
            try:
                if remaining > 0 and wait:  # woken by a command, or for the next cycle
                    if paced:
                        self._scheduling.real_time()
                    received = self.link.intake.inbox.get(timeout=min(remaining / 1e9, 0.2))
                else:
                    received = self.link.intake.inbox.get_nowait()
            except queue.Empty:
                # woken for the next cycle: real-time on into it, or the hand-over to the
                # ordinary class gave other threads the CPU just when the cycle was due
                if remaining <= 0 or not wait:
                    return
                continue
            self.link.intake.done()
            self._scheduling.ordinary()  # a command is answered in the ordinary class
            reply = self._answer(received)
            if reply is not None:
                self.link.reply(received.query, reply)
            del received  # a Zenoh query is finalised when its last reference goes
            # a command may have stepped, stopped or written: show its outcome at once
            self._safely(self._publish_after_command)
            if self.clock.now_ns() >= deadline_ns:
                return

    def _publish_after_command(self) -> None:
        self._follow_field_io()
        self._publish_values(at_once=True)
        self._publish_status()

    def _answer(self, received: Received) -> bytes | None:
        """The reply to a request (decoded and checked whole by the link's intake, off this
        thread); None when it is a reload that answers later."""
        query, request = received.query, received.decoded
        if isinstance(request, Exception):  # what the decoder met: a defect of the runtime
            return encode_refusal(internal_failure(self.resource, request))
        try:
            if isinstance(request.command, Reload | ReloadPreview):
                self._start_reload(query, request)
                return None
            later = LATER_HANDLERS.get(type(request.command))
            if later is not None:
                authorize(self.resource, request)
                work = later(self.resource, request.command)
                self._files.submit(self._reply_later, query, work)
                return None
        except Refusal as refusal:
            return encode_refusal(refusal)
        except Exception as exc:
            return encode_refusal(internal_failure(self.resource, exc))
        return respond(self.resource, lambda: answer(self.resource, request))

    def _reply_later(self, query: zenoh.Query, work: Callable[[], Any]) -> None:
        """On the files thread: the reply of a command that reads files."""
        try:
            reply = encode_reply(work())
        except Refusal as refusal:
            reply = encode_refusal(refusal)
        except Exception as exc:  # a defect: logged; the event log is the cycle thread's
            log.exception("internal error while reading files for a command")
            reply = encode_refusal(Refusal("internal", f"internal error ({type(exc).__name__})"))
        self.link.reply(query, reply)

    def _start_reload(self, query: zenoh.Query, request: Request) -> None:
        """A reload (or its preview) prepares on a worker thread while cycles go on
        (compiling the new code and planning take far longer than a cycle); its query is
        answered when the switch-over between two cycles is done (`_finish_reload`)."""
        if self._reload is not None:
            raise Refusal("busy", "a reload is already under way")
        authorize(self.resource, request)
        assert isinstance(request.command, Reload | ReloadPreview)
        job = begin_reload(self.resource, request.command)
        worker = threading.Thread(target=job.prepare, name="padt-reload", daemon=True)
        worker.start()
        self._reload = (query, job, worker)

    def _finish_reload(self) -> None:
        if self._reload is None or self._reload[2].is_alive():
            return
        query, job, _ = self._reload
        self._reload = None
        self.link.reply(query, respond(self.resource, lambda: finish_reload(self.resource, job)))
        del query
        self._publish_after_command()

    def _publish_values(self, at_once: bool = False, only: set[str] | None = None) -> None:
        """The watch sets whose period has passed (all of them after a command, which may
        have stepped, stopped or written; `only` those named), read within the
        communication time slice: the sets that do not fit wait for the next cycle, and
        are counted. A set whose reading plan is still being made (on the files thread)
        waits for it. Sets whose session ended, or whose client holds no liveliness token
        for them, are dropped first."""
        resource, now = self.resource, self.clock.now_ns()
        watches, access, watchers = resource.online.watches, resource.access, self.link.watchers
        watches.drop_where(
            lambda s: (
                (s.owner is not None and not access.valid(s.owner))
                or (s.watch_id not in watchers and now - s.registered_ns > WATCHER_GRACE_NS)
            )
        )
        self.link.follow_watchers(watches.every_id())
        running, forces = resource.running(), resource.forcing.table
        bad = resource.field_io.bad if resource.field_io is not None else frozenset()
        budget_end = now + resource.params.com_slice_ms * 1_000_000
        due = watches.due(now, all_of_them=at_once)
        if only is not None:
            due = [s for s in due if s.watch_id in only]
        self._unplanned = set()
        for number, watch_set in enumerate(due):
            if number > 0 and self.clock.now_ns() >= budget_end:
                resource.stats.watch_deferred += len(due) - number
                return
            if not resource.online.planned(watch_set, self._files.submit):
                self._unplanned.add(watch_set.watch_id)  # sent once its plan is made
                continue
            snapshot = resource.online.snapshot(
                watch_set, resource.cycle_count, running, forces, bad
            )
            self.link.publish_watch(watch_set.watch_id, snapshot)
            watches.sent(watch_set, now)

    def _publish_events(self) -> None:
        """What the event log got since the last time, in order."""
        for event in self.resource.events.recent(self._events_sent):
            self.link.publish_event(event)
            self._events_sent = event.seq

    def _publish_status(self) -> None:
        """Publish on change (cycle statistics aside) and at least every second; the
        events that led to a change go first."""
        self._publish_events()
        status = self.resource.status()
        significant = dataclasses.replace(status, stats=_UNCOUNTED, cycle=0, io=_uncounted(status))
        now = self.clock.now_ns()
        if significant != self._last_status or now - self._last_status_ns >= STATUS_PERIOD_NS:
            self.link.publish_status(status)
            self._last_status = significant
            self._last_status_ns = now


def _uncounted(status: Status) -> IoStatus | None:
    """The I/O status without its counters: a request more is no change to publish."""
    io = status.io
    if io is None:
        return None
    server = io.server and dataclasses.replace(io.server, requests=0, exceptions=0, writes=0)
    devices = [
        dataclasses.replace(d, requests=0, failures=0, round_trip_ms=0.0) for d in io.devices
    ]
    return IoStatus(server, devices)
