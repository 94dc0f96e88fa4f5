"""The signal list: every global variable and every located variable (I/O), with its
type, initial value, address and the description its comment gives."""

from __future__ import annotations

from dataclasses import dataclass

from backend.engineering.documentation.declarations import declared
from backend.engineering.documentation.markup import Section, grid, heading
from backend.engineering.documentation.subject import Subject


@dataclass(frozen=True)
class Signal:
    scope: str  # "" for a global, else the POU that declares it
    name: str
    type: str
    initial: str
    location: str
    qualifiers: str  # CONSTANT, RETAIN
    comment: str
    file: str
    line: int

    @property
    def qualified(self) -> str:
        return f"{self.scope}.{self.name}" if self.scope else self.name


def signals(subject: Subject) -> list[Signal]:
    """The globals (in declaration order, file by file) and then the located variables of
    POUs (by POU)."""
    found: list[Signal] = []
    for unit in subject.units:
        lines = subject.lines.get(unit.file, ())
        blocks = [(b, "") for b in unit.globals]
        blocks += [(b, "") for c in unit.configurations for b in c.globals]
        blocks += [(b, "") for c in unit.configurations for r in c.resources for b in r.globals]
        for pou in sorted(unit.pous, key=lambda p: p.name.upper()):
            blocks += [(b, pou.name) for b in pou.var_blocks if b.kind != "VAR_EXTERNAL"]
        for block, scope in blocks:
            for decl in block.decls:
                if scope and decl.location is None and block.kind != "VAR_GLOBAL":
                    continue  # a POU's own variable: its interface, not a signal
                text = declared(decl, lines)
                found.append(
                    Signal(
                        scope if block.kind != "VAR_GLOBAL" else "",
                        decl.name,
                        text.type,
                        text.initial,
                        text.location,
                        " ".join(q for q in block.qualifiers),
                        text.comment,
                        subject.shown(unit.file),
                        decl.pos.line,
                    )
                )
    return found


def located_signals(subject: Subject) -> list[Signal]:
    """The variables with an address, by address."""
    located = [s for s in signals(subject) if s.location]
    return sorted(located, key=lambda s: (s.location.upper(), s.qualified.upper()))


def signal_section(subject: Subject) -> Section:
    title, entry = heading(1, "Signal list", "signals")
    rows = [
        [s.qualified, s.type, s.initial, s.location, s.qualifiers, f"{s.file}:{s.line}", s.comment]
        for s in signals(subject)
    ]
    columns = [
        ("variable", 24),
        ("type", 14),
        ("initial", 10),
        ("address", 8),
        ("", 8),
        ("declared", 16),
        ("description", 0),
    ]
    body = grid(columns, rows)
    return Section(f'<section class="part">{title}{body}</section>', (entry,))
