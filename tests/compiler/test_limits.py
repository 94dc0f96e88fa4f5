"""No source can kill or stall the compiler: pathological inputs, generated here, each end
in diagnostics, in a child process whose address space is capped at 1 GiB (so a compile
that needs more fails the test) and within the 10 s the hardening issue allows.
"""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass

from tests.conftest import REPO

MEMORY_CAP = 1 << 30
SECONDS = 10

# The child compiles what it reads on stdin, as one file, and prints one JSON line; it
# caps its own address space before importing the compiler.
CHILD = f"""
import json, resource, sys, time
resource.setrlimit(resource.RLIMIT_AS, ({MEMORY_CAP}, {MEMORY_CAP}))
from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
text = sys.stdin.read()
start = time.monotonic()
result = compile_sources([SourceFile("big.st", text)])
seconds = time.monotonic() - start
print(json.dumps({{"seconds": seconds, "diagnostics": [str(d) for d in result.diagnostics]}}))
"""


@dataclass(frozen=True)
class Outcome:
    seconds: float
    diagnostics: list[str]

    def codes(self) -> set[str]:
        return {d.rsplit("[", 1)[-1].rstrip("]") for d in self.diagnostics}


def compile_capped(text: str) -> Outcome:
    """Compile `text` in a capped child; any traceback or crash fails the test."""
    run = subprocess.run(
        [sys.executable, "-c", CHILD],
        input=text,
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=60,
    )
    assert run.returncode == 0 and "Traceback" not in run.stderr, run.stderr[-2000:]
    found = json.loads(run.stdout)
    outcome = Outcome(found["seconds"], found["diagnostics"])
    assert outcome.seconds < SECONDS, outcome
    return outcome


def program(body: str, declarations: str = "x : DINT;") -> str:
    return f"PROGRAM P\nVAR {declarations} END_VAR\n{body}\nEND_PROGRAM\n"


# ---- comments and literals cost memory in proportion to their size, not more ----------------


def test_a_50_mb_comment_compiles_in_little_memory() -> None:
    for opening, closing in (("(*", "*)"), ("/*", "*/"), ("{{", "}}")):
        outcome = compile_capped(opening + "x\n" * 25_000_000 + closing + program("x := 1;"))
        assert "E0001" not in outcome.codes(), outcome


def test_a_string_literal_of_a_million_escapes_lexes_in_little_memory() -> None:
    outcome = compile_capped(program("s := '" + "$$" * 1_000_000 + "';", "s : STRING;"))
    assert "E0001" not in outcome.codes(), outcome
