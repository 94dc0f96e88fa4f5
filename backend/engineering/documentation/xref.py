"""The cross-reference: every variable, where it is declared, read and written
(file:line), from the compiler's resolved AST (backend/compiler/cross_reference.py)."""

from __future__ import annotations

from collections.abc import Callable

from backend.compiler.cross_reference import DECLARED, READ, WRITTEN, Use, VariableUses
from backend.engineering.documentation.markup import Section, code, grid, heading
from backend.engineering.documentation.subject import Subject


def places(uses: tuple[Use, ...], shown: Callable[[str], str]) -> str:
    """The lines of `uses`, file by file: `filler.st:4, 13; globals.st:9` (a file name
    written once per cell keeps the cross-reference of a large library short); `shown`
    names a file, "" the file every line is in (then the numbers stand alone)."""
    lines: dict[str, list[int]] = {}
    for use in uses:
        numbers = lines.setdefault(shown(use.pos.file), [])
        if use.pos.line not in numbers:
            numbers.append(use.pos.line)
    return "; ".join(
        f"{file}:{', '.join(map(str, numbers))}" if file else ", ".join(map(str, numbers))
        for file, numbers in lines.items()
    )


def xref_section(subject: Subject) -> Section:
    title, entry = heading(1, "Cross-reference", "xref")
    intro = (
        "<p>Every variable with the lines that declare, read and write it. A member, element "
        "or bit of a variable counts as the variable; calling a function block instance "
        "writes it; an output or in-out argument writes the variable connected to it."
    )
    only = _only_file(subject)
    if only is not None:
        intro += f" All lines are lines of {code(subject.shown(only))}."
    intro += "</p>"
    columns = [("variable", 30), ("type", 14), ("declared", 22), ("read", 22), ("written", 0)]
    body = grid(columns, xref_rows(subject))
    return Section(f'<section class="part">{title}{intro}{body}</section>', (entry,))


def xref_rows(subject: Subject) -> list[list[str]]:
    """Per variable: its name, type, and the places declaring, reading and writing it."""
    only = _only_file(subject)

    def shown(file: str) -> str:
        return "" if file == only else subject.shown(file)

    return [_row(variable, shown) for variable in subject.uses]


def _only_file(subject: Subject) -> str | None:
    """The file of a one-file subject: its name in every cell would fill the
    cross-reference of a large library and say nothing."""
    return next(iter(subject.lines)) if len(subject.lines) == 1 else None


def _row(variable: VariableUses, shown: Callable[[str], str]) -> list[str]:
    def cell(how: str) -> str:
        return places(variable.where(how), shown) or "-"

    return [variable.qualified, variable.type, cell(DECLARED), cell(READ), cell(WRITTEN)]
