"""The cross-reference: every variable, where it is declared, read and written
(file:line), from the compiler's resolved AST (backend/compiler/cross_reference.py)."""

from __future__ import annotations

from backend.compiler.cross_reference import DECLARED, READ, WRITTEN, Use, VariableUses
from backend.engineering.documentation.markup import Section, code, escape, heading, table
from backend.engineering.documentation.subject import Subject


def places(uses: tuple[Use, ...]) -> list[str]:
    """`file:line` of each use, once per line, in file and line order."""
    return list(dict.fromkeys(f"{use.pos.file}:{use.pos.line}" for use in uses))


def xref_section(subject: Subject) -> Section:
    title, entry = heading(1, "Cross-reference", "xref")
    intro = (
        "<p>Every variable with the lines that declare, read and write it. A member, element "
        "or bit of a variable counts as the variable; calling a function block instance "
        "writes it; an output or in-out argument writes the variable connected to it.</p>"
    )
    rows = [_row(entry_) for entry_ in subject.uses]
    body = table(["variable", "type", "declared", "read", "written"], rows, "xref")
    return Section(f'<section class="part">{title}{intro}{body}</section>', (entry,))


def _row(variable: VariableUses) -> list[str]:
    def cell(how: str) -> str:
        return ", ".join(escape(p) for p in places(variable.where(how))) or "-"

    return [
        code(variable.qualified),
        escape(variable.type),
        cell(DECLARED),
        cell(READ),
        cell(WRITTEN),
    ]
