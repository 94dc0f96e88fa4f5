"""The interface of every POU of the project: kind, return type, CRC, and what a caller or
the plant connects to it: its inputs, outputs, in-outs, the globals it uses, and its
located variables, as written (type, initial value, address, description); for a function
block also what it extends and implements, its methods and its properties. Then every
INTERFACE with its method and property prototypes. Internal variables are in the POU's
listing and in the cross-reference."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.source import Pos
from backend.engineering.documentation.declarations import declared
from backend.engineering.documentation.markup import Section, anchor, code, escape, grid, heading
from backend.engineering.documentation.subject import Subject

_COLUMNS = (
    ("block", 14),
    ("name", 20),
    ("type", 18),
    ("initial", 12),
    ("address", 8),
    ("description", 0),
)
_INTERNAL = ("VAR", "VAR_TEMP")  # shown when located (AT %I, %Q, %M)
# the interface first (what a caller connects), then what the POU keeps to itself
_BLOCK_ORDER = (
    "VAR_INPUT",
    "VAR_OUTPUT",
    "VAR_IN_OUT",
    "VAR_EXTERNAL",
    "VAR_GLOBAL",
    "VAR",
    "VAR_TEMP",
)


_METHOD_COLUMNS = (("method", 20), ("access", 18), ("result", 12), ("parameters", 0))
_PROPERTY_COLUMNS = (("property", 20), ("access", 18), ("type", 12), ("accessors", 0))
_PARAMETERS = {"VAR_INPUT": "IN", "VAR_OUTPUT": "OUT", "VAR_IN_OUT": "IN_OUT"}


def project_pous(subject: Subject) -> list[tuple[str, ast.Pou]]:
    """(file, POU) of every POU of the project, by name."""
    pous = [(unit.file, pou) for unit in subject.units for pou in unit.pous]
    return sorted(pous, key=lambda item: item[1].name.upper())


def project_interfaces(subject: Subject) -> list[tuple[str, ast.Interface]]:
    """(file, INTERFACE) of every interface of the project, by name."""
    found = [(unit.file, i) for unit in subject.units for i in unit.interfaces]
    return sorted(found, key=lambda item: item[1].name.upper())


def interface_section(subject: Subject) -> Section:
    title, entry = heading(1, "POU interfaces", "interfaces")
    parts, headings = [title], [entry]
    crcs = {p.name.upper(): p.crc for p in subject.artifact.pous}
    for file, pou in project_pous(subject):
        sub, sub_entry = heading(2, f"{pou.kind} {pou.name}", anchor("interface", pou.name))
        headings.append(sub_entry)
        facts = [f"{escape(subject.shown(file))}:{pou.pos.line}"]
        if pou.return_type is not None:
            facts.append(f"returns {code(_header_type(subject, file, pou.pos))}")
        facts += _lineage(pou.modifiers, pou.extends, pou.implements)
        crc = crcs.get(pou.name.upper())
        facts.append(f"CRC {code(crc)}" if crc else "not in the configuration (unused)")
        rows = []
        lines = subject.lines.get(file, ())
        order = {kind: n for n, kind in enumerate(_BLOCK_ORDER)}
        internal = 0
        for block in sorted(pou.var_blocks, key=lambda b: order.get(b.kind, len(order))):
            kind = " ".join([block.kind, *block.qualifiers])
            for decl in block.decls:
                if block.kind in _INTERNAL and decl.location is None:
                    internal += 1
                    continue
                text = declared(decl, lines)
                rows.append([kind, decl.name, text.type, text.initial, text.location, text.comment])
        if internal:
            facts.append(f"{internal} internal variable{'s' if internal > 1 else ''}")
        members = _members(subject, file, pou.methods, pou.properties, "")
        # a block of methods only: its tables say it all, "none" above them would puzzle
        body = (grid(_COLUMNS, rows) if rows or not members else "") + members
        parts.append(f'<div class="pou">{sub}<p class="facts">{" · ".join(facts)}</p>{body}</div>')
    for file, interface in project_interfaces(subject):
        sub, sub_entry = heading(
            2, f"INTERFACE {interface.name}", anchor("interface", interface.name)
        )
        headings.append(sub_entry)
        facts = [f"{escape(subject.shown(file))}:{interface.pos.line}"]
        facts += _lineage((), interface.extends, ())
        body = _members(subject, file, interface.methods, interface.properties, "PUBLIC")
        parts.append(f'<div class="pou">{sub}<p class="facts">{" · ".join(facts)}</p>{body}</div>')
    return Section('<section class="part">' + "".join(parts) + "</section>", tuple(headings))


def _lineage(
    modifiers: tuple[str, ...], extends: tuple[str, ...], implements: tuple[str, ...]
) -> list[str]:
    facts = [escape(" ".join(modifiers))] if modifiers else []
    if extends:
        facts.append("extends " + ", ".join(code(name) for name in extends))
    if implements:
        facts.append("implements " + ", ".join(code(name) for name in implements))
    return facts


def _members(
    subject: Subject,
    file: str,
    methods: tuple[ast.Method, ...],
    properties: tuple[ast.Property, ...],
    access: str,
) -> str:
    """The methods and properties of a block (`access` "": as written, PROTECTED when not
    written, as IEC says) or of an interface (always PUBLIC), each by name."""
    lines = subject.lines.get(file, ())
    method_rows = [
        [
            m.name,
            " ".join([access or m.access or "PROTECTED", *m.modifiers]),
            _header_type(subject, file, m.pos) if m.return_type is not None else "-",
            "; ".join(
                f"{_PARAMETERS[block.kind]} {decl.name} : {declared(decl, lines).type}"
                for block in m.var_blocks
                if block.kind in _PARAMETERS
                for decl in block.decls
            ),
        ]
        for m in sorted(methods, key=lambda m: m.name.upper())
    ]
    property_rows = [
        [
            p.name,
            " ".join([access or p.access or "PROTECTED", *p.modifiers]),
            _header_type(subject, file, p.pos),
            ", ".join(a.kind.upper() for a in p.accessors) or "GET, SET (prototype)",
        ]
        for p in sorted(properties, key=lambda p: p.name.upper())
    ]
    parts = [grid(_METHOD_COLUMNS, method_rows)] if method_rows else []
    if property_rows:
        parts.append(grid(_PROPERTY_COLUMNS, property_rows))
    return "".join(parts)


def _header_type(subject: Subject, file: str, pos: Pos) -> str:
    """`FUNCTION F : INT`, `METHOD M : BOOL`, `PROPERTY P : REAL` -> the type, as written."""
    line = subject.lines.get(file, ())[pos.line - 1 : pos.line]
    head = line[0] if line else ""
    _, colon, rest = head.partition(":")
    return " ".join(rest.split(";")[0].split("(*")[0].split("//")[0].split()) if colon else ""
