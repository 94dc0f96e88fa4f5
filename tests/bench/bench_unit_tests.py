"""`padt test` on 1,000 small tests: a generated project (one program, 10 suites of 100 test
methods, each a few asserts after RUN_CYCLES(1..5)), the whole command timed as a user waits
for it (start, compile, the native build, the tests, the report): serial and with `-j 2`, on
both tiers and on the Python tier alone; the native build from an empty cache and from a
warm one; what each test costs; and what `--coverage summary` adds.

Run with `python -m tests.bench.bench_unit_tests`. Prints figures; asserts nothing about
time (machines are shared and noisy)."""

from __future__ import annotations

import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

SUITES = 10
TESTS_PER_SUITE = 100
GOAL_S = 10.0

PADT_TOML = """[project]
name = "bench"
[resource]
name = "R"
target_cycle_ms = 100
[[resource.program]]
name = "Counter"
pou = "Counter"
id = 1
priority = 1
"""

PROGRAM = """VAR_GLOBAL
  start : BOOL;
  step : DINT := 1;
END_VAR
PROGRAM Counter
VAR
  count : DINT;
  total : DINT;
  running : BOOL;
END_VAR
IF start THEN
  count := count + 1;
  total := total + step;
END_IF;
running := start;
END_PROGRAM
"""


def _suite(number: int) -> str:
    methods = []
    for test in range(TESTS_PER_SUITE):
        cycles, step = test % 5 + 1, test % 7 + 1
        methods.append(
            f"METHOD Test{test:03d}\n"
            f"start := TRUE;\nstep := {step};\n"
            f"RUN_CYCLES({cycles});\n"
            f"ASSERT_EQUAL(DINT#{cycles}, Counter.count, 'cycles counted');\n"
            f"ASSERT_EQUAL(DINT#{cycles * step}, Counter.total, 'steps added');\n"
            "ASSERT_TRUE(Counter.running, 'running');\n"
            "END_METHOD\n"
        )
    return f"FUNCTION_BLOCK Suite{number:02d}\n{''.join(methods)}END_FUNCTION_BLOCK\n"


def _project(folder: Path) -> None:
    (folder / "test").mkdir(parents=True)
    (folder / "padt.toml").write_text(PADT_TOML)
    (folder / "counter.st").write_text(PROGRAM)
    for number in range(SUITES):
        (folder / "test" / f"suite{number:02d}_test.st").write_text(_suite(number))


@dataclass(frozen=True)
class Timing:
    wall_s: float  # the whole command, as a user waits for it
    cpu_s: float  # its processes' CPU time (the workers' too): what a loaded machine hides
    tests_s: float  # the tests' own time from the summary, summed over the workers


def _padt_test(folder: Path, cache: Path, *options: str) -> Timing:
    env = {**os.environ, "XDG_CACHE_HOME": str(cache)}
    command = [sys.executable, "-m", "padt.cli", "test", str(folder), *options]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    run = subprocess.run(command, capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    # the summary line (a coverage table may follow it)
    found = re.search(r"^(\d+) passed of \d+ tests .* in ([0-9.]+) s$", run.stdout, re.M)
    if run.returncode != 0 or found is None or found[1] != str(SUITES * TESTS_PER_SUITE):
        raise RuntimeError(f"padt test {' '.join(options)}: {run.stdout[-500:]}{run.stderr}")
    return Timing(wall, cpu, float(found[2]))


def _line(label: str, timing: Timing) -> str:
    per_test = timing.tests_s / (SUITES * TESTS_PER_SUITE) * 1e3
    goal = "within" if timing.wall_s < GOAL_S else "OVER"
    return (
        f"  {label}: {timing.wall_s:.1f} s ({goal} the {GOAL_S:.0f} s goal), "
        f"CPU {timing.cpu_s:.1f} s; the tests {timing.tests_s:.2f} s, {per_test:.2f} ms a test"
    )


def main() -> None:
    print(f"padt test, {SUITES * TESTS_PER_SUITE} tests ({SUITES} suites of {TESTS_PER_SUITE}):")
    with tempfile.TemporaryDirectory() as base:
        folder, cache = Path(base) / "bench", Path(base) / "cache"
        _project(folder)
        print(_line("both tiers, serial, empty native cache", _padt_test(folder, cache)))
        print(_line("both tiers, serial", _padt_test(folder, cache)))
        print(_line("both tiers, -j 2", _padt_test(folder, cache, "-j", "2")))
        python = _padt_test(folder, cache, "--tier", "python")
        print(_line("Python tier, serial", python))
        print(_line("Python tier, -j 2", _padt_test(folder, cache, "--tier", "python", "-j", "2")))
        covered = _padt_test(folder, cache, "--tier", "python", "--coverage", "summary")
        print(_line("Python tier, serial, --coverage summary", covered))
        print(
            f"  --coverage summary against none: {covered.wall_s - python.wall_s:+.1f} s, "
            f"CPU {covered.cpu_s - python.cpu_s:+.1f} s, "
            f"the tests {covered.tests_s / max(python.tests_s, 1e-9):.1f} times as long"
        )


if __name__ == "__main__":
    main()
