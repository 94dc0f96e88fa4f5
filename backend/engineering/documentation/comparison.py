"""The version comparison: what changed between a previous version and this one, per POU,
program, variable, parameter and user, with old and new CRCs, and the changed source
lines of each POU as a diff (old and new line numbers)."""

from __future__ import annotations

import difflib
from dataclasses import dataclass

from backend.engineering.documentation.declarations import declared
from backend.engineering.documentation.markup import Section, anchor, code, escape, heading, table
from backend.engineering.documentation.resource import value_text
from backend.engineering.documentation.st_highlight import Token, numbered, tokenized
from backend.engineering.documentation.subject import Subject
from backend.engineering.sources import PouSource
from runtime.contract.parameters import PROGRAM_PARAMETERS, RESOURCE_PARAMETERS

ADDED, REMOVED, CHANGED = "added", "removed", "changed"


@dataclass(frozen=True)
class Change:
    area: str  # configuration | POU | program | parameter | variable | user
    name: str
    what: str  # added | removed | changed, or what about it changed
    old: str
    new: str


def changes(new: Subject, old: Subject) -> list[Change]:
    found: list[Change] = []
    if new.crc != old.crc:
        found.append(Change("configuration", "CRC", CHANGED, old.crc, new.crc))
    if new.version != old.version:
        found.append(Change("configuration", "version", CHANGED, old.version, new.version))
    found += _by_name("POU", _pou_crcs(old), _pou_crcs(new), "CRC")
    found += _programs(old, new)
    found += _parameters(old, new)
    found += _by_name("variable", _variables(old), _variables(new), "declaration")
    found += _users(old, new)
    return found


def _by_name(area: str, old: dict[str, str], new: dict[str, str], what: str) -> list[Change]:
    result = []
    for name in sorted(set(old) | set(new), key=str.upper):
        before, after = old.get(name), new.get(name)
        if before is None:
            result.append(Change(area, name, ADDED, "", after or ""))
        elif after is None:
            result.append(Change(area, name, REMOVED, before, ""))
        elif before != after:
            result.append(Change(area, name, f"{what} {CHANGED}", before, after))
    return result


def _pou_crcs(subject: Subject) -> dict[str, str]:
    return {p.name: p.crc for p in subject.artifact.pous}


def _programs(old: Subject, new: Subject) -> list[Change]:
    before = {p.name: p for p in old.artifact.programs}
    after = {p.name: p for p in new.artifact.programs}
    result = _by_name(
        "program",
        {n: p.crc for n, p in before.items()},
        {n: p.crc for n, p in after.items()},
        "CRC",
    )
    for name in sorted(set(before) & set(after), key=str.upper):
        for spec in PROGRAM_PARAMETERS:
            a, b = getattr(before[name], spec.name), getattr(after[name], spec.name)
            if a != b:
                result.append(Change("program", name, spec.name, value_text(a), value_text(b)))
    return result


def _parameters(old: Subject, new: Subject) -> list[Change]:
    result = []
    if old.artifact.resource.name != new.artifact.resource.name:
        result.append(
            Change("parameter", "resource name", CHANGED, old.artifact.resource.name,
                   new.artifact.resource.name)
        )  # fmt: skip
    for spec in RESOURCE_PARAMETERS:
        a = getattr(old.artifact.resource, spec.name)
        b = getattr(new.artifact.resource, spec.name)
        if a != b:
            result.append(Change("parameter", spec.name, CHANGED, value_text(a), value_text(b)))
    return result


def _variables(subject: Subject) -> dict[str, str]:
    """Every declared variable (globals by name, a POU's as POU.name) -> its declaration."""
    found: dict[str, str] = {}
    for unit in subject.units:
        lines = subject.lines.get(unit.file, ())
        blocks = [("", b) for b in unit.globals]
        blocks += [("", b) for c in unit.configurations for b in c.globals]
        blocks += [("", b) for c in unit.configurations for r in c.resources for b in r.globals]
        blocks += [(pou.name, b) for pou in unit.pous for b in pou.var_blocks]
        for scope, block in blocks:
            for decl in block.decls:
                text = declared(decl, lines)
                parts = [" ".join([block.kind, *block.qualifiers]), text.type]
                if text.location:
                    parts.append(f"AT {text.location}")
                if text.initial:
                    parts.append(f":= {text.initial}")
                found[f"{scope}.{decl.name}" if scope else decl.name] = " ".join(parts)
    return found


