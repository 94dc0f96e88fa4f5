"""Which lines of generated code ran: a trace function (sys.settrace; Python 3.11 has no
sys.monitoring) counts the line events of the generated code of the POUs measured and of
nothing else, so the runtime's own code runs untraced."""

from __future__ import annotations

import sys
from collections import Counter
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from types import FrameType
from typing import Any

from backend.compiler.test_functions import is_test_file
from runtime.code.code_image import CodeImage

# a frame's local trace function, as sys.settrace takes it
LocalTrace = Any


@dataclass
class LineHits:
    """Per code file name (`<PROGRAM Main>`), how often each line of its generated code
    ran. Worker processes each fill one; `merge` adds them up."""

    by_code: dict[str, Counter[int]] = field(default_factory=dict)

    def merge(self, other: LineHits) -> None:
        for name, counts in other.by_code.items():
            self.by_code.setdefault(name, Counter()).update(counts)


@dataclass
class CoverageMeter:
    """Counts the lines of the POUs of `files` (the project's and the libraries', not the
    tests' nor the standard library's) that run while `measuring`."""

    files: frozenset[str]
    hits: LineHits = field(default_factory=LineHits)

    @contextmanager
    def measuring(self, image: CodeImage) -> Iterator[None]:
        """Count the lines of `image`'s code that run in this thread meanwhile: the
        programs' cycles and what a test calls directly alike."""
        counters = {
            name: self.hits.by_code.setdefault(name, Counter())
            for name, unit in image.units.items()
            if unit.file in self.files
        }
        with _tracing(counters):
            yield


@contextmanager
def _tracing(counters: dict[str, Counter[int]]) -> Iterator[None]:
    def on_call(frame: FrameType, event: str, arg: object) -> LocalTrace:
        counts = counters.get(frame.f_code.co_filename)
        if counts is None:
            return None  # no line events for the runtime's code, nor for the tests'

        def on_line(frame: FrameType, event: str, arg: object) -> LocalTrace:
            if event == "line":
                counts[frame.f_lineno] += 1
            return on_line

        return on_line

    previous = sys.gettrace()
    sys.settrace(on_call)
    try:
        yield
    finally:
        sys.settrace(previous)


def measured_files(names: Iterable[str]) -> frozenset[str]:
    """The source files whose POUs count: every one but the test files."""
    return frozenset(name for name in names if not is_test_file(name))
