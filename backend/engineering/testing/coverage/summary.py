"""Coverage as a table for the terminal: a row per POU, its statements and branches
covered of all, and the share of both together."""

from __future__ import annotations

from backend.engineering.testing.coverage.model import Coverage, Figures


def percent(figures: Figures) -> str:
    """Statements and branches covered together, of all (as coverage.py's total)."""
    total = figures.statements + figures.branches
    if not total:
        return "100%"
    covered = figures.statements_covered + figures.branches_covered
    return f"{100 * covered / total:.0f}%"


def summary_table(coverage: Coverage) -> str:
    rows = [("POU", "File", "Statements", "Branches", "Cover")]
    for file in coverage.files:
        for pou in file.pous:
            rows.append((pou.name, file.file, *_cells(pou.figures)))
    rows.append(("TOTAL", "", *_cells(coverage.figures)))
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    lines = []
    for index, row in enumerate(rows):
        cells = [
            cell.ljust(width) if i < 2 else cell.rjust(width)
            for i, (cell, width) in enumerate(zip(row, widths, strict=True))
        ]
        lines.append("  ".join(cells).rstrip())
        if index == 0 or index == len(rows) - 2:
            lines.append("  ".join("-" * width for width in widths))
    return "\n".join(lines)


def _cells(figures: Figures) -> tuple[str, str, str]:
    return (
        f"{figures.statements_covered}/{figures.statements}",
        f"{figures.branches_covered}/{figures.branches}",
        percent(figures),
    )
