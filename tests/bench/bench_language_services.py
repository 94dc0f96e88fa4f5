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
import re
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
# a statement that assigns a name; a variable declared (`name : TYPE`, maybe `:= value`)
_STATEMENT = re.compile(r"\s*[A-Za-z_][A-Za-z0-9_.\[\]]*\s*:=")
_DECLARATION = re.compile(r"\s*[A-Za-z_][A-Za-z0-9_]*\s*:\s*[A-Za-z]")


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
    """First analyses, then ~50 keystrokes in the name a statement assigns and ~20 in the
    name a declaration declares (which checks the whole project again): a character typed
    and deleted, each followed by the file's diagnostics as an editor asks for them."""
    first = _timed(lambda: LanguageProject({file: text}).analysis())
    second = _timed(lambda: LanguageProject({file: text}).analysis())
    full = _timed(lambda: analyse({file: text}))
    project = LanguageProject({file: text})
    project.analysis()
    rng = random.Random(2026)
    lines = text.splitlines(keepends=True)
    starts = [sum(len(line) for line in lines[:i]) for i in range(len(lines))]
    places = {
        "in a body": [
            starts[i] + line.index(":=") - 1
            for i, line in enumerate(lines)
            if _STATEMENT.match(line) and line.rstrip().endswith(";")
        ],
        "in a declaration": [
            starts[i] + line.index(":") - 1
            for i, line in enumerate(lines)
            if _DECLARATION.match(line)
        ],
    }
    figures = []
    for where, count in (("in a body", KEYSTROKES), ("in a declaration", KEYSTROKES * 2 // 5)):
        waits: list[float] = []
        work: list[float] = []  # the process's CPU time: the wait less what other loads take
        for _ in range(count):
            at = rng.choice(places[where])
            for version in (text[:at] + "x" + text[at:], text):
                project.set_text(file, version)
                started = time.process_time()
                waits.append(_timed(lambda: project.diagnostics(file)) * 1e3)
                work.append((time.process_time() - started) * 1e3)
        figures.append(
            f"{where} p50 {statistics.median(waits):.0f} ms, "
            f"p95 {_percentile(waits, 0.95):.0f} ms (CPU p50 {statistics.median(work):.0f} ms, "
            f"p95 {_percentile(work, 0.95):.0f} ms; {len(waits)} edits)"
        )
    print(
        f"language services, {label} ({len(lines):,} lines): diagnostics after a keystroke "
        f"{'; '.join(figures)}; first analysis {first * 1e3:.0f} ms, in a second session "
        f"{second * 1e3:.0f} ms; a full analysis from scratch {full * 1e3:.0f} ms"
    )


def bench_completion(label: str, file: str, text: str) -> None:
    """Completion as one types: on ~10 new lines before statements of the file, the name
    the statement assigns typed letter by letter (or `delay.` where the file has timers
    called so), a completion request after each keystroke, the line then deleted again.
    The wait for each list, over the analysis of the text as typed (which the diagnostics
    made already)."""
    project = LanguageProject({file: text})
    complete(project.analysis(), file, 1, 1)  # the file as opened
    rng = random.Random(2026)
    lines = text.splitlines(keepends=True)
    statements = [i for i, line in enumerate(lines) if ":=" in line and line.rstrip().endswith(";")]
    waits: list[float] = []
    offered = 0
    while len(waits) < KEYSTROKES:
        row = rng.choice(statements)
        assigned = lines[row].split(":=")[0].strip()
        word = "delay." if "delay" in text and len(waits) % 2 else assigned[:6]
        for typed in range(len(word) + 1):  # nothing yet: everything in scope is offered
            project.set_text(file, "".join([*lines[:row], word[:typed] + "\n", *lines[row:]]))
            analysis = project.analysis()
            started = time.perf_counter()
            offered += len(complete(analysis, file, row + 1, typed + 1))
            waits.append((time.perf_counter() - started) * 1e3)
        project.set_text(file, text)
    print(
        f"language services, {label}: completion while typing p50 "
        f"{statistics.median(waits):.1f} ms, p95 {_percentile(waits, 0.95):.1f} ms "
        f"({len(waits)} requests, {offered / len(waits):.0f} items each on average)"
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
