"""Where in the ST source a run-time error happened: the innermost frame of generated code
in the exception's traceback, mapped back through the artifact's line table."""

from __future__ import annotations

from dataclasses import dataclass

from runtime.contract.artifact import PouCode


@dataclass(frozen=True)
class SourceLocation:
    pou: str
    file: str
    line: int  # 0: the generated line has no ST line (declarations, SFC housekeeping)

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}" if self.line else self.file
        return f"POU {self.pou} ({where})"


def code_filename(unit: PouCode) -> str:
    """The file name generated code is compiled under, so tracebacks name its POU."""
    return f"<{unit.kind} {unit.name}>"


def locate(exc: BaseException, units: dict[str, PouCode]) -> SourceLocation | None:
    """`units`: by `code_filename`. None when no generated code is on the traceback."""
    found: SourceLocation | None = None
    traceback = exc.__traceback__
    while traceback is not None:
        unit = units.get(traceback.tb_frame.f_code.co_filename)
        if unit is not None:
            index = traceback.tb_lineno - 1
            line = unit.st_lines[index] if 0 <= index < len(unit.st_lines) else 0
            found = SourceLocation(unit.name, unit.file, line)
        traceback = traceback.tb_next
    return found