def _users(old: Subject, new: Subject) -> list[Change]:
    before = {u.name: u for u in old.artifact.users}
    after = {u.name: u for u in new.artifact.users}
    result = _by_name(
        "user",
        {n: u.level for n, u in before.items()},
        {n: u.level for n, u in after.items()},
        "level",
    )
    for name in sorted(set(before) & set(after), key=str.upper):
        if before[name].password_hash != after[name].password_hash:
            result.append(Change("user", name, "password changed", "", ""))
    return result


def comparison_section(new: Subject, old: Subject) -> Section:
    title, entry = heading(1, "Version comparison", "comparison")
    headings = [entry]
    summary = table(
        ["", "previous version", "this version"],
        [
            ["version", escape(old.version or "-"), escape(new.version or "-")],
            ["configuration CRC", code(old.crc), code(new.crc)],
        ],
    )
    found = changes(new, old)
    rows = [
        [escape(c.area), code(c.name), escape(c.what), escape(c.old), escape(c.new)]
        for c in found
        if c.area != "configuration"
    ]
    sub, sub_entry = heading(2, "Changes", "comparison-changes")
    headings.append(sub_entry)
    listed = (
        table(["what", "name", "change", "previous", "this version"], rows)
        if rows
        else '<p class="none">No change: both versions are the same configuration.</p>'
    )
    diff_title, diff_entry = heading(2, "Changed source lines", "comparison-diff")
    headings.append(diff_entry)
    diffs = _source_diffs(old, new) or '<p class="none">No source line changed.</p>'
    body = f'<section class="part">{title}{summary}{sub}{listed}{diff_title}{diffs}</section>'
    return Section(body, tuple(headings))


def _source_diffs(old: Subject, new: Subject) -> str:
    before = _own_pous(old)
    after = _own_pous(new)
    parts = []
    for name in sorted(set(before) | set(after)):
        a, b = before.get(name), after.get(name)
        if a is not None and b is not None and a.lines == b.lines:
            continue
        shown = (b or a).name  # type: ignore[union-attr]
        status = ADDED if a is None else REMOVED if b is None else CHANGED
        names = [old.shown(a.file) if a else "", new.shown(b.file) if b else ""]
        files = " → ".join(dict.fromkeys(name for name in names if name))
        parts.append(
            f'<h3 id="{anchor("diff", shown)}">{escape(shown)} ({status}, {escape(files)})</h3>'
            + _diff(a, b)
        )
    return "".join(parts)


def _own_pous(subject: Subject) -> dict[str, PouSource]:
    return {k: p for k, p in subject.pous.items() if not p.standard}


def _diff(old: PouSource | None, new: PouSource | None) -> str:
    """The changed lines with three lines of context; removed lines numbered as in the old
    file (`-12`), added ones as in the new (`+14`)."""
    a = list(old.lines) if old else []
    b = list(new.lines) if new else []
    a_first = old.first_line if old else 1
    b_first = new.first_line if new else 1
    a_tokens, b_tokens = tokenized(a), tokenized(b)
    rows: list[tuple[str, list[Token], str]] = []
    matcher = difflib.SequenceMatcher(a=a, b=b, autojunk=False)
    for group in matcher.get_grouped_opcodes(3):
        rows.append(("...", [], ""))
        for tag, i1, i2, j1, j2 in group:
            if tag == "equal":
                rows += [(str(b_first + j), b_tokens[j], "") for j in range(j1, j2)]
                continue
            rows += [(f"-{a_first + i}", a_tokens[i], "removed") for i in range(i1, i2)]
            rows += [(f"+{b_first + j}", b_tokens[j], "added") for j in range(j1, j2)]
    return numbered(rows)
