"""The native tier's heavy work, in a child process: the translation (Python, which in the
runtime would hold the interpreter lock the cycle thread needs, 0.4 s for the benchmark
program) and the C compiler. The runtime sends the artifact, waits for the answer with
the lock released, and only loads and binds what the child built.

A translation is kept beside the compiled modules, by the hash of what it depends on (the
unit's source, the classes it reads, the translator itself), so a unit built before is
neither translated nor compiled again.

Run as `python -m runtime.native.worker CACHE`: a request (JSON) on stdin, the answer on
stdout.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import sys
from pathlib import Path
from typing import Any

from runtime.contract.artifact import Artifact, PouCode, load_artifact
from runtime.native.build import BuildError, build, find_toolchain
from runtime.native.kinds import class_table, function_table
from runtime.native.translate import translate_unit

WORKER_NICE = 10  # background work: below the runtime and below normal programs
_SOURCES = ("translate.py", "kinds.py", "padt_native.h", "build.py")


def translatable_units(artifact: Artifact) -> list[PouCode]:
    """What the native tier looks at: the generated classes (not the FUNCTIONs)."""
    units = [*artifact.types, *(p for p in artifact.pous if p.kind != "FUNCTION")]
    return [*units, *([artifact.globals] if artifact.globals is not None else [])]


def _translator_fingerprint() -> str:
    here = Path(__file__).parent
    text = "".join((here / name).read_text() for name in _SOURCES)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def make(artifact: Artifact, cache: Path) -> dict[str, Any]:
    """Per program and function block: the POU, its module (name and built shared object)
    when a body translated, the bodies left to Python with the reasons, a build failure."""
    toolchain = find_toolchain()
    if toolchain is None:
        return {"error": "no C compiler or no Python.h on this machine"}
    units = translatable_units(artifact)
    classes = class_table(units)
    functions = function_table(list(artifact.pous))
    globals_class = artifact.globals.class_name if artifact.globals is not None else None
    shape = repr(
        (
            sorted((name, sorted(info.members.items(), key=str)) for name, info in classes.items()),
            sorted(functions.items()),
        )
    )
    fingerprint = _translator_fingerprint()
    index = cache / toolchain.fingerprint / "index"
    index.mkdir(parents=True, exist_ok=True)
    answers = []
    for unit in units:
        if unit.kind not in ("PROGRAM", "FUNCTION_BLOCK"):
            continue
        key = hashlib.sha256(
            "\n".join((fingerprint, f"{globals_class}", shape, unit.source)).encode()
        ).hexdigest()[:32]
        known = index / f"{key}.json"
        answer: dict[str, Any] | None = None
        if known.is_file():
            with contextlib.suppress(OSError, ValueError):
                answer = json.loads(known.read_text())
        if answer is None or (answer.get("module") and not Path(answer["path"]).is_file()):
            translated = translate_unit(unit, classes, globals_class, functions)
            answer = {"pou": unit.name, "left": [reason for _, reason in translated.left]}
            if translated.source:
                try:
                    path = build(translated.module, translated.source, cache, toolchain)
                except BuildError as exc:
                    answer["failed"] = str(exc)
                else:
                    answer.update(module=translated.module, path=str(path))
            if "failed" not in answer:
                known.write_text(json.dumps(answer))
        answers.append(answer)
    return {"units": answers}


def main() -> None:
    with contextlib.suppress(OSError):
        os.setpriority(os.PRIO_PROCESS, 0, WORKER_NICE)
    cache = Path(sys.argv[1])
    artifact = load_artifact(sys.stdin.buffer.read())
    json.dump(make(artifact, cache), sys.stdout)


if __name__ == "__main__":
    main()
