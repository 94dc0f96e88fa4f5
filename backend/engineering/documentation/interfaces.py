"""The interface of every POU of the project: kind, return type, CRC, and what a caller or
the plant connects to it: its inputs, outputs, in-outs, the globals it uses, and its
located variables, as written (type, initial value, address, description). Its internal
variables are in its listing and in the cross-reference."""

from __future__ import annotations

from backend.compiler import ast
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


def project_pous(subject: Subject) -> list[tuple[str, ast.Pou]]:
    """(file, POU) of every POU of the project, by name."""
    pous = [(unit.file, pou) for unit in subject.units for pou in unit.pous]
    return sorted(pous, key=lambda item: item[1].name.upper())


def interface_section(subject: Subject) -> Section:
    title, entry = heading(1, "POU interfaces", "interfaces")
    parts, headings = [title], [entry]
    crcs = {p.name.upper(): p.crc for p in subject.artifact.pous}
    for file, pou in project_pous(subject):
        sub, sub_entry = heading(2, f"{pou.kind} {pou.name}", anchor("interface", pou.name))
        headings.append(sub_entry)
        facts = [f"{escape(subject.shown(file))}:{pou.pos.line}"]
        if pou.return_type is not None:
            facts.append(f"returns {code(_return_type(subject, file, pou))}")
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
        body = grid(_COLUMNS, rows)
        parts.append(f'<div class="pou">{sub}<p class="facts">{" · ".join(facts)}</p>{body}</div>')
    return Section('<section class="part">' + "".join(parts) + "</section>", tuple(headings))


def _return_type(subject: Subject, file: str, pou: ast.Pou) -> str:
    """`FUNCTION F : INT` -> INT, as written."""
    line = subject.lines.get(file, ())[pou.pos.line - 1 : pou.pos.line]
    head = line[0] if line else ""
    _, colon, rest = head.partition(":")
    return " ".join(rest.split(";")[0].split("(*")[0].split()) if colon else ""
