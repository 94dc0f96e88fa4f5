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
import importlib.machinery
import importlib.util
import shutil
import tempfile
import threading
import weakref
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

from runtime.contract.artifact import PouCode
from runtime.native.build import BuildError, Toolchain, build, find_toolchain
from runtime.native.kinds import class_table
from runtime.native.translate import Translated, translate_unit

NAMESPACE_ATTR = "_native_namespace"  # a bound class holds its namespace through it


def _breathe() -> None:
    """Called every few thousand loop passes of native code: entering it, the interpreter
    serves its pending requests (padt_native.h, padt_breathe)."""


@dataclass(frozen=True)
class NativeReport:
    """What runs as C after a binding, and why the rest does not."""

    bodies: tuple[str, ...]  # "POU_TON.__call__"
    left: tuple[tuple[str, str], ...]  # (body, reason) run as Python
    failed: tuple[str, ...] = ()  # units whose C did not build or bind

    def summary(self) -> str:
        total = len(self.bodies) + len(self.left)
        return f"native code: {len(self.bodies)} of {total} bodies"


@dataclass
class _Copies:
    """The loaded copies of one compiled module; `free` ones have no living class."""

    loaded: int = 0
    free: list[ModuleType] = field(default_factory=list)


class NativeTier:
    """Translates, builds and binds; shared by every image of a resource (thread-safe:
    a reload prepares on another thread)."""

    def __init__(self, cache: Path, toolchain: Toolchain | None = None) -> None:
        self.cache = cache
        self.toolchain = toolchain or find_toolchain()
        self._lock = threading.Lock()
        self._copies: dict[str, _Copies] = {}
        self._translations: dict[tuple[str, str], Translated] = {}
        self._scratch: Path | None = None

    @property
    def available(self) -> bool:
        return self.toolchain is not None

    def apply(
        self, units: list[PouCode], globals_class: str | None, namespace: dict[str, Any]
    ) -> NativeReport:
        """Bind native bodies to the classes of `namespace` (made from `units`)."""
        if self.toolchain is None:
            return NativeReport((), (), ("no C compiler or Python headers on this machine",))
        classes = class_table(units)
        shape = repr(
            sorted((name, sorted(info.members.items(), key=str)) for name, info in classes.items())
        )
        bodies: list[str] = []
        left: list[tuple[str, str]] = []
        failed: list[str] = []
        for unit in units:
            if unit.kind not in ("PROGRAM", "FUNCTION_BLOCK"):
                continue
            translated = self._translated(unit, classes, globals_class, shape)
            left.extend(translated.left)
            if not translated.source:
                continue
            try:
                self._bind(translated, namespace)
            except (BuildError, OSError, ImportError, TypeError, ValueError) as exc:
                failed.append(f"{unit.name}: {exc}")
                left.extend(
                    (body, "its C module did not build or bind") for body in translated.bodies
                )
                continue
            bodies.extend(translated.bodies)
        return NativeReport(tuple(sorted(bodies)), tuple(sorted(left)), tuple(failed))

    def _translated(
        self, unit: PouCode, classes: Any, globals_class: str | None, shape: str
    ) -> Translated:
        key = (unit.source, f"{globals_class}|{shape}")
        with self._lock:
            known = self._translations.get(key)
        if known is None:
            known = translate_unit(unit, classes, globals_class)
            with self._lock:
                self._translations[key] = known
        return known

    def _bind(self, translated: Translated, namespace: dict[str, Any]) -> None:
        assert self.toolchain is not None
        shared = build(translated.module, translated.source, self.cache, self.toolchain)
        module = self._copy(translated.module, shared)
        try:
            found: dict[tuple[str, str], Any] = module.bind(namespace, _breathe)
        except BaseException:
            self._release(translated.module, module)
            raise
        bound = {namespace[cls] for cls, _ in found}
        for kind in bound:
            setattr(kind, NAMESPACE_ATTR, namespace)
        for (cls, method), body in found.items():
            setattr(namespace[cls], method, body)
        # the copy is free again once every class it was bound to is gone
        remaining = [len(bound)]

        def gone() -> None:
            remaining[0] -= 1
            if remaining[0] == 0:
                self._release(translated.module, module)

        for kind in bound:
            weakref.finalize(kind, gone)

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
        loader = importlib.machinery.ExtensionFileLoader(name, str(path))
        spec = importlib.util.spec_from_file_location(name, path, loader=loader)
        assert spec is not None
        module = importlib.util.module_from_spec(spec)
        loader.exec_module(module)
        return module

    def _release(self, name: str, module: ModuleType) -> None:
        with self._lock:
            self._copies[name].free.append(module)
