"""The native tier's heavy work, in a child process: the translation (Python, which in the
runtime would hold the interpreter lock the cycle thread needs, 0.4 s for the benchmark
program) and the C compiler. The runtime sends the artifact, waits for the answer with
the lock released, and only loads and binds what the child built.

A translation is kept beside the compiled modules, by the hash of what it depends on (the
unit's name and typed form, the classes it reads, the FUNCTIONs it calls, the translator
itself), so a unit built before is neither translated nor compiled again.

Nothing is translated of an artifact with a unit that is not one the compiler could have
built: `load_artifact` decodes and checks every unit's typed form
(`runtime/contract/code/form_check.py`), and the names the C is made of are checked again
here (`check_artifact_names`), so no name of an artifact's choosing becomes C.

Run as `python -m runtime.code.native.worker CACHE`: a request (JSON) on stdin, the answer on
stdout.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import sys
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from runtime.code.fault_location import code_filename
from runtime.code.native.build import BuildError, build, find_toolchain, mark_used, prune
from runtime.code.native.function_body import translate_function, translate_methods
from runtime.code.native.image_body import translate_image_unit
from runtime.code.native.kinds import ClassInfo, Forms, FunctionInfo, class_table, function_table
from runtime.code.native.translate import Translated, translate_unit
from runtime.contract.artifact import Artifact, PouCode, load_artifact
from runtime.contract.generated_code import GeneratedCodeError, check_artifact_names
from runtime.contract.layout import LayoutRefused, Layouts, class_layouts, runtime_layouts

WORKER_NICE = 10  # background work: below the runtime and below normal programs
_SOURCES = (
    "translate.py",
    "image_body.py",
    "function_body.py",
    "kinds.py",
    "padt_native.h",
    "padt_image.h",
    "build.py",
)
# the C is made from the typed form and numbers lines as the printer does
_FORM_SOURCES = ("python_text.py", "typed_form.py", "statements.py", "units.py")


def translatable_units(artifact: Artifact) -> list[PouCode]:
    """What the native tier looks at: the generated classes (not the FUNCTIONs)."""
    units = [*artifact.types, *(p for p in artifact.pous if p.kind != "FUNCTION")]
    return [*units, *([artifact.globals] if artifact.globals is not None else [])]


@dataclass(frozen=True)
class ArtifactTranslation:
    """What translating the bodies of one artifact needs beside each unit's own form: the
    classes the bodies read and the FUNCTIONs they call."""

    units: list[PouCode]  # the programs and function blocks, whose bodies are translated
    function_units: list[PouCode]  # the FUNCTIONs, whose bodies are translated too
    forms: Forms
    classes: dict[str, ClassInfo]
    functions: dict[str, FunctionInfo]
    globals_class: str | None

    @classmethod
    def of(cls, artifact: Artifact) -> ArtifactTranslation:
        """GeneratedCodeError for an artifact with any unit named otherwise than the
        compiler names units and variables, before any name is put into C (the forms are
        checked as they are decoded)."""
        check_artifact_names(artifact)
        units = translatable_units(artifact)
        bodies = [unit for unit in units if unit.kind in ("PROGRAM", "FUNCTION_BLOCK")]
        functions = [unit for unit in artifact.pous if unit.kind == "FUNCTION"]
        forms = {unit.class_name: unit.unit for unit in [*bodies, *functions]}
        return cls(
            bodies,
            functions,
            forms,
            class_table(units, forms),
            function_table([*units, *functions], forms),
            artifact.globals.class_name if artifact.globals is not None else None,
        )

    def shape(self) -> str:
        """All of it a translation depends on but the unit's form (a cache key's part)."""
        members = [
            (
                name,
                sorted(c.members.items(), key=str),
                sorted(c.methods.items()),
                sorted(c.overridden),
            )
            for name, c in self.classes.items()
        ]
        return repr((self.globals_class, sorted(members), sorted(self.functions.items())))

    def translate_methods(self, unit: PouCode, layouts: Layouts | None = None) -> Translated:
        """The C of the methods of a block's class that take and give numbers, BOOLs and
        texts: on the slots of objects, or in image mode at `layouts`' offsets."""
        form = self.forms[unit.class_name]
        return translate_methods(
            unit, form, self.classes, self.globals_class, self.functions, layouts
        )

    def translate(self, unit: PouCode, layouts: Layouts | None = None) -> Translated:
        """The unit's C: on the slots of objects, or in image mode at `layouts`' offsets."""
        form = self.forms[unit.class_name]
        if unit.kind == "FUNCTION":
            return translate_function(
                unit, form, self.classes, self.globals_class, self.functions, layouts
            )
        if layouts is not None:
            return translate_image_unit(
                unit, form, self.classes, self.globals_class, layouts, self.functions
            )
        return translate_unit(unit, form, self.classes, self.globals_class, self.functions)


