"""Coverage as ST sees it: per file and POU, how often each statement line ran and how
often each branch was taken (docs/testing.md, "Coverage").

A line's hits are those of the first line of code generated for it: that line runs once
each time the first statement written on the line runs (an IF's ELSIF tests and a loop's
passes are later lines of the same ST line). The branches come from the compiler's syntax
tree: the ways of an IF and a CASE, the bodies of loops, the steps and transitions of a
chart."""

from __future__ import annotations

import ast as python
from collections import Counter
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.source import SourceFile
from backend.engineering.testing.coverage.measure import LineHits
from runtime.code.fault_location import code_filename
from runtime.contract.artifact import Artifact, PouCode


@dataclass(frozen=True)
class Branch:
    line: int  # where the decision is written: IF, CASE, loop, step, transition
    label: str  # which way: `THEN`, `ELSIF (line 5)`, `implicit ELSE`, `loop body`...
    taken: int  # how often


@dataclass(frozen=True)
class Figures:
    statements: int
    statements_covered: int
    branches: int
    branches_covered: int

    def __add__(self, other: Figures) -> Figures:
        return Figures(
            self.statements + other.statements,
            self.statements_covered + other.statements_covered,
            self.branches + other.branches,
            self.branches_covered + other.branches_covered,
        )

    @property
    def line_rate(self) -> float:
        """Covered statements as a fraction; 1 without any (nothing left to cover)."""
        return self.statements_covered / self.statements if self.statements else 1.0

    @property
    def branch_rate(self) -> float:
        return self.branches_covered / self.branches if self.branches else 1.0


NO_FIGURES = Figures(0, 0, 0, 0)


@dataclass(frozen=True)
class PouCoverage:
    name: str
    kind: str  # PROGRAM, FUNCTION_BLOCK, FUNCTION
    file: str
    lines: tuple[tuple[int, int], ...]  # (line, hits) of every line with a statement, by line
    branches: tuple[Branch, ...]  # by line, then as written

    @property
    def figures(self) -> Figures:
        return Figures(
            len(self.lines),
            sum(hits > 0 for _, hits in self.lines),
            len(self.branches),
            sum(b.taken > 0 for b in self.branches),
        )


@dataclass(frozen=True)
class FileCoverage:
    file: str  # by its path in the project
    text: str
    pous: tuple[PouCoverage, ...]  # by their first statement line

    @property
    def lines(self) -> dict[int, int]:
        return {line: hits for pou in self.pous for line, hits in pou.lines}

    def branches_by_line(self) -> dict[int, list[Branch]]:
        found: dict[int, list[Branch]] = {}
        for pou in self.pous:
            for branch in pou.branches:
                found.setdefault(branch.line, []).append(branch)
        return found

    @property
    def figures(self) -> Figures:
        return sum((pou.figures for pou in self.pous), NO_FIGURES)


@dataclass(frozen=True)
class Coverage:
    files: tuple[FileCoverage, ...]  # by path

    @property
    def figures(self) -> Figures:
        return sum((file.figures for file in self.files), NO_FIGURES)

    def as_json(self) -> dict[str, Any]:
        """Per file its lines' hits and its branches, for a client shading an editor."""
        return {
            "files": {
                file.file: {
                    "lines": {str(line): hits for line, hits in sorted(file.lines.items())},
                    "branches": [
                        {"line": b.line, "label": b.label, "taken": b.taken}
                        for pou in file.pous
                        for b in pou.branches
                    ],
                    "pous": [
                        {"name": pou.name, "kind": pou.kind, "figures": _figures_json(pou.figures)}
                        for pou in file.pous
                    ],
                    "figures": _figures_json(file.figures),
                }
                for file in self.files
            },
            "figures": _figures_json(self.figures),
        }


def _figures_json(figures: Figures) -> dict[str, int]:
    return {
        "statements": figures.statements,
        "statements_covered": figures.statements_covered,
        "branches": figures.branches,
        "branches_covered": figures.branches_covered,
    }


