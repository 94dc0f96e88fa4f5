"""The tests of a build run on one tier: one resource on a virtual clock, each test from fresh
instances at time 0 (docs/testing.md, "How a test runs").

The test methods are called here, between cycles; the test functions in them call back
through the `_test` intrinsic (`UnitTestFunctions`), which runs cycles, checks asserts and
forces. A failed assert raises `UnitTestFailure`, which ends the test."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from backend.engineering.replay import ReplayError, read_parts, store_recorded
from backend.engineering.simulation import sim_cycle_ms
from backend.engineering.testing.test_build import UnitTest
from runtime.clock import VirtualClock
from runtime.code.fault_location import locate
from runtime.code.instances import instances_of
from runtime.code.native.image_views import is_array, is_instance
from runtime.code.native.tier import NativeTier
from runtime.contract.artifact import Artifact
from runtime.contract.protocol import ProgramState, ResourceState
from runtime.contract.recording import Recording, RecordingUnreadable
from runtime.contract.refusal import Refusal
from runtime.contract.values import format_value
from runtime.force_table import GLOBAL, ForceEntry
from runtime.resource import Resource

NS_PER_MS = 1_000_000
# a test that runs longer than this is stopped: an endless RUN_UNTIL loop of the test's own
# making, or a RUN_CYCLES with a wrong count
MAX_CYCLES_PER_TEST = 1_000_000


@dataclass(frozen=True)
class Place:
    file: str
    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


class UnitTestFailure(Exception):
    """An assert that failed, or a test that cannot go on (a program faulted)."""

    def __init__(self, message: str, place: Place | None, detail: str = "") -> None:
        super().__init__(message)
        self.message, self.place, self.detail = message, place, detail


@dataclass(frozen=True)
class Outcome:
    """How one test ended on one tier."""

    status: str  # passed | failed | error
    message: str = ""
    place: Place | None = None
    detail: str = ""  # expected and actual
    cycles: int = 0


# (cycle number, every variable's value after it): the tiers compare through it
CycleWatcher = Callable[[int, dict[str, Any]], None]


class WatchStop(Exception):
    """Raised by a CycleWatcher to end the test; `UnitTestBench.run` lets it through."""


def same(a: Any, b: Any) -> bool:
    """ST equality of two values of one type: REALs by value (a NaN equals no value),
    arrays element by element, structures and blocks member by member; each held as a
    Python object or in the memory image (a view), as the test's own locals and the
    programs' variables may be."""
    if is_array(a) and is_array(b):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if is_instance(a) and is_instance(b) and type(a).__name__ == type(b).__name__:
        return all(same(getattr(a, s), getattr(b, s)) for s in type(a).__slots__)
    return bool(a == b)


def shown(value: Any, type_name: str) -> str:
    """A value as an ST literal, structures as `(a := 1, b := TRUE)`."""
    if is_instance(value):
        members = ", ".join(
            f"{s.removesuffix('__')} := {shown(getattr(value, s), '')}"
            for s in type(value).__slots__
        )
        return f"({members})"
    if is_array(value) and not isinstance(value, list):  # an array in the memory image
        value = list(value)
    if isinstance(value, float) and type_name.startswith("ANY"):
        type_name = "LREAL"
    return format_value(value, type_name)


