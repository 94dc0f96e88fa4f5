"""The native tier of a resource: the bodies of its generated classes translated to C
(`translate.py`), compiled (`build.py`) and bound to the classes in place of the Python
bodies, which stay the reference: whatever cannot be translated runs as Python.

A compiled module keeps what it binds (the namespace, the classes' slot offsets, its call
sites) in C statics. A shared object is loaded once per path, so each binding loads a
copy of its own; a copy whose classes are gone is bound again by a later image (a reload,
a cold start) rather than loading yet another.
"""

from __future__ import annotations

import atexit
import json
import shutil
import subprocess
import sys
import tempfile
import threading
import weakref
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import ModuleType
from typing import Any

from runtime.code.compile_worker import child_environment
from runtime.code.native.build import (
    BuildError,
    Toolchain,
    find_toolchain,
    load,
    runtime_module,
)
from runtime.code.native.image_body import NOT_YET
from runtime.code.native.image_plan import ImagePlan, plan_image
from runtime.contract.artifact import Artifact

# Attributes the tier sets on a bound class. Their names have `__`, which no ST name has
# (E0004): a variable of the block is a slot of the same class, which a class attribute of
# its name would replace.
IN_IMAGE = "image"  # NativeReport.memory: the variables go into the memory image
IMAGE_ATTR = "_native_image"  # on a view class: what its module's statics borrow
FUNCTIONS_ATTR = "native__functions"  # on a class bound in slot mode: its FUNCTIONs' table
NAMESPACE_ATTR = "native__namespace"  # a bound class holds its namespace through it
# the Python body, for a derived block's SUPER^(), which runs it on an instance of another
# class (padt_native.h)
PYTHON_BODY_ATTR = "python__call"
WORKER_TIMEOUT_S = 1800  # a very large project compiles for minutes; never for ever
CYCLE_SOURCE = Path(__file__).with_name("padt_cycle.c")


def _breathe() -> None:
    """Called every few thousand loop passes of native code: entering it, the interpreter
    serves its pending requests (padt_native.h, padt_breathe)."""


@dataclass(frozen=True)
class NativeReport:
    """What runs as C after a binding, and why the rest does not."""

    bodies: tuple[str, ...]  # the POUs (programs, function blocks) whose bodies run as C
    left: tuple[tuple[str, str], ...]  # (POU, reason): bodies that run as Python
    failed: tuple[str, ...] = ()  # what did not build or bind, with the compiler's words
    # where the variables are once the bodies run: "image" (native memory), or why they
    # stay on objects; "" where no image was asked for
    memory: str = ""
    methods: tuple[str, ...] = ()  # "POU.M__X": the methods whose bodies run as C

    def summary(self, cycle_in_c: bool = False) -> str:
        """What the event log says; `cycle_in_c`: the resource's usual cycle runs in C
        (runtime/cycle_core.py)."""
        total = len(self.bodies) + len(self.left)
        text = f"native code in place: {len(self.bodies)} of {total} POU bodies run as C"
        if self.methods:
            text += f" (and {len(self.methods)} methods)"
        if self.memory == IN_IMAGE:
            text += ", the variables in native memory"
        elif self.memory:
            text += f", the variables on Python objects ({self.memory})"
        if cycle_in_c:
            text += ", the usual CPU cycle in C"
        if self.left:
            pou, reason = self.left[0]
            more = f" and {len(self.left) - 1} more" if len(self.left) > 1 else ""
            text += f"; as Python: {pou} ({reason}){more}"
        if self.failed:
            text += f"; not built: {self.failed[0][:300]}"
        return text


@dataclass
class _Copies:
    """The loaded copies of one compiled module; `free` ones have no living class."""

    loaded: int = 0
    free: list[ModuleType] = field(default_factory=list)