def coverage_of(
    artifact: Artifact,
    syntax: Iterable[ast.SourceUnit],
    sources: Iterable[SourceFile],
    files: frozenset[str],
    hits: LineHits,
) -> Coverage:
    """The coverage of the POUs of `files` by the line counts `hits` of the artifact's
    code; `syntax` is the parse the artifact was compiled from, `sources` its files."""
    declared = {(key(pou.name), pou.pos.file): pou for unit in syntax for pou in unit.pous}
    texts = {source.name: source.text for source in sources if source.name in files}
    by_file: dict[str, list[PouCoverage]] = {}
    for unit in artifact.pous:
        pou = declared.get((key(unit.name), unit.file))
        if pou is None or unit.file not in files:
            continue
        counts = hits.by_code.get(code_filename(unit), Counter())
        by_file.setdefault(unit.file, []).append(_pou_coverage(unit, pou, counts))
    return Coverage(
        tuple(
            FileCoverage(
                file,
                texts.get(file, ""),
                tuple(sorted(pous, key=lambda p: (p.lines[0][0] if p.lines else 0, p.name))),
            )
            for file, pous in sorted(by_file.items())
        )
    )


def _pou_coverage(unit: PouCode, pou: ast.Pou, counts: Counter[int]) -> PouCoverage:
    first_code_line: dict[int, int] = {}  # ST line -> its first generated line (1-based)
    for index, line in enumerate(unit.st_lines):
        if line:
            first_code_line.setdefault(line, index + 1)
    line_hits = {line: counts[code] for line, code in first_code_line.items()}
    branches = _Branches(line_hits, _statement_starts(pou))
    for body in _bodies(pou):
        branches.walk(body)
    if pou.sfc is not None:
        fired = _fired_code_lines(unit, {t.pos.line for t in pou.sfc.transitions})
        for step in pou.sfc.steps:
            branches.add(step.pos.line, f"step {step.name} active", line_hits.get(step.pos.line, 0))
        for transition in pou.sfc.transitions:
            line = transition.pos.line
            code = fired.get(line)
            label = f"transition {', '.join(transition.sources)} to {', '.join(transition.targets)}"
            branches.add(line, f"{label} fired", counts[code] if code is not None else 0)
    # a decision the compiler made no code for (`IF FALSE THEN`) has no line to show it at
    kept = [b for b in branches.found if b.line in line_hits]
    ordered = sorted(kept, key=lambda b: b.line)  # stable: as written within a line
    return PouCoverage(
        unit.name, unit.kind, unit.file, tuple(sorted(line_hits.items())), tuple(ordered)
    )


def _bodies(pou: ast.Pou) -> Iterator[tuple[ast.Statement, ...]]:
    """The statement lists of a POU: its body, methods, property accessors and actions."""
    yield pou.body
    for method in pou.methods:
        yield method.body
    for prop in pou.properties:
        for accessor in prop.accessors:
            yield accessor.body
    if pou.sfc is not None:
        for action in pou.sfc.actions:
            yield action.body


def _children(statement: ast.Statement) -> Iterator[tuple[ast.Statement, ...]]:
    match statement:
        case ast.If(branches=ways, orelse=orelse):
            for _, body in ways:
                yield body
            yield orelse
        case ast.Case(branches=ways, orelse=orelse):
            for _, body in ways:
                yield body
            yield orelse
        case ast.While(body=body) | ast.Repeat(body=body) | ast.For(body=body):
            yield body


def _statement_starts(pou: ast.Pou) -> dict[int, int]:
    """Per line, the column of the first statement written on it."""
    starts: dict[int, int] = {}

    def visit(body: tuple[ast.Statement, ...]) -> None:
        for statement in body:
            line, col = statement.pos.line, statement.pos.col
            starts[line] = min(col, starts.get(line, col))
            for child in _children(statement):
                visit(child)

    for body in _bodies(pou):
        visit(body)
    return starts


