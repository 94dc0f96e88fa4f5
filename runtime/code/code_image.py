"""Executable form of an artifact: its generated source run into one namespace per resource,
plus the flat variable paths used for OLT values."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from types import CodeType
from typing import Any

from runtime.code.code_warmup import unspecialized, warm_up
from runtime.code.compile_worker import compile_here
from runtime.code.fault_location import SourceLocation, code_filename, locate
from runtime.code.intrinsics import Namespace, SystemView, namespace
from runtime.code.native.image_plan import ImagePlan
from runtime.code.native.tier import NativeJob, NativeReport, NativeTier
from runtime.contract.artifact import Artifact, PouCode, VarInfo
from runtime.contract.generated_code import check_artifact_names
from runtime.contract.values import array_shape

# An attribute name, or an offset into the flat list that holds an array.
Accessor = str | int


@dataclass(frozen=True)
class VariablePath:
    path: str  # e.g. "TankControl.refillDelay.ET", "gPoints[2].x"
    attrs: tuple[Accessor, ...]  # attribute chain (and list offsets) below the owner instance
    type: str
    constant: bool = False
    location: str | None = None  # `%QX0.1`: a located variable (a process-image point)


def reusing(
    previous: CodeImage, compile_units: Callable[[list[tuple[str, str]]], list[CodeType]]
) -> Callable[[list[tuple[str, str]]], list[CodeType]]:
    """`compile_units` for the units a reload changed; the others take copies of the code
    objects of the running image, never run and warmed up (`runtime/code/code_warmup.py`): the
    compile saved, and none of the old code's specializations, which were made for the
    classes the reload replaces."""

    def compile_changed(units: list[tuple[str, str]]) -> list[CodeType]:
        kept = [previous.code_of(*unit) for unit in units]
        changed = [unit for unit, code in zip(units, kept, strict=True) if code is None]
        compiled = iter(compile_units(changed) if changed else [])
        copies = [unspecialized(code) for code in kept if code is not None]
        warm_up(copies)
        copied = iter(copies)
        return [next(compiled) if code is None else next(copied) for code in kept]

    return compile_changed


class CodeImage:
    """The loaded code of one configuration; instances are created from it."""

    def __init__(
        self,
        artifact: Artifact,
        system: SystemView,
        printf: Callable[..., int] | None = None,
        compile_units: Callable[[list[tuple[str, str]]], list[CodeType]] = compile_here,
        native: NativeTier | None = None,
        memory_image: bool = False,
    ) -> None:
        """`compile_units`: how the generated source becomes code (a reload prepared
        while cycles run passes the compile worker's); `native`: the tier that binds C
        bodies to the classes, where it can; `memory_image`: its C works on a memory image
        a resource moves the values into (image_switch.py), where the configuration can
        have one, else on the slot objects."""
        check_artifact_names(artifact)  # the code: where its forms are decoded
        self.artifact = artifact
        self.system = system
        # the generated code's module globals: its classes, `_SYS`, `_G`, `_tick`, `_P`
        self.namespace = namespace(system) if printf is None else namespace(system, printf)
        self._pous = {pou.name.upper(): pou for pou in (*artifact.types, *artifact.pous)}
        # Functions come last: their default arguments may read globals, which need the
        # classes of structs and function blocks first.
        classes = [*artifact.types, *(p for p in artifact.pous if p.kind != "FUNCTION")]
        functions = [p for p in artifact.pous if p.kind == "FUNCTION"]
        first = [*classes, *([artifact.globals] if artifact.globals is not None else [])]
        units = [*first, *functions]
        self.units = {code_filename(unit): unit for unit in units}
        codes = compile_units([(unit.source, code_filename(unit)) for unit in units])
        self._codes = dict(zip(self.units, codes, strict=True))
        for code in codes[: len(first)]:
            exec(code, self.namespace)
        # the native bodies are made on a thread of their own, while this image runs as
        # Python; `tier_up` puts them in place
        self.native: NativeReport | None = None
        self.native_job: NativeJob | None = None
        # where the values go once the bodies are in place, when they go into an image
        # (image_plan.py): the resource moves them there between two cycles
        self.image: ImagePlan | None = None
        self._installed: NativeJob | None = None  # the job whose C bodies are in place
        self.python_only = False
        if native is not None and native.available:
            self.native_job = native.start(artifact, self.namespace, memory_image)
        self.globals: Any = None
        if artifact.globals is not None:
            self.globals = self.namespace[artifact.globals.class_name]()
            self.namespace["_G"] = self.globals
        for code in codes[len(first) :]:
            exec(code, self.namespace)
        # only code that makes references (REF) reads `reference_roots`; naming them walks
        # every variable, 20 ms of a reload's pause with 100,000 of them
        self.makes_references = any("_ref(" in unit.source for unit in self.units.values())

    def tier_up(self, wait: bool = False) -> NativeReport | None:
        """Put the native bodies in place once they are ready (`wait`: until they are); the
        report when this call installed them, else None. Called between two cycles."""
        job = self.native_job
        if job is None or not (job.wait() if wait else job.ready):
            return None
        self.native_job = None
        self.native = job.install()
        self._installed = job
        self.image = job.image
        if self.python_only:
            job.bodies(native=False)
        return self.native

    def run_as_python(self, python: bool) -> None:
        """Every body as Python (while debugging: runtime/debugging), or back to C where
        the native tier put C. Called between two cycles."""
        if python != self.python_only:
            self.python_only = python
            if self._installed is not None:
                self._installed.bodies(native=not python)

    def code_of(self, source: str, filename: str) -> CodeType | None:
        """The compiled code of a unit of this image with exactly this source."""
        unit = self.units.get(filename)
        return self._codes[filename] if unit is not None and unit.source == source else None

    def locate(self, exc: BaseException) -> SourceLocation | None:
        """The ST source line of a run-time error raised by generated code."""
        return locate(exc, self.units)

    def declared_attrs(self) -> dict[type, frozenset[str]]:
        """Per generated class, the attributes that are declared variables; other slots
        (edge memories, action control blocks, step start times) are internal state."""
        declared: dict[type, frozenset[str]] = {}
        for unit in self._units():
            kind = self.namespace.get(unit.class_name)
            if isinstance(kind, type):
                declared[kind] = frozenset(v.attr for v in unit.variables)
        return declared

    def classes(self) -> dict[str, type]:
        """The generated classes (structs, function blocks, programs, the globals) by name."""
        found = {unit.class_name: self.namespace.get(unit.class_name) for unit in self._units()}
        return {name: kind for name, kind in found.items() if isinstance(kind, type)}

    def object_attrs(self) -> dict[type, tuple[str, ...]]:
        """Per generated class, the declared attributes that hold generated objects or
        arrays of them (the edges a walk over the instances follows)."""
        classes = self.classes()
        return {
            classes[unit.class_name]: tuple(
                v.attr for v in unit.variables if self._is_aggregate(v.type)
            )
            for unit in self._units()
            if unit.class_name in classes
        }

    def adopt_program(self, fresh: Any, adopted: Any) -> None:
        """A program instance carried over from the configuration before a reload takes
        the place of the fresh one `prog();` calls reach."""
        programs = self.namespace["_P"]
        for name, instance in list(vars(programs).items()):
            if instance is fresh:
                setattr(programs, name, adopted)

    def adopt_globals(self, adopted: Any) -> None:
        """The globals carried over from the configuration before a reload become these."""
        self.globals = self.namespace["_G"] = adopted

    def _units(self) -> list[PouCode]:
        units = [*self.artifact.types, *self.artifact.pous]
        if self.artifact.globals is not None:
            units.append(self.artifact.globals)
        return units

    def reference_roots(self) -> dict[int, str]:
        """The paths of instances by id, that references made by the code read as paths
        (`runtime.code.instances.name_reference_roots` fills it)."""
        roots: dict[int, str] = self.namespace["_reference_roots"]
        return roots

    def new_globals(self) -> Any:
        """Another instance of the globals: a user program's own view of them."""
        assert self.artifact.globals is not None
        return self.namespace[self.artifact.globals.class_name]()

    def use(self, globals_view: Any, tick: Callable[[], None] | None) -> None:
        """What `_G` and `_tick` mean for the code that runs next (`_tick` None: loop
        passes are not metered)."""
        self.namespace["_G"] = globals_view
        self.namespace["_tick"] = tick

    def register_program(self, pou_name: str, instance: Any) -> None:
        """Make a program instance callable from ST by its POU name (`prog();`)."""
        class_name = self._pous[pou_name.upper()].class_name
        programs = self.namespace["_P"]
        if not hasattr(programs, class_name):
            setattr(programs, class_name, instance)

    def program_instance(self, pou_name: str) -> Any:
        class_name = self._pous[pou_name.upper()].class_name
        return getattr(self.namespace["_P"], class_name)

    def function(self, pou_name: str) -> Callable[..., Any]:
        pou = self._pous[pou_name.upper()]
        function: Callable[..., Any] = self.namespace[pou.class_name]
        return function

    def replace_function(self, pou_name: str, function: Callable[..., Any]) -> None:
        """What calls of a FUNCTION reach from now on (a debugger's traced entry)."""
        self.namespace[self._pous[pou_name.upper()].class_name] = function

    def renew(self) -> None:
        """Forget the instances made so far: fresh globals, and the program instances
        registered again by whoever makes them next (`padt test` starts every test from
        fresh instances of one image)."""
        self.namespace["_P"] = Namespace()
        if self.artifact.globals is not None:
            self.globals = self.namespace["_G"] = self.new_globals()

    def run_tests_with(self, runner: Callable[..., Any]) -> None:
        """`padt test`: the test functions of test files call `runner` (the `_test`
        intrinsic; docs/testing.md)."""
        self.namespace["_test"] = runner

    def new_instance(self, pou_name: str) -> Any:
        pou = self._pous[pou_name.upper()]
        return self.namespace[pou.class_name]()

    def variable_paths(self, program: str, pou_name: str) -> list[VariablePath]:
        """Every elementary variable of a program instance, FB members included."""
        paths: list[VariablePath] = []
        self._collect(self._pous[pou_name.upper()], program, (), False, paths)
        return self._configured(paths)

    def global_paths(self) -> list[VariablePath]:
        """Every elementary global variable (paths below `_G`), named without a prefix."""
        paths: list[VariablePath] = []
        if self.artifact.globals is not None:
            self._collect(self.artifact.globals, "", (), False, paths)
        return self._configured(paths)

    def _configured(self, paths: list[VariablePath]) -> list[VariablePath]:
        """The paths with the addresses VAR_CONFIG gave their partly specified locations
        (`AT %Q*` becomes `%QX0.1` there: an output point like any other)."""
        located = {path.upper(): location for path, location in self.artifact.located}
        if not located:
            return paths
        return [
            dataclasses.replace(p, location=located[p.path.upper()])
            if p.path.upper() in located
            else p
            for p in paths
        ]

    def _collect(
        self,
        pou: PouCode,
        prefix: str,
        attrs: tuple[Accessor, ...],
        constant: bool,
        out: list[VariablePath],
    ) -> None:
        for var in pou.variables:
            path = f"{prefix}.{var.name}" if prefix else var.name
            start = len(out)
            self._add(var.type, path, (*attrs, var.attr), constant or var.constant, out)
            if var.location is not None and len(out) == start + 1:
                out[start] = dataclasses.replace(out[start], location=var.location)

    def _add(
        self,
        type_name: str,
        path: str,
        attrs: tuple[Accessor, ...],
        constant: bool,
        out: list[VariablePath],
    ) -> None:
        inner = self._pous.get(type_name.upper())
        if inner is not None:
            self._collect(inner, path, attrs, constant, out)
            return
        shape = array_shape(type_name)
        if shape is not None and self._is_aggregate(shape.element):
            # elements with members get a path each; arrays of elementary values stay one
            # value (a list), so a large buffer does not flood the value list
            for offset, index in enumerate(shape.indices()):
                self._add(shape.element, f"{path}[{index}]", (*attrs, offset), constant, out)
            return
        out.append(VariablePath(path, attrs, type_name, constant))

    def members(self, type_name: str) -> tuple[VarInfo, ...]:
        """The declared variables of a struct or function block type; () for any other."""
        pou = self._pous.get(type_name.upper())
        return pou.variables if pou is not None else ()

    def _is_aggregate(self, type_name: str) -> bool:
        shape = array_shape(type_name)
        if shape is not None:
            return self._is_aggregate(shape.element)
        return type_name.upper() in self._pous


def slot_names(target: Any) -> Iterator[str]:
    """The attributes of a generated object (its class's and its bases' `__slots__`)."""
    for kind in type(target).__mro__:
        yield from getattr(kind, "__slots__", ())