class NativeTier:
    """Translates, builds and binds; shared by every image of a resource (thread-safe:
    jobs run on threads of their own)."""

    def __init__(self, cache: Path, toolchain: Toolchain | None = None) -> None:
        self.cache = cache
        self.toolchain = toolchain or find_toolchain()
        self._lock = threading.Lock()
        self._copies: dict[str, _Copies] = {}
        self._scratch: Path | None = None
        # padt_cycle as a native job left it (the cycle thread takes it from here, never
        # waiting for a compiler or a disk), or why there is none
        self.cycle_built: ModuleType | str = "its C is not built yet"

    @property
    def available(self) -> bool:
        return self.toolchain is not None

    def cycle_module(self) -> ModuleType:
        """padt_cycle, the usual CPU cycle in C (runtime/cycle_core.py), built into the
        cache unless it is there (BuildError), loaded once per process."""
        assert self.toolchain is not None
        return runtime_module("padt_cycle", CYCLE_SOURCE, self.cache, self.toolchain)

    def start(
        self, artifact: Artifact, namespace: dict[str, Any], memory_image: bool = False
    ) -> NativeJob:
        """The native bodies of the classes of `namespace` (made from `artifact`),
        prepared on a thread of their own; `NativeJob.install` puts them in place. With
        `memory_image`, bodies on the configuration's image where it can have one."""
        return NativeJob(self, artifact, namespace, memory_image)

    def prepare(
        self, artifact: Artifact, namespace: dict[str, Any], image: ImagePlan | None = None
    ) -> tuple[list[tuple[type, str, Any]], NativeReport]:
        """Translated and built by the worker process, then loaded and bound here (the C
        statics; no class changes yet): the bodies to install, and the report. With
        `image`, the bodies of image mode, to install on its view classes."""
        if not any(pou.kind != "FUNCTION" for pou in artifact.pous):
            # no body a class runs, so no C that calls a FUNCTION: nothing to start a worker for
            return [], NativeReport((), ())
        mode = ["image"] if image is not None else []
        try:
            done = subprocess.run(
                [sys.executable, "-m", "runtime.code.native.worker", str(self.cache), *mode],
                input=artifact.to_json().encode(),
                capture_output=True,
                env=child_environment(),
                process_group=0,  # a Ctrl-C at the terminal is the runtime's to handle
                timeout=WORKER_TIMEOUT_S,
                check=False,
            )
            answer = json.loads(done.stdout) if done.returncode == 0 else None
        except (OSError, ValueError, subprocess.TimeoutExpired) as exc:
            return [], NativeReport((), (), (f"the native worker did not run: {exc}",))
        if not isinstance(answer, dict) or "units" not in answer:
            why = answer.get("error") if isinstance(answer, dict) else None
            why = why or done.stderr.decode(errors="replace").strip()[-500:]
            return [], NativeReport((), (), (f"the native worker failed: {why}",))
        found: list[tuple[type, str, Any]] = []
        bodies: list[str] = []
        methods: list[str] = []
        left: list[tuple[str, str]] = []
        failed: list[str] = []
        # the FUNCTIONs' C bodies by name and C signature (function_body.py): an image's
        # registry, beside its blocks' bodies
        functions: dict[str, Any] = image.registry if image is not None else {}
        # a FUNCTION's module binds no class: it lives as long as the classes whose C
        # calls it, so it is bound after them
        units = sorted(answer["units"], key=lambda unit: bool(unit.get("function")))
        for unit in units:
            pou = str(unit["pou"])
            left.extend((pou, str(reason)) for reason in unit["left"])
            if "failed" in unit:
                failed.append(f"{pou}: {unit['failed']}")
                left.append((pou, "its C module did not build"))
            if "module" not in unit:
                continue
            keep_with = None
            if unit.get("function"):
                keep_with = (
                    set(image.views.values()) if image is not None else {k for k, _, _ in found}
                )
                if not keep_with:
                    left.append((pou, "no body's C calls it"))
                    continue
            try:
                found.extend(
                    self._bind(
                        str(unit["module"]),
                        Path(unit["path"]),
                        namespace,
                        image,
                        functions,
                        keep_with,
                    )
                )
            except (OSError, ImportError, TypeError, ValueError) as exc:
                failed.append(f"{pou}: {exc}")
                left.append((pou, "its C module did not bind"))
                continue
            if "methods" in unit:
                methods.extend(f"{pou}.{method}" for method in unit["methods"])
            else:
                bodies.append(pou)
        report = NativeReport(tuple(sorted(bodies)), tuple(sorted(left)), tuple(failed))
        return found, replace(report, methods=tuple(sorted(methods)))

    def _bind(
        self,
        name: str,
        shared: Path,
        namespace: dict[str, Any],
        image: ImagePlan | None,
        functions: dict[str, Any],
        keep_with: set[type] | None = None,
    ) -> list[tuple[type, str, Any]]:
        """The bodies a module binds; `keep_with`: the classes a module that binds none
        (a FUNCTION's) lives as long as."""
        if not shared.resolve().is_relative_to(self.cache.resolve()):
            raise ValueError(f"{shared} is not in the cache")
        module = self._copy(name, shared)
        classes = namespace if image is None else image.views
        try:
            found: dict[tuple[str, str], Any] = (
                module.bind(namespace, _breathe, functions)
                if image is None
                else module.bind(
                    namespace, _breathe, image.views, image.registry, image.memory.View
                )
            )
        except BaseException:
            self._release(name, module)
            raise
        bound = {classes[cls] for cls, _ in found} | (keep_with or set())
        for kind in bound:
            # the C statics borrow the namespace (and an image's view classes and registry,
            # or the FUNCTIONs' table): a class it was bound to keeps them alive
            setattr(kind, NAMESPACE_ATTR, namespace)
            if image is not None:
                setattr(kind, IMAGE_ATTR, (image.views, image.registry))
            else:
                setattr(kind, FUNCTIONS_ATTR, functions)
        # the copy is free again once every class it was bound to is gone
        remaining = [len(bound)]

        def gone() -> None:
            remaining[0] -= 1
            if remaining[0] == 0:
                self._release(name, module)

        for kind in bound:
            weakref.finalize(kind, gone)
        return [(classes[cls], method, body) for (cls, method), body in sorted(found.items())]

    def _copy(self, name: str, shared: Path) -> ModuleType:
        with self._lock:
            copies = self._copies.setdefault(name, _Copies())
            if copies.free:
                return copies.free.pop()
            copies.loaded += 1
            number = copies.loaded
            if self._scratch is None:
                self._scratch = Path(tempfile.mkdtemp(prefix="padt-native-"))
                atexit.register(shutil.rmtree, self._scratch, ignore_errors=True)
            path = self._scratch / f"{name}-{number}{shared.suffix}"
        # a copy, not a link: the dynamic loader takes a file it knows (same inode) once
        shutil.copyfile(shared, path)
        return load(name, path)

    def _release(self, name: str, module: ModuleType) -> None:
        with self._lock:
            self._copies[name].free.append(module)


