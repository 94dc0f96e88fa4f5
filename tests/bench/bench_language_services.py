"""Language-service benchmarks: how long an editor waits for the diagnostics after one
keystroke (a character typed, then deleted) in a 2,000-line file and in OSCAT, how long
the first analysis of a project takes, for the first session and for a second one (which
shares the first one's parses), and how long a completion request takes (goal: p95 under
50 ms).

"OSCAT BASIC" is its largest chapter, BASIC_3.33-12_Time_and_Date (1,478 lines): each
chapter is complete in itself and repeats POUs of the others, so together they do not
compile; OSCAT BUILDING (4,888 lines, one file) is measured beside it.

Run with `python -m tests.bench.bench_language_services`. It prints figures and asserts
nothing about time (machines are shared and noisy).
"""

from __future__ import annotations

import random
import statistics
import time
from collections.abc import Callable
from pathlib import Path

from backend.compiler.language.analysis import analyse
from backend.compiler.language.completion import complete
from backend.compiler.language.language_project import LanguageProject

REPO = Path(__file__).resolve().parents[2]
OSCAT = REPO.parent / "shared" / "corpus" / "oscat" / "st"
KEYSTROKES = 50


def two_thousand_lines(blocks: int = 55) -> str:
    """A file of `blocks` function blocks of 37 lines each, in the style of a plant's code:
    declarations, timers, IF, CASE and FOR, calls of the blocks before."""
    parts = []
    for n in range(blocks):
        called = "inner(start := start, setpoint := output, mode := mode);\n" if n % 8 else "\n"
        inner = f"  inner : Block{n - 1};\n" if n % 8 else "  unused : INT;\n"
        parts.append(
            f"FUNCTION_BLOCK Block{n}\n"
            "VAR_INPUT\n  start : BOOL;\n  setpoint : REAL;\n  mode : INT;\nEND_VAR\n"
            "VAR_OUTPUT\n  running : BOOL;\n  output : REAL;\n  count : DINT;\nEND_VAR\n"
            f"VAR\n  delay : TON;\n  values : ARRAY[1..10] OF REAL;\n  i : INT;\n{inner}END_VAR\n"
            "delay(IN := start, PT := T#2s);\n"
            "running := delay.Q AND mode > 0;\n"
            "IF running THEN\n"
            "    output := setpoint * 0.5 + values[1];\n"
            "    count := count + 1;\n"
            "ELSIF mode = 2 THEN\n"
            "    output := 0.0;\n"
            "END_IF;\n"
            "CASE mode OF\n"
            "    1: output := output + 1.0;\n"
            "    2, 3: output := output - 1.0;\n"
            "ELSE\n"
            "    output := setpoint;\n"
            "END_CASE;\n"
            "FOR i := 1 TO 10 DO\n"
            "    values[i] := output * INT_TO_REAL(i);\n"
            "END_FOR;\n"
            f"{called}"
            "END_FUNCTION_BLOCK\n\n"
        )
    return "".join(parts)


def _percentile(samples: list[float], fraction: float) -> float:
    ordered = sorted(samples)
    return ordered[min(len(ordered) - 1, int(len(ordered) * fraction))]


def _timed(action: Callable[[], object]) -> float:
    started = time.perf_counter()
    action()
    return time.perf_counter() - started


def bench_keystrokes(label: str, file: str, text: str) -> None:
    """First analyses, then ~50 keystrokes in statement lines of the file: a character typed
    and deleted, each followed by the file's diagnostics as an editor asks for them."""
    first = _timed(lambda: LanguageProject({file: text}).analysis())
    second = _timed(lambda: LanguageProject({file: text}).analysis())
    full = _timed(lambda: analyse({file: text}))
    project = LanguageProject({file: text})
    project.analysis()
    rng = random.Random(2026)
    lines = text.splitlines(keepends=True)
    starts = [sum(len(line) for line in lines[:i]) for i in range(len(lines))]
    statements = [i for i, line in enumerate(lines) if ":=" in line and line.rstrip().endswith(";")]
    waits: list[float] = []
    for _ in range(KEYSTROKES):
        row = rng.choice(statements)
        at = starts[row] + lines[row].index(":=") - 1  # within the name assigned
        typed = text[:at] + "x" + text[at:]
        for version in (typed, text):
            project.set_text(file, version)
            waits.append(_timed(lambda: project.diagnostics(file)) * 1e3)
    print(
        f"language services, {label} ({len(lines):,} lines): diagnostics after a keystroke "
        f"p50 {statistics.median(waits):.0f} ms, p95 {_percentile(waits, 0.95):.0f} ms "
        f"({len(waits)} edits); first analysis {first * 1e3:.0f} ms, in a second session "
        f"{second * 1e3:.0f} ms; a full analysis from scratch {full * 1e3:.0f} ms"
    )


def bench_completion(label: str, file: str, text: str) -> None:
    """~50 completion requests, each on a line just typed before a statement of the file:
    the first two letters of the name the statement assigns, nothing yet (everything in
    scope is offered), or `delay.` where the file has timers called so: the wait for the
    list, over the analysis of the text as typed (which the diagnostics made already)."""
    project = LanguageProject({file: text})
    project.analysis()
    rng = random.Random(2026)
    lines = text.splitlines(keepends=True)
    statements = [i for i, line in enumerate(lines) if ":=" in line and line.rstrip().endswith(";")]
    waits: list[float] = []
    offered = 0
    for n in range(KEYSTROKES):
        row = rng.choice(statements)
        assigned = lines[row].split(":=")[0].strip()
        variants = (assigned[:2], "", "delay." if "delay" in text else assigned[:1])
        typed_line = variants[n % 3]
        typed = "".join([*lines[:row], typed_line + "\n", *lines[row:]])
        project.set_text(file, typed)
        analysis = project.analysis()
        started = time.perf_counter()
        items = complete(analysis, file, row + 1, len(typed_line) + 1)
        waits.append((time.perf_counter() - started) * 1e3)
        offered += len(items)
    print(
        f"language services, {label}: completion p50 {statistics.median(waits):.1f} ms, "
        f"p95 {_percentile(waits, 0.95):.1f} ms ({len(waits)} requests, "
        f"{offered / len(waits):.0f} items each on average)"
    )


def main() -> None:
    bench_keystrokes("a 2,000-line file", "plant.st", two_thousand_lines())
    bench_completion("a 2,000-line file", "plant.st", two_thousand_lines())
    if not OSCAT.is_dir():
        print(f"OSCAT corpus absent ({OSCAT}): OSCAT language-service figures skipped")
    else:
        for chapter, label in (
            ("BASIC_3.33-12_Time_and_Date.st", "OSCAT BASIC (its largest chapter)"),
            ("BUILDING_1.0.st", "OSCAT BUILDING"),
        ):
            text = (OSCAT / chapter).read_text(encoding="utf-8", errors="replace")
            bench_keystrokes(label, chapter, text)
            bench_completion(label, chapter, text)


if __name__ == "__main__":
    main()
