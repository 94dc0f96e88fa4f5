"""The data types the project declares (TYPE ... END_TYPE): structures with their
members, enumerations with their values, and aliases, arrays and subranges as written."""

from __future__ import annotations

from backend.compiler import ast
from backend.engineering.documentation.declarations import declared
from backend.engineering.documentation.markup import (
    Section,
    anchor,
    code,
    escape,
    grid,
    heading,
    table,
)
from backend.engineering.documentation.subject import Subject


def data_type_section(subject: Subject) -> Section:
    title, entry = heading(1, "Data types", "types")
    parts, headings = [title], [entry]
    types = sorted(
        ((unit.file, decl) for unit in subject.units for decl in unit.types),
        key=lambda item: item[1].name.upper(),
    )
    if not types:
        parts.append('<p class="none">The project declares no data types.</p>')
    for file, decl in types:
        sub, sub_entry = heading(2, decl.name, anchor("type", decl.name))
        headings.append(sub_entry)
        place = f"{escape(subject.shown(file))}:{decl.pos.line}"
        where = f'<p class="facts">{place} · {_kind(decl.spec)}</p>'
        parts.append(f'<div class="pou">{sub}{where}{_body(subject, file, decl)}</div>')
    return Section('<section class="part">' + "".join(parts) + "</section>", tuple(headings))


def _kind(spec: ast.TypeRef) -> str:
    match spec:
        case ast.StructSpec():
            return "structure"
        case ast.EnumSpec():
            return "enumeration"
        case ast.ArrayType():
            return "array"
        case ast.SubrangeSpec():
            return "subrange"
    return "alias"


def _body(subject: Subject, file: str, decl: ast.TypeDecl) -> str:
    lines = subject.lines.get(file, ())
    match decl.spec:
        case ast.StructSpec(members=members):
            rows = []
            for member in members:
                text = declared(member, lines)
                rows.append([member.name, text.type, text.initial, text.comment])
            columns = [("member", 24), ("type", 20), ("initial", 14), ("description", 0)]
            return grid(columns, rows)
        case ast.EnumSpec(values=values):
            return table(["value"], [[code(name)] for name, _, _ in values])
    text = declared(ast.VarDecl(decl.name, decl.spec, decl.init, None, decl.pos), lines)
    shown = text.type + (f" := {text.initial}" if text.initial else "")
    return f"<p>{code(decl.name)} : {code(shown)}</p>"
