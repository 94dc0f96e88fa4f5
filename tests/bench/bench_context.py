"""Saved context (warm start): snapshot, save and load + restore of 10,000 variables.

Run with `python -m tests.bench.bench_context`. It prints figures and asserts nothing
about time (machines are shared and noisy); the best of several rounds is the one least
disturbed by other work.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.code.code_image import CodeImage, VariablePath
from runtime.code.intrinsics import SystemView
from runtime.context import Context, ContextInvalid, encode_context, load_context, save_context
from runtime.context_snapshot import restore, snapshot

SCALARS, TIMERS, POINTS, SAMPLES = 2_399, 100, 1_000, 2_000  # and the loop counter
SCALAR_TYPES = ("INT", "DINT", "LREAL", "BOOL", "REAL", "TIME", "STRING[16]", "ULINT")


def ten_thousand_variables() -> str:
    """A program and globals of exactly 10,000 elementary variables: scalars of every common
    type, TON instances, an array of structs and a REAL array, all away from zero."""
    declarations = []
    for n in range(SCALARS):
        kind = SCALAR_TYPES[n % len(SCALAR_TYPES)]
        initial = {
            "BOOL": "TRUE",
            "LREAL": f"{n}.25",
            "REAL": f"{n}.5",
            "TIME": f"T#{n}ms",
            "STRING[16]": f"'text {n}'",
        }.get(kind, str(n))
        declarations.append(f"  v{n} : {kind} := {initial};")
    declarations += [f"  t{n} : TON;" for n in range(TIMERS)]
    timer_calls = [f"t{n}(IN := TRUE, PT := T#1h);" for n in range(TIMERS)]
    return "\n".join(
        [
            "TYPE Point : STRUCT x, y : REAL; n : DINT; ok : BOOL; name : STRING[16]; "
            "END_STRUCT; END_TYPE",
            f"VAR_GLOBAL points : ARRAY[1..{POINTS}] OF Point; END_VAR",
            "PROGRAM Bench",
            "VAR",
            *declarations,
            f"  samples : ARRAY[1..{SAMPLES}] OF LREAL;",
            "  i : DINT;",
            "END_VAR",
            f"FOR i := 1 TO {POINTS} DO",
            "  points[i].x := DINT_TO_REAL(i) / 7.0; points[i].y := -DINT_TO_REAL(i);",
            "  points[i].n := i * 1000; points[i].ok := i MOD 2 = 0; points[i].name := 'p';",
            "END_FOR;",
            f"FOR i := 1 TO {SAMPLES} DO samples[i] := DINT_TO_LREAL(i) / 3.0; END_FOR;",
            *timer_calls,
            "END_PROGRAM",
            "",
        ]
    )


def _count(paths: list[VariablePath], owner: Any) -> int:
    """Elementary variables: an array of elementary values counts each element."""
    total = 0
    for path in paths:
        value = owner
        for accessor in path.attrs:
            value = value[accessor] if isinstance(accessor, int) else getattr(value, accessor)
        total += len(value) if isinstance(value, list) else 1
    return total


def _best_ms(action: Callable[[], object], rounds: int) -> tuple[float, float]:
    """Best and median of `rounds` runs, in milliseconds."""
    samples = []
    for _ in range(rounds):
        started = time.perf_counter()
        action()
        samples.append((time.perf_counter() - started) * 1e3)
    return min(samples), statistics.median(samples)


def main(rounds: int = 20) -> None:
    result = compile_sources([SourceFile("bench_context.st", ten_thousand_variables())])
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    artifact = result.artifact
    system = SystemView(now_ns=1_000_000_000)
    image = CodeImage(artifact, system)
    program = image.new_instance("Bench")
    program()  # fills the arrays and starts the timers
    variables = _count(image.variable_paths("Bench", "Bench"), program)
    variables += _count(image.global_paths(), image.globals)

    def context() -> Context:
        return Context(
            signature=artifact.crc,
            saved_ns=time.time_ns(),
            resource={},
            programs={"Bench": {"state": "RUN", "time_ns": 0, "values": snapshot(program)}},
            globals=snapshot(image.globals),
        )

    best, median = _best_ms(context, rounds)
    size = len(encode_context(context()))
    print(
        f"context of {variables:,} variables: snapshot {best:.1f} ms "
        f"(median {median:.1f}); file {size / 1024:,.0f} KiB"
    )
    best, median = _best_ms(lambda: encode_context(context()), rounds)
    print(
        f"context: snapshot + encode (canonical JSON, SHA-256) {best:.1f} ms (median {median:.1f})"
    )

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "context"
        saved = context()
        best, median = _best_ms(lambda: save_context(path, saved), rounds)
        print(f"context: save_context (encode, write, fsync) {best:.1f} ms (median {median:.1f})")
        best, median = _best_ms(lambda: load_context(path, artifact.crc), rounds)
        print(f"context: load_context (read, SHA-256, parse) {best:.1f} ms (median {median:.1f})")
        loaded = load_context(path, artifact.crc)
    assert not isinstance(loaded, ContextInvalid), loaded

    # restore needs fresh instances: made beforehand, so that only restoring is timed
    targets = []
    for _ in range(rounds):
        fresh = CodeImage(artifact, SystemView())
        targets.append((fresh.new_instance("Bench"), fresh.globals))
    remaining = iter(targets)

    def restore_one() -> None:
        instance, globals_instance = next(remaining)
        restore(instance, loaded.programs["Bench"]["values"])
        restore(globals_instance, loaded.globals)

    best, median = _best_ms(restore_one, rounds)
    print(f"context: restore into fresh instances {best:.1f} ms (median {median:.1f})")


if __name__ == "__main__":
    main()
