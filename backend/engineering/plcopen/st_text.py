"""The model as Structured Text: one POU, the data types, the global variables."""

from __future__ import annotations

import textwrap

from backend.compiler.graphics.text_form import write_body
from backend.engineering.plcopen.model import (
    Accessor,
    Action,
    DataType,
    Interface,
    Method,
    Pou,
    Property,
    VarSection,
)

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
    if pou.extends:
        head += f" EXTENDS {pou.extends}"
    if pou.implements:
        head += f" IMPLEMENTS {', '.join(pou.implements)}"
    if pou.return_type:
        head += f" : {pou.return_type}"
    parts = [comment(pou.comment)] if pou.comment else []
    parts.append(head)
    if pou.sections:
        parts.append(sections_text(pou.sections))
    # IEC's order: the methods (and properties) after the declarations, before the body
    parts += [method_text(method) for method in pou.methods]
    parts += [property_text(item) for item in pou.properties]
    if pou.graphic is not None:  # the drawing in its text form, in place of statements
        parts.append(write_body(pou.graphic))
    elif pou.body:
        parts.append(pou.body)
    parts += [f"ACTION {a.name}:\n{_action_body(a)}\nEND_ACTION" for a in pou.actions]
    parts.append(f"END_{pou.kind}")
    return "\n".join(parts) + "\n"


def _action_body(action: Action) -> str:
    return write_body(action.drawing) if action.drawing is not None else action.body


def _member_head(word: str, access: str, modifiers: tuple[str, ...], name: str) -> str:
    """`METHOD PUBLIC FINAL Name`; an interface's members (access empty) are PUBLIC by
    definition and take no specifier."""
    return " ".join(part for part in (word, access, *modifiers, name) if part)


def method_text(method: Method, prototype: bool = False) -> str:
    """A METHOD of a POU or, `prototype`, of an interface (no access, no body)."""
    head = _member_head("METHOD", "" if prototype else method.access, method.modifiers, method.name)
    if method.return_type:
        head += f" : {method.return_type}"
    parts = [comment(method.comment)] if method.comment else []
    parts.append(head)
    if method.sections:
        parts.append(sections_text(method.sections))
    if method.body:
        parts.append(method.body)
    parts.append("END_METHOD")
    return "\n".join(parts)


def _accessor_text(word: str, accessor: Accessor) -> str:
    parts = [word]
    if accessor.sections:
        parts.append(sections_text(accessor.sections))
    if accessor.body:
        parts.append(accessor.body)
    parts.append(f"END_{word}")
    return "\n".join(parts)


def property_text(item: Property, prototype: bool = False) -> str:
    head = _member_head("PROPERTY", "" if prototype else item.access, item.modifiers, item.name)
    parts = [comment(item.comment)] if item.comment else []
    parts.append(f"{head} : {item.type}")
    if item.get is not None:
        parts.append(_accessor_text("GET", item.get))
    if item.set is not None:
        parts.append(_accessor_text("SET", item.set))
    parts.append("END_PROPERTY")
    return "\n".join(parts)


def interface_text(interface: Interface) -> str:
    head = f"INTERFACE {interface.name}"
    if interface.extends:
        head += f" EXTENDS {', '.join(interface.extends)}"
    parts = [comment(interface.comment)] if interface.comment else []
    parts.append(head)
    parts += [method_text(method, prototype=True) for method in interface.methods]
    parts += [property_text(item, prototype=True) for item in interface.properties]
    parts.append("END_INTERFACE")
    return "\n".join(parts) + "\n"


def types_text(types: list[DataType]) -> str:
    declarations = [
        INDENT + textwrap.indent(f"{t.name} : {t.declaration};", INDENT)[len(INDENT) :]
        for t in types
    ]
    return "\n".join(["TYPE", *declarations, "END_TYPE"]) + "\n"


def globals_text(sections: list[VarSection]) -> str:
    return sections_text(sections) + "\n"
