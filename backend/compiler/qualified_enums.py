"""CODESYS/TwinCAT qualified enumeration values: `Color.Red` where IEC 61131-3 writes
`Color#Red`.

The parser reads `Color.Red` as a member access. Before resolve, every such access whose
base names an enumeration type of the project that has that value becomes the typed
enumeration literal, marked as qualified so that the check stage warns (W0801). IEC wins
where the text means something else there: when the base is also a variable visible in the
POU (its own, a global, an SFC step) or a POU, it stays a member access.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from backend.compiler import ast
from backend.compiler.ast import key


class EnumMemo:
    """The work of `qualify_enum_values` on each top-level declaration, kept by identity
    for the next run on the same project, while its enumerations stay as they were (see
    `qualified_names.QualifyMemo`)."""

    def __init__(self) -> None:
        self.enums: dict[str, set[str]] = {}
        self.rebuilt: dict[int, tuple[Any, Any]] = {}


def qualify_enum_values(
    units: list[ast.SourceUnit], memo: EnumMemo | None = None
) -> list[ast.SourceUnit]:
    """The units with every CODESYS qualified enumeration value made an `EnumLiteral`."""
    enums = {
        key(decl.name): {key(name) for name, _, _ in decl.spec.values}
        for unit in units
        for decl in unit.types
        if isinstance(decl.spec, ast.EnumSpec)
    }
    if not enums:
        return units
    hidden = {key(pou.name) for unit in units for pou in unit.pous}
    hidden |= {key(d.name) for unit in units for block in global_blocks(unit) for d in block.decls}
    enums = {name: values for name, values in enums.items() if name not in hidden}
    if not enums:
        return units
    memo = memo or EnumMemo()
    kept = memo.rebuilt if enums == memo.enums else {}
    memo.enums, memo.rebuilt = enums, {}

    def qualified(item: Any, hidden: set[str]) -> Any:
        found = kept.get(id(item)) or (item, _Qualifier(enums, hidden).node(item))
        memo.rebuilt[id(item)] = found
        return found[1]

    return [
        replace(
            unit,
            pous=tuple(qualified(pou, _own_names(pou)) for pou in unit.pous),
            globals=tuple(qualified(block, set()) for block in unit.globals),
            types=tuple(qualified(decl, set()) for decl in unit.types),
            configurations=tuple(qualified(c, set()) for c in unit.configurations),
        )
        for unit in units
    ]


def global_blocks(unit: ast.SourceUnit) -> list[ast.VarBlock]:
    """Every VAR_GLOBAL block of a file: its own, its configurations' and their resources'."""
    blocks = list(unit.globals)
    for configuration in unit.configurations:
        blocks += configuration.globals
        blocks += [b for resource in configuration.resources for b in resource.globals]
    return blocks


def _own_names(pou: ast.Pou) -> set[str]:
    names = {key(d.name) for block in pou.var_blocks for d in block.decls}
    if pou.sfc is not None:
        names |= {key(step.name) for step in pou.sfc.steps}
    return names


class _Qualifier:
    """Rebuilds a subtree with the qualified values replaced; a node without one is
    returned as it is (the AST is immutable, so sharing it is safe)."""

    def __init__(self, enums: dict[str, set[str]], hidden: set[str]) -> None:
        self.enums = {name: values for name, values in enums.items() if name not in hidden}

    def node(self, value: Any) -> Any:
        return ast.rebuilt(value, lambda node: self._literal(node) or node)

    def _literal(self, value: object) -> ast.EnumLiteral | None:
        if not isinstance(value, ast.MemberRef) or not isinstance(value.base, ast.NameRef):
            return None
        values = self.enums.get(key(value.base.name))
        if values is None or key(value.member) not in values:
            return None
        return ast.EnumLiteral(value.base.name, value.member, value.pos, qualified=True)
