"""rusty's lit tests: every runnable file through `padt exec`, its output matched against its
`// CHECK:` lines; the expect-error files must be refused. Each runnable file with a
function block or a program runs on both tiers, and the native tier (their bodies as C)
must print, exit and fail exactly as Python; in a file of FUNCTIONs alone the native tier
has nothing to build and runs the very same Python. Each command is a process of its own,
forked from one that imported the command line once (tests/support/forked_cli.py). Known
failures are listed, each with its reason, in tests/compiler/corpus/rusty_known_failures.tsv."""

from __future__ import annotations

import re
from pathlib import Path

from runtime.code.native.tier import NativeTier
from tests.support.corpus_paths import corpus_dir, known_failures
from tests.support.filecheck import match_output, parse_checks
from tests.support.forked_cli import Finished, run_commands

TIMEOUT_S = 30
REQUIRED_PASS_RATE = 0.90
# what the native tier builds: the bodies of function blocks and programs
_BODIES = re.compile(r"^\s*(FUNCTION_BLOCK|PROGRAM)\b", re.IGNORECASE | re.MULTILINE)


def ran(path: Path, run: Finished) -> tuple[bool, str]:
    """`padt exec FILE`: whether it printed what the file's CHECK lines want."""
    if run.returncode is None:
        return False, f"no result within {TIMEOUT_S} s"
    stderr = run.stderr.decode("utf-8", "replace")
    if "Traceback" in stderr:
        return False, f"traceback: {stderr.strip().splitlines()[-1]}"
    if run.returncode != 0:
        return False, f"exit {run.returncode}: {stderr.strip()[:300]}"
    # STRINGs are bytes: print them as lit does, invalid UTF-8 shown as U+FFFD
    output = run.stdout.decode("utf-8", "replace")
    result = match_output(parse_checks(path.read_text(encoding="utf-8")), output)
    return result.ok, result.message


def refused(run: Finished) -> tuple[bool, str]:
    """`padt compile FILE` of an expect-error file: whether it was refused with an error."""
    stdout, stderr = (s.decode("utf-8", "replace") for s in (run.stdout, run.stderr))
    if run.returncode is None:
        return False, f"no result within {TIMEOUT_S} s"
    if "Traceback" in stderr:
        return False, "traceback"
    return run.returncode == 1 and ": error: " in stdout, stdout[-300:]


def on_the_tier(run: Finished) -> tuple[int | None, bytes, list[bytes]]:
    """What a user of either tier sees alike: the exit, the output, the errors but the
    lines that say which bodies run as Python."""
    said = [line for line in run.stderr.splitlines() if not line.startswith(b"padt exec: ")]
    return run.returncode, run.stdout, said


def test_rusty_lit_corpus(native_tier: NativeTier) -> None:
    root = corpus_dir("rusty-lit")
    files = sorted(root.rglob("*.st"))
    runnable = [f for f in files if "expect-error" not in f.parts]
    must_fail = [f for f in files if "expect-error" in f.parts]
    built = [f for f in runnable if _BODIES.search(f.read_text(encoding="utf-8"))]
    commands = [["exec", str(f), "--tier", "python"] for f in runnable]
    commands += [["exec", str(f), "--tier", "native"] for f in built]
    commands += [["compile", str(f)] for f in must_fail]
    runs = run_commands(commands, TIMEOUT_S)
    python = dict(zip(runnable, runs, strict=False))
    native = dict(zip(built, runs[len(runnable) :], strict=False))
    results = {f: ran(f, python[f]) for f in runnable}
    results.update(
        (f, refused(run))
        for f, run in zip(must_fail, runs[len(runnable) + len(built) :], strict=True)
    )
    assert len(built) >= 30, f"only {len(built)} files with a block or a program"
    unlike = [
        str(f.relative_to(root)) for f in built if on_the_tier(python[f]) != on_the_tier(native[f])
    ]
    assert not unlike, f"the native tier runs these otherwise than Python: {unlike}"
    known = known_failures("rusty_known_failures.tsv")
    failing = {str(p.relative_to(root)): why for p, (ok, why) in results.items() if not ok}

    unexplained = {p: why for p, why in failing.items() if p not in known}
    now_passing = sorted(p for p in known if p not in failing)
    passed = sum(1 for p in runnable if results[p][0])
    rate = passed / len(runnable)
    print(f"rusty-lit: {passed}/{len(runnable)} runnable files pass ({rate:.1%})")
    assert not unexplained, "failures missing from the known-failures file:\n" + "\n".join(
        f"{p}\t{why}" for p, why in sorted(unexplained.items())
    )
    assert not now_passing, f"these pass now; remove them from the known failures: {now_passing}"
    assert rate >= REQUIRED_PASS_RATE