@dataclass
class UnitTestFunctions:
    """The `_test` intrinsic of one resource: what the test functions of a test do."""

    resource: Resource
    clock: VirtualClock
    cycle_ns: int
    folder: Path | None = None  # the project's: where REPLAY finds recordings
    watch: CycleWatcher | None = None
    cycles: int = 0  # run by the current test
    until: int | None = None  # RUN_UNTIL's last cycle
    forced: set[str] = field(default_factory=set)

    def __call__(self, op: str, *args: Any) -> Any:
        if op == "count":
            return self.cycles
        *values, file, line, col = args
        place = Place(file, line, col)
        handler = getattr(self, f"_{op}")
        return handler(place, *values)

    # ---- asserts
    def _true(self, place: Place, condition: bool, message: str) -> None:
        if condition is not True:
            raise UnitTestFailure(
                _failed("ASSERT_TRUE", message), place, "expected TRUE, actual FALSE"
            )

    def _false(self, place: Place, condition: bool, message: str) -> None:
        if condition is not False:
            raise UnitTestFailure(
                _failed("ASSERT_FALSE", message), place, "expected FALSE, actual TRUE"
            )

    def _equal(
        self, place: Place, expected: Any, actual: Any, type_name: str, message: str
    ) -> None:
        if not same(expected, actual):
            detail = f"expected {shown(expected, type_name)}, actual {shown(actual, type_name)}"
            raise UnitTestFailure(_failed("ASSERT_EQUAL", message), place, detail)

    def _not_equal(
        self, place: Place, expected: Any, actual: Any, type_name: str, message: str
    ) -> None:
        if same(expected, actual):
            detail = f"expected anything but {shown(expected, type_name)}, actual the same"
            raise UnitTestFailure(_failed("ASSERT_NOT_EQUAL", message), place, detail)

    def _near(
        self,
        place: Place,
        expected: float,
        actual: float,
        tolerance: float,
        type_name: str,
        message: str,
    ) -> None:
        if not abs(expected - actual) <= tolerance:  # NaN: never near
            detail = (
                f"expected {shown(expected, type_name)} within {shown(tolerance, type_name)}, "
                f"actual {shown(actual, type_name)}"
            )
            raise UnitTestFailure(_failed("ASSERT_NEAR", message), place, detail)

    def _fail(self, place: Place, message: str) -> None:
        raise UnitTestFailure(_failed("FAIL", message), place)

    # ---- cycles on virtual time
    def _cycles(self, place: Place, count: int) -> None:
        if count < 0:
            raise UnitTestFailure(f"RUN_CYCLES({count}): the count must not be negative", place)
        for _ in range(count):
            self.cycle(place)

    def _for(self, place: Place, duration_ns: int) -> None:
        if duration_ns < 0:
            raise UnitTestFailure("RUN_FOR: the time must not be negative", place)
        self._cycles(place, math.ceil(duration_ns / self.cycle_ns))

    def _until(self, place: Place, duration_ns: int) -> None:
        self.until = self.cycles + max(0, math.ceil(duration_ns / self.cycle_ns))

    def _step(self, place: Place) -> None:
        if self.until is None or self.cycles >= self.until:
            limit = format_value((self.until or 0) * self.cycle_ns, "TIME")
            raise UnitTestFailure(f"RUN_UNTIL: the condition was not TRUE within {limit}", place)
        self.cycle(place)

    # ---- a recording's inputs
    def _replay(self, place: Place, name: str) -> None:
        """Every cycle of a recording made with all inputs, each with what it took from
        outside, at the recorded times (one cycle time apart at least)."""
        recording = self._recording(place, name)
        clock, start = self.clock, self.clock.now_ns()
        first = recording.inputs[0].begin_ns if recording.inputs else 0
        for item in recording.inputs:
            clock.sleep_until(start + item.begin_ns - first)
            store_recorded(self.resource, item.before)
            self.cycle(place)
            store_recorded(self.resource, item.after)

    def _recording(self, place: Place, name: str) -> Recording:
        folder = self.folder
        if folder is None:
            raise UnitTestFailure("REPLAY: these tests have no project folder", place)
        path = (folder / name).resolve()
        if not path.is_relative_to(folder.resolve()) or not path.is_file():
            raise UnitTestFailure(f"REPLAY: no recording {name!r} in the project folder", place)
        try:
            recording = read_parts(path)
        except (RecordingUnreadable, ReplayError) as exc:
            raise UnitTestFailure(f"REPLAY: {name}: {exc}", place) from None
        if not recording.header.all_inputs:
            message = f"REPLAY: {name} holds no inputs: record with --all-inputs"
            raise UnitTestFailure(message, place)
        return recording

    def cycle(self, place: Place) -> None:
        """One CPU cycle, then virtual time moves on by one cycle time."""
        if self.cycles >= MAX_CYCLES_PER_TEST:
            raise UnitTestFailure(f"the test ran {MAX_CYCLES_PER_TEST} cycles: stopped", place)
        resource = self.resource
        resource.cycle()
        self.cycles += 1
        self.clock.advance(self.cycle_ns)
        between_cycles(resource)
        if self.watch is not None:
            self.watch(self.cycles, resource.variables.values())
        if resource.state == ResourceState.ERROR_STOP:
            raise UnitTestFailure(f"cycle {self.cycles}: ERROR STOP, {resource.error}", place)
        for program in resource.programs:
            if program.state == ProgramState.ERROR:
                message = f"cycle {self.cycles}: program {program.config.name} faulted"
                raise UnitTestFailure(message, place, program.error or "")

    # ---- forcing (the project's forcing permissions are for the controller, not tests)
    def _force(self, place: Place, path: str, value: Any) -> None:
        variables = self.resource.variables
        bound = variables.find(path)
        if bound is None:
            raise UnitTestFailure(f"FORCE: no variable {path}", place)
        level = GLOBAL if bound.program is None else bound.program.name
        table = self.resource.forcing.table
        table.set(ForceEntry(bound.path.path, level, variables.checked(bound, value), True))
        table.start(level, self.clock.now_ns(), None)
        self.forced.add(bound.path.path)
        self.resource.forcing.apply()

    def _release(self, place: Place, path: str) -> None:
        bound = self.resource.variables.find(path)
        if bound is None or self.resource.forcing.table.remove(bound.path.path) is None:
            raise UnitTestFailure(f"RELEASE: {path} is not forced", place)


