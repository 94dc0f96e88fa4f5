"""The model as Structured Text: one POU, the data types, the global variables."""

from __future__ import annotations

import textwrap

from backend.engineering.plcopen.model import DataType, Pou, VarSection

INDENT = "    "


def comment(text: str) -> str:
    """`(* text *)`, with whatever would end or nest the comment early broken up."""
    safe = text.replace("(*", "( *").replace("*)", "* )")
    return f"(* {safe} *)"


def sections_text(sections: tuple[VarSection, ...] | list[VarSection]) -> str:
    blocks = []
    for section in sections:
        head = " ".join((section.kind, *section.qualifiers))
        lines = []
        for variable in section.variables:
            line = f"{INDENT}{textwrap.indent(variable.declaration(), INDENT)[len(INDENT) :]};"
            if variable.comment:
                line += " " + comment(" ".join(variable.comment.split()))
            lines.append(line)
        blocks.append("\n".join([head, *lines, "END_VAR"]))
    return "\n".join(blocks)


def pou_text(pou: Pou) -> str:
    head = f"{pou.kind} {pou.name}"
    if pou.return_type:
        head += f" : {pou.return_type}"
    parts = [comment(pou.comment)] if pou.comment else []
    parts.append(head)
    if pou.sections:
        parts.append(sections_text(pou.sections))
    if pou.body:
        parts.append(pou.body)
    parts += [f"ACTION {action.name}:\n{action.body}\nEND_ACTION" for action in pou.actions]
    parts.append(f"END_{pou.kind}")
    return "\n".join(parts) + "\n"


def types_text(types: list[DataType]) -> str:
    declarations = [
        INDENT + textwrap.indent(f"{t.name} : {t.declaration};", INDENT)[len(INDENT) :]
        for t in types
    ]
    return "\n".join(["TYPE", *declarations, "END_TYPE"]) + "\n"


def globals_text(sections: list[VarSection]) -> str:
    return sections_text(sections) + "\n"