def _translator_fingerprint() -> str:
    here, form = Path(__file__).parent, Path(__file__).parents[2] / "contract" / "code"
    paths = [*(here / name for name in _SOURCES), *(form / name for name in _FORM_SOURCES)]
    text = "".join(path.read_text() for path in paths)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _known(entry: Path) -> dict[str, Any] | None:
    """A unit's answer from the index when it is there whole (its module built), both marked
    used for the cache's pruning."""
    try:
        answer = json.loads(entry.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(answer, dict):
        return None
    if answer.get("module"):
        module = Path(str(answer.get("path")))
        if not module.is_file():
            return None
        mark_used(module)
    mark_used(entry)
    return answer


def _write_atomically(path: Path, text: str) -> None:
    """`path` with `text`, whole or not at all: runtimes that share a cache (PADT_NATIVE_CACHE)
    may write and read the same entry at once, and a reader must never see half of it."""
    scratch = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        scratch.write_text(text)
        os.replace(scratch, path)
    except OSError:  # not kept (a full disk, a prune meanwhile): translated again when needed
        with contextlib.suppress(OSError):
            scratch.unlink()


def make(artifact: Artifact, cache: Path, image: bool = False) -> dict[str, Any]:
    """Per program, function block and FUNCTION: the POU, its module (name and built shared
    object) when a body translated, the bodies left to Python with the reasons, a build
    failure. With `image`, the bodies in image mode, on the configuration's memory image,
    and per block the methods whose bodies are C (`methods`)."""
    toolchain = find_toolchain()
    if toolchain is None:
        return {"error": "no C compiler or no Python.h on this machine"}
    try:
        translation = ArtifactTranslation.of(artifact)
        layouts = {**runtime_layouts(), **class_layouts(artifact.units())} if image else None
    except (GeneratedCodeError, LayoutRefused) as exc:
        return {"error": str(exc)}
    shape = translation.shape()
    if layouts is not None:  # every offset a body reads is in its C
        shape += "image" + repr(sorted(layouts.items()))
    fingerprint = _translator_fingerprint()
    index = cache / toolchain.fingerprint / "index"
    index.mkdir(parents=True, exist_ok=True)
    work: list[tuple[PouCode, str]] = [
        *((unit, "") for unit in [*translation.units, *translation.function_units]),
        # each block's methods of numbers, BOOLs and texts too: a module of their own
        *((unit, "methods") for unit in translation.units),
    ]
    answers: list[dict[str, Any]] = []
    # each module compiled on a thread of its own while the next units translate: the C
    # compilers run on every core, the translation (Python) beside them
    pending: list[tuple[dict[str, Any], Path, str, Future[Path] | None]] = []
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as builds:
        for unit, part in work:
            # the unit's name too: it is in the C text (a module built before names were
            # checked could otherwise serve another unit of the same form)
            named = (fingerprint, shape, code_filename(unit), part, unit.form)
            key = hashlib.sha256("\n".join(named).encode()).hexdigest()[:32]
            known = index / f"{key}.json"
            answer = _known(known)
            if answer is None:
                if part:
                    translated = translation.translate_methods(unit, layouts)
                else:
                    translated = translation.translate(unit, layouts)
                answer = {"pou": unit.name, "left": [reason for _, reason in translated.left]}
                if part:  # the methods translated; the others stay Python, as before
                    answer.update(function=True, methods=list(translated.bodies), left=[])
                elif unit.kind == "FUNCTION":  # its module binds to no class (tier.py)
                    answer["function"] = True
                source, module = translated.source, translated.module
                compiled = (
                    builds.submit(build, module, source, cache, toolchain) if source else None
                )
                pending.append((answer, known, module, compiled))
            answers.append(answer)  # a pending one is completed below, in place
        for answer, known, module, compiled in pending:
            if compiled is not None:
                try:
                    answer.update(module=module, path=str(compiled.result()))
                except BuildError as exc:
                    answer["failed"] = str(exc)
            if "failed" not in answer:
                _write_atomically(known, json.dumps(answer))
    prune(cache)
    return {"units": answers}


def main() -> None:
    with contextlib.suppress(OSError):
        os.setpriority(os.PRIO_PROCESS, 0, WORKER_NICE)
    cache = Path(sys.argv[1])
    image = sys.argv[2:] == ["image"]
    artifact = load_artifact(sys.stdin.buffer.read())
    json.dump(make(artifact, cache, image), sys.stdout)


if __name__ == "__main__":
    main()