def between_cycles(resource: Resource) -> None:
    """What the test's code sees between cycles: the globals all programs share (not the
    view of the program that ran last) and the clock's time (`TIME()`, a timer of the
    suite), as online test sees them."""
    code = resource.variables.code
    assert code is not None
    code.use(resource.variables.globals, None)
    resource.system.now_ns = resource.clock.now_ns()


def _failed(function: str, message: str) -> str:
    return f"{function} failed: {message}" if message else f"{function} failed"


class UnitTestBench:
    """A resource for the tests of one build on one tier."""

    def __init__(
        self, artifact: Artifact, native: NativeTier | None, folder: Path | None = None
    ) -> None:
        self.clock = VirtualClock()
        self.resource = Resource(artifact.resource.name, self.clock)
        self.resource.native = native
        self.resource.load(artifact)
        if native is not None:
            self.resource.tier_up(wait=True)
        code = self.resource.variables.code
        assert code is not None
        self.image = code
        self.functions = UnitTestFunctions(
            self.resource, self.clock, sim_cycle_ms(artifact) * NS_PER_MS, folder
        )
        self.image.run_tests_with(self.functions)

    @property
    def native_bodies(self) -> tuple[str, ...]:
        report = self.image.native
        return report.bodies if report is not None else ()

    def run(self, case: UnitTest, watch: CycleWatcher | None = None) -> Outcome:
        functions = self.functions
        if case.problem:
            return Outcome("error", case.problem, Place(case.file, case.line, 1))
        self._fresh()
        functions.watch, functions.cycles, functions.until = watch, 0, None
        suite = self.image.new_instance(case.suite)
        try:
            try:
                if case.setup is not None:
                    getattr(suite, case.setup)()
                arguments = []
                if case.cases is not None and case.case is not None:
                    elements = getattr(suite, case.cases)
                    arguments.append(elements[case.case - case.first])
                getattr(suite, case.method)(*arguments)
            finally:
                if case.teardown is not None:
                    getattr(suite, case.teardown)()
        except WatchStop:
            raise
        except UnitTestFailure as failure:
            return Outcome(
                "failed", failure.message, failure.place, failure.detail, functions.cycles
            )
        except Refusal as refused:
            return Outcome("error", f"refused: {refused.message}", None, "", functions.cycles)
        except Exception as exc:  # a fault of the test's own code (a division by zero)
            where = locate(exc, self.image.units)
            place = Place(where.file, where.line, 0) if where is not None else None
            message = f"{type(exc).__name__}: {exc}"
            return Outcome("error", message, place, "", functions.cycles)
        return Outcome("passed", cycles=functions.cycles)

    def _fresh(self) -> None:
        """Every variable at its initial value, time 0, no forcing, the resource in RUN."""
        resource = self.resource
        if resource.running():
            resource.stop("test start")
        resource.forcing.reset()
        self.image.renew()
        resource.variables.adopt(instances_of(self.image))
        resource.tier_up()  # the fresh values into the memory image, as the runtime has them
        self.clock.rewind()
        resource.start()
        between_cycles(resource)
