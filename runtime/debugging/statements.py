"""Where the ST statements are in the generated code: the artifact's line table of each
unit (`PouCode.st_lines`) read both ways."""

from __future__ import annotations

from collections.abc import Mapping

from runtime.contract.artifact import PouCode


class StatementMap:
    """`units`: the code image's units by the file name their code is compiled under."""

    def __init__(self, units: Mapping[str, PouCode]) -> None:
        self.units = dict(units)
        # ST file -> ST line -> the code file names with a statement at that line
        self._at: dict[str, dict[int, set[str]]] = {}
        for filename, unit in sorted(self.units.items()):
            if not unit.file:
                continue
            lines = self._at.setdefault(unit.file, {})
            for line in unit.st_lines:
                if line:
                    lines.setdefault(line, set()).add(filename)

    def st_line(self, filename: str, lineno: int) -> int:
        """The ST line of line `lineno` of generated code (0: none)."""
        unit = self.units.get(filename)
        if unit is None or not 0 < lineno <= len(unit.st_lines):
            return 0
        return unit.st_lines[lineno - 1]

    def files(self) -> list[str]:
        return sorted(self._at)

    def statement_at(self, file: str, line: int) -> int:
        """The first line at or after `line` of `file` that holds a statement (0: none), as
        a debugger moves a breakpoint set on a comment or a declaration."""
        lines = self._at.get(file, {})
        later = [found for found in lines if found >= line]
        return min(later) if later else 0

    def code_files(self, file: str, line: int) -> frozenset[str]:
        """The code file names that hold a statement at `file:line`."""
        return frozenset(self._at.get(file, {}).get(line, ()))
