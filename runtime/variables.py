"""The variables of the loaded configuration: the program and global instances, and every
elementary variable by its path (`Program.fb.var`, globals by their bare name), to look up,
read, check against its type and store wherever its readers see it."""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

from runtime.code.code_image import CodeImage
from runtime.code.instances import (
    BoundVariable,
    Instances,
    index,
    name_reference_roots,
    output_points,
)
from runtime.code.native.image_plan import ImagePlan
from runtime.code.user_program import UserProgram
from runtime.collector import COLLECTOR
from runtime.contract.artifact import AccessPath
from runtime.contract.protocol import VariableInfo
from runtime.contract.refusal import Refusal
from runtime.contract.values import ValueRejected, representation
from runtime.memory import Memory, ObjectMemory


class Variables:
    # slots: the CPU cycle in C reads them at their offsets (padt_cycle.c)
    __slots__ = (
        "_all_of",
        "_all_paths",
        "_by_name",
        "_read_all",
        "_resource",
        "access",
        "bound",
        "code",
        "globals",
        "image",
        "image_held",
        "memory",
        "outputs",
        "programs",
        "tap",
    )

    def __init__(self, resource: str) -> None:
        self._resource = resource
        self.code: CodeImage | None = None
        self.programs: list[UserProgram] = []  # by priority, then Program ID
        self.globals: Any = None  # the globals as all programs see them between cycles
        self.memory: Memory = ObjectMemory(None, [])  # where the variables' values are
        # the plan of the memory image the values are in (runtime/image_switch.py; its
        # bytes are `memory`'s); None: they are on the objects
        self.image: ImagePlan | None = None
        # while a reload job plans against the objects, the values stay there (the job)
        self.image_held: Callable[[], object] | None = None
        self.bound: list[BoundVariable] = []
        self._by_name: dict[str, BoundVariable] = {}
        # the configuration's VAR_ACCESS by upper-case name: more names for variables
        self.access: dict[str, AccessPath] = {}
        self.outputs: list[BoundVariable] = []  # the output points
        # while an all-inputs recording runs: every store from outside the programs, in order
        self.tap: list[tuple[str, Any]] | None = None
        # `values()`: a reader of every variable, for the configuration it was made for
        self._all_of: list[BoundVariable] | None = None
        self._read_all: Callable[[], list[Any]] = list
        self._all_paths: list[str] = []

    def adopt(self, instances: Instances) -> None:
        self.outputs = instances.outputs
        self.code, self.programs, self.globals = (
            instances.image,
            instances.programs,
            instances.globals,
        )
        self.memory = ObjectMemory(self.globals, self.programs)
        self.image = None
        # `bound` last: a reading plan made on another thread (online_values.py) takes it
        # first, and counts as current only while it is the same, so the lookups it made
        # after it cannot be those of the configuration before
        self._by_name = instances.by_name
        self.bound = instances.bound
        name_reference_roots(self.code, self.programs)
        COLLECTOR.arrived()  # out of the collector's sight

    def instances(self) -> Instances:
        """What is loaded now (a reload plans against it; the program list is a copy, as a
        restart replaces a program)."""
        assert self.code is not None
        return Instances(
            self.code, list(self.programs), self.globals, self.bound, self._by_name, self.outputs
        )

    def replace_program(self, old: UserProgram, new: UserProgram) -> None:
        """A program restarted from fresh instances (it leaves ERROR by a start)."""
        self.programs[self.programs.index(old)] = new
        self.memory = ObjectMemory(self.globals, self.programs)
        self.bound = [BoundVariable(new, b.path) if b.program is old else b for b in self.bound]
        self._by_name = index(self.bound)
        if self.code is not None:
            name_reference_roots(self.code, self.programs)
        self.outputs = output_points(self.bound)

    def program(self, name: str) -> UserProgram:
        for program in self.programs:
            if program.name.upper() == name.upper():
                return program
        raise Refusal("unknown_program", f"resource {self._resource} has no program '{name}'")

    def find(self, path: str) -> BoundVariable | None:
        return self._by_name.get(path.upper())  # ST names are case-insensitive

    def lookup(self, name: str) -> BoundVariable:
        """A variable by its path or by an access path (VAR_ACCESS) that names it."""
        bound = self.find(name)
        if bound is None and name.upper() in self.access:
            bound = self.find(self.access[name.upper()].path)
        if bound is None:
            raise Refusal("unknown_variable", f"resource {self._resource} has no variable '{name}'")
        return bound

    def lookup_to_write(self, name: str) -> BoundVariable:
        """`lookup`, refusing an access path that is READ_ONLY."""
        access = self.access.get(name.upper())
        if self.find(name) is None and access is not None and not access.writable:
            raise Refusal("read_only", f"access path '{access.name}' is READ_ONLY")
        return self.lookup(name)

    def value(self, name: str) -> Any:
        """The value of one variable, as `values()` has it."""
        return self.read(self.lookup(name))

    def read(self, bound: BoundVariable) -> Any:
        return self.memory.read(bound)

    def store(self, bound: BoundVariable, value: Any) -> None:
        """Write a variable where every reader sees it: a global into the globals and into
        every program's view of them."""
        if self.tap is not None:
            kept = copy.deepcopy(value) if isinstance(value, list) else value
            self.tap.append((bound.path.path, kept))
        self.memory.store(bound, value)

    def checked(self, bound: BoundVariable, value: Any) -> Any:
        """`value` as the variable holds it; Refusal when it cannot hold it."""
        if bound.path.constant:
            raise Refusal("constant", f"'{bound.path.path}' is a constant")
        try:
            return representation(bound.path.type, value)
        except ValueRejected as exc:
            raise Refusal("bad_value", f"'{bound.path.path}': {exc}") from None

    def tapped(self) -> list[tuple[str, Any]]:
        """The stores from outside since the last call (none when not tapped)."""
        if self.tap is None:
            return []
        taken, self.tap = self.tap, []
        return taken

    def values(self) -> dict[str, Any]:
        """Every elementary variable: `Program.var`, `Program.fb.var`, globals by their bare
        name; struct and FB members with dots; arrays of elementary values as lists."""
        return self.read_values()()

    def read_values(self) -> Callable[[], dict[str, Any]]:
        """Every elementary variable's value, read now (between two cycles); the function
        returned makes them the dict `values` gives on whatever thread calls it. With
        100,000 variables the dict costs four times the reading."""
        bound = self.bound
        if self._all_of is not bound:  # read through one reader, made once per configuration
            self._all_of = bound
            self._read_all = self.memory.reader(bound)
            self._all_paths = [b.path.path for b in bound]
        paths, got = self._all_paths, self._read_all()

        def by_path() -> dict[str, Any]:
            # a batch per C call: one call over 100,000 entries holds the GIL for 15 ms
            values: dict[str, Any] = {}
            for n in range(0, len(paths), 5_000):
                values.update(zip(paths[n : n + 5_000], got[n : n + 5_000], strict=True))
            return values

        return by_path

    def infos(self) -> list[VariableInfo]:
        return [VariableInfo(bound.path.path, bound.path.type) for bound in self.bound]

    def publish(self, finished: list[UserProgram]) -> None:
        """The writes of programs whose program cycle ended become visible to the others
        (in their next program cycle: one CPU cycle later at the earliest)."""
        master = self.globals
        for program in finished:
            if program.view is not master:  # a test here, not a call: every CPU cycle
                program.publish(master)
