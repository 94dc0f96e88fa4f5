"""`padt exec`: compile one ST file and run its entry once, printing what `printf` prints.

This is how ST test programs from other compilers' suites run here: the entry is a
FUNCTION (`main` by default), called once, or a PROGRAM, run for one cycle; on the native
tier, the bodies of programs and function blocks that translate run as C, built before the
entry runs (a FUNCTION's own body stays Python, as on a runtime).
"""

from __future__ import annotations

import sys
from pathlib import Path

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import read_source
from backend.engineering.tiers import left_as_python
from runtime.code.code_image import CodeImage
from runtime.code.intrinsics import ProgramFault, SystemView
from runtime.code.native.tier import NativeTier
from runtime.contract.artifact import ArtifactError


def run_entry(path: Path, entry: str = "main", native: NativeTier | None = None) -> int:
    """Exit code: 0 after a run, 1 on compile errors, 2 on a run-time fault. On the native
    tier where `native` is given, all as Python otherwise."""
    source = read_source(path)
    result = compile_sources([source], programs=[])
    for diagnostic in result.diagnostics:
        print(diagnostic, file=sys.stderr)
    artifact = result.artifact
    if artifact is None:
        return 1
    pous = {pou.name.upper(): pou for pou in artifact.pous}
    target = pous.get(entry.upper())
    if target is None or target.kind not in ("FUNCTION", "PROGRAM"):
        print(f"{path}: no FUNCTION or PROGRAM '{entry}'", file=sys.stderr)
        return 1
    try:
        image = CodeImage(artifact, SystemView(), native=native)
    except ArtifactError as exc:  # the check of generated code before it is compiled
        print(f"{path}: the compiled code does not load: {exc}", file=sys.stderr)
        return 2
    for line in left_as_python(image.tier_up(wait=True)):
        print(f"padt exec: {line}", file=sys.stderr)
    for pou in artifact.pous:  # programs are callable from ST by name: `prog();`
        if pou.kind == "PROGRAM":
            image.register_program(pou.name, image.new_instance(pou.name))
    try:
        if target.kind == "FUNCTION":
            image.function(target.name)()
        else:
            image.program_instance(target.name)()
    except (ProgramFault, ArithmeticError, RecursionError) as exc:
        sys.stdout.flush()
        print(f"{path}: run-time error: {exc}", file=sys.stderr)
        return 2
    sys.stdout.flush()
    return 0
