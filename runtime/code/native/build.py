"""C modules of the native tier compiled into shared objects, kept in a cache folder by the
hash of their source (the module name is that hash), so that a unit is compiled once per
machine: at the next load, reload or cold start it is taken from the cache. The cache is
bounded: each use marks an entry, and the entries used longest ago go once it holds more than
`CACHE_LIMIT_BYTES` (a controller's disk is not for a history of online changes).

The compiler runs as a child process: waiting for it releases the interpreter lock, so a
reload prepared while cycles run does not hold up the cycle thread.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.machinery
import importlib.util
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path
from stat import S_ISREG
from types import ModuleType

HEADER = Path(__file__).with_name("padt_native.h")
IMAGE_HEADER = HEADER.with_name("padt_image.h")  # which HEADER includes
SUFFIX = ".so"
# -O1: a tenth of -O2's compile time for generated code of this shape, and within a few
# per cent of its speed (make bench, bench_language)
# -ffp-contract=off: a*b+c stays two roundings, as in Python (never a fused multiply-add)
FLAGS = ("-O1", "-shared", "-fPIC", "-fwrapv", "-fno-strict-aliasing", "-ffp-contract=off", "-w")
COMPILE_TIMEOUT_S = 300
CACHE_LIMIT_BYTES = 128 * 2**20  # a thousand units of the size of the benchmark program's


_runtime_modules: dict[str, ModuleType] = {}  # the runtime's own C, loaded, by name
# one lock per module of the runtime's own C (by prefix): a thread building one never
# waits for another's build
_loading: dict[str, threading.Lock] = {}


class BuildError(Exception):
    """A unit that did not compile; the message carries the compiler's words."""


@dataclass(frozen=True)
class Toolchain:
    compiler: str  # path of the C compiler
    include: str  # Python's headers

    @property
    def fingerprint(self) -> str:
        """What a cached shared object depends on besides its source."""
        text = "\n".join(
            (
                HEADER.read_text(),
                IMAGE_HEADER.read_text(),
                sys.version,
                self.compiler,
                " ".join(FLAGS),
                self.include,
            )
        )
        return hashlib.sha256(text.encode()).hexdigest()[:12]


def find_toolchain() -> Toolchain | None:
    """The C compiler ($CC, else cc or gcc) and Python.h, or None when either is missing."""
    include = sysconfig.get_paths()["include"]
    if not Path(include, "Python.h").is_file():
        return None
    for name in (os.environ.get("CC", ""), "cc", "gcc"):
        found = shutil.which(name) if name else None
        if found:
            return Toolchain(found, include)
    return None


def build(module: str, source: str, cache: Path, toolchain: Toolchain) -> Path:
    """The shared object of a translated module, compiled unless the cache has it."""
    folder = cache / toolchain.fingerprint
    target = folder / f"{module}{SUFFIX}"
    if target.is_file():
        mark_used(target)
        return target
    folder.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=folder, prefix="build-") as scratch:
        c_file = Path(scratch, f"{module}.c")
        c_file.write_text(source)
        output = Path(scratch, f"{module}{SUFFIX}")
        command = [
            toolchain.compiler,
            *FLAGS,
            "-I",
            toolchain.include,
            "-I",
            str(HEADER.parent),
            "-o",
            str(output),
            str(c_file),
        ]
        try:
            done = subprocess.run(
                command, capture_output=True, text=True, timeout=COMPILE_TIMEOUT_S, check=False
            )
        except (OSError, subprocess.TimeoutExpired) as exc:
            raise BuildError(f"{module}: the C compiler did not run: {exc}") from None
        if done.returncode != 0 or not output.is_file():
            raise BuildError(f"{module}: {done.stderr.strip()[-2000:]}")
        os.replace(output, target)  # atomic: another process may build the same module
    return target


def load(name: str, path: Path) -> ModuleType:
    """The extension module `name` of the shared object at `path`, loaded and run."""
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    spec = importlib.util.spec_from_file_location(name, path, loader=loader)
    assert spec is not None
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def mark_used(path: Path) -> None:
    """A cache entry just used: the last to go when the cache is pruned."""
    with contextlib.suppress(OSError):  # gone meanwhile: it is made again when next needed
        os.utime(path)


def prune(cache: Path, limit: int = CACHE_LIMIT_BYTES) -> int:
    """The files of the cache used longest ago removed until it holds at most `limit` bytes;
    the number removed. A loaded module is a copy elsewhere, so nothing running depends on
    the cache; an entry removed is made again when needed. Builds in progress are left."""
    entries: list[tuple[float, int, Path]] = []
    # links are not followed: nothing outside the cache is ever removed
    for folder, subfolders, files in os.walk(cache):
        subfolders[:] = [name for name in subfolders if not name.startswith("build-")]
        for name in files:
            path = Path(folder, name)
            with contextlib.suppress(OSError):
                stat = path.lstat()
                if S_ISREG(stat.st_mode):
                    entries.append((stat.st_mtime, stat.st_size, path))
    total = sum(size for _, size, _ in entries)
    removed = 0
    for _, size, path in sorted(entries, key=lambda entry: (entry[0], str(entry[2]))):
        if total <= limit:
            break
        with contextlib.suppress(OSError):
            path.unlink()
            removed += 1
        total -= size
    return removed


def runtime_module(prefix: str, source: Path, cache: Path, toolchain: Toolchain) -> ModuleType:
    """A C module of the runtime itself (not of a unit: `padt_memory`, `padt_cycle`), built
    into `cache` unless it is there and loaded once per process. It is named by the hash of
    its source and of `padt_image.h`, which it may include."""
    text = source.read_text()
    hashed = IMAGE_HEADER.read_text() + text
    name = f"{prefix}_{hashlib.sha256(hashed.encode()).hexdigest()[:16]}"
    with _loading.setdefault(prefix, threading.Lock()):  # setdefault: atomic
        module = _runtime_modules.get(name)
        if module is None:
            path = build(name, f"#define PADT_INIT PyInit_{name}\n{text}", cache, toolchain)
            module = _runtime_modules[name] = load(name, path)
    return module