class NativeJob:
    """The native bodies of one image, prepared on a thread of its own while the image
    runs as Python; the thread that runs the image installs them (between two cycles)."""

    def __init__(
        self,
        tier: NativeTier,
        artifact: Artifact,
        namespace: dict[str, Any],
        memory_image: bool = False,
    ) -> None:
        self._done = threading.Event()
        self._found: list[tuple[type, str, Any]] = []
        self.report: NativeReport | None = None
        # the configuration's memory image, when its values go there (image_plan.py)
        self.image: ImagePlan | None = None
        self.installed = False
        # (class, method, Python body, C body) of every installed body
        self.swaps: list[tuple[type, str, Any, Any]] = []
        self._thread = threading.Thread(
            target=self._run,
            args=(tier, artifact, namespace, memory_image),
            name="padt-native",
            daemon=True,
        )
        self._thread.start()

    def _run(
        self, tier: NativeTier, artifact: Artifact, namespace: dict[str, Any], memory_image: bool
    ) -> None:
        # the CPU cycle's C, built here rather than on the cycle thread (a compiler run the
        # first time on a machine), beside the worker; a resource takes it once its code is
        # in place (runtime/cycle_core.py)
        cycle = threading.Thread(target=_build_cycle, args=(tier,), name="padt-native-cycle")
        cycle.start()
        try:
            plan = _plan(tier, artifact, namespace) if memory_image else ""
            image = plan if isinstance(plan, ImagePlan) else None
            memory = plan if isinstance(plan, str) else IN_IMAGE
            self._found, report = tier.prepare(artifact, namespace, image)
            # a body image mode leaves to Python is C on slots: the image would cost more
            # than it gives, and a defect of image mode costs the image, not the bodies
            held = [(pou, reason) for pou, reason in report.left if NOT_YET in reason]
            if image is not None and (report.failed or held):
                memory = (
                    f"its image-mode C did not build: {report.failed[0][:200]}"
                    if report.failed
                    else f"in native memory {held[0][0]} would run as Python: {held[0][1]}"
                )
                self._found, report = tier.prepare(artifact, namespace)
            else:
                self.image = image
            self.report = replace(report, memory=memory)
        except Exception as exc:  # a defect of the tier: the image stays Python
            self.report = NativeReport(
                (), (), (f"the native tier failed: {type(exc).__name__}: {exc}",)
            )
        finally:
            cycle.join()
            self._done.set()

    @property
    def ready(self) -> bool:
        return self._done.is_set()

    def wait(self, timeout: float | None = None) -> bool:
        return self._done.wait(timeout)

    def install(self) -> NativeReport:
        """The prepared bodies in place of the Python ones (once; only when ready)."""
        assert self.ready and self.report is not None
        if not self.installed:
            self.installed = True
            for kind, method, body in self._found:
                python = kind.__dict__[method]
                if method == "__call__" and PYTHON_BODY_ATTR not in kind.__dict__:
                    setattr(kind, PYTHON_BODY_ATTR, python)
                self.swaps.append((kind, method, python, body))
                setattr(kind, method, body)
            self._found = []
        return self.report

    def bodies(self, native: bool) -> None:
        """The installed bodies as C (`native`) or as the Python they replaced: a debugged
        resource runs as Python, whose lines can be traced (runtime/debugging). Values live
        in the instances, not in the code, so they are the same on either side."""
        for kind, method, python, body in self.swaps:
            setattr(kind, method, body if native else python)


def _build_cycle(tier: NativeTier) -> None:
    """padt_cycle built and loaded; where it cannot be, `Resource.tier_up` says why."""
    if tier.available:
        try:
            tier.cycle_built = tier.cycle_module()
        except (BuildError, OSError, ImportError) as exc:
            tier.cycle_built = str(exc)[:300]


def _plan(tier: NativeTier, artifact: Artifact, namespace: dict[str, Any]) -> ImagePlan | str:
    """The image of the configuration whose classes `namespace` holds, or why it has none."""
    assert tier.toolchain is not None
    classes = {
        unit.class_name: namespace[unit.class_name]
        for unit in artifact.units()
        if isinstance(namespace.get(unit.class_name), type)
    }
    return plan_image(artifact, classes, tier.cache, tier.toolchain)