class _Branches:
    """The branches of one POU's statements, with how often each was taken."""

    def __init__(self, hits: dict[int, int], starts: dict[int, int]) -> None:
        self.hits = hits  # ST line -> runs of its first statement
        self.starts = starts
        self.found: list[Branch] = []

    def add(self, line: int, label: str, taken: int) -> None:
        self.found.append(Branch(line, label, taken))

    def walk(self, body: tuple[ast.Statement, ...]) -> None:
        for statement in body:
            self._decision(statement)
            for child in _children(statement):
                self.walk(child)

    def _counted(self, statement: ast.Statement) -> int | None:
        """How often `statement` ran, when its line tells: it is the first statement
        written on its line (else the line's count is an earlier statement's)."""
        line = statement.pos.line
        if self.starts.get(line) != statement.pos.col:
            return None
        return self.hits.get(line, 0)

    def _decision(self, statement: ast.Statement) -> None:
        line = statement.pos.line
        match statement:
            case ast.If(branches=ways, orelse=orelse):
                labels = ["THEN"] + [f"ELSIF (line {c.pos.line})" for c, _ in ways[1:]]
                bodies = [body for _, body in ways]
                self._ways(statement, [*zip(labels, bodies, strict=True), ("ELSE", orelse)])
            case ast.Case(branches=ways, orelse=orelse):
                labelled = [(f"case (line {labels[0].pos.line})", body) for labels, body in ways]
                self._ways(statement, [*labelled, ("ELSE", orelse)])
            case ast.While(body=body) | ast.For(body=body) if body:
                taken = self._counted(body[0])
                if taken is not None:
                    self.add(line, "loop body", taken)
            case ast.Repeat(body=body) if body:
                # the body runs at least once; the branch is the UNTIL sending it round again
                passes, runs = self._counted(body[0]), self._counted(statement)
                if passes is not None and runs is not None:
                    self.add(line, "loop repeated", max(0, passes - runs))

    def _ways(
        self, statement: ast.Statement, ways: list[tuple[str, tuple[ast.Statement, ...]]]
    ) -> None:
        """The ways of an IF or a CASE; the one without statements (a missing ELSE) was
        taken as often as the decision ran and no other way did. A decision whose ways
        its lines cannot tell apart (more than one empty way, a way written on the line
        of another statement) is left out."""
        counts: list[int | None] = []  # per way, None: no statements
        for _, body in ways:
            count = self._counted(body[0]) if body else None
            if body and count is None:
                return
            counts.append(count)
        if counts.count(None) > 1:
            return
        remainder = 0
        if None in counts:
            runs = self._counted(statement)
            if runs is None:
                return
            remainder = max(0, runs - sum(c for c in counts if c is not None))
        for (label, _), count in zip(ways, counts, strict=True):
            if count is not None:
                self.add(statement.pos.line, label, count)
            else:
                empty = "implicit ELSE" if label == "ELSE" else f"{label} (empty)"
                self.add(statement.pos.line, empty, remainder)


def _fired_code_lines(unit: PouCode, transitions: set[int]) -> dict[int, int]:
    """Per transition line, the generated line that runs when the transition fires.

    The chart's code evaluates each transition into a flag, on the transition's line, and
    later clears the source steps under `if flag:` (code of no ST line): the first line
    under that test runs once per firing."""
    flags: dict[str, int] = {}
    fired: dict[int, int] = {}
    nodes = sorted(
        (
            n
            for n in python.walk(python.parse(unit.source))
            if isinstance(n, python.Assign | python.If)
        ),
        key=lambda n: n.lineno,
    )
    for node in nodes:
        st_line = unit.st_lines[node.lineno - 1]
        if isinstance(node, python.Assign):
            target = node.targets[0]
            first = st_line in transitions and st_line not in flags.values()
            if first and isinstance(target, python.Name):
                flags[target.id] = st_line
        elif isinstance(node.test, python.Name) and node.test.id in flags and st_line == 0:
            fired.setdefault(flags[node.test.id], node.body[0].lineno)
    return fired
