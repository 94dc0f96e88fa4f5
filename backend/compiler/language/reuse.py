"""What one analysis of a `LanguageProject` leaves to the next: each declaration with its
qualified names resolved (`resolve.ResolveMemo`) and the diagnostics of each POU's check.
Typing in a POU's body changes no declaration of the project, so every other POU checks as
it did: its diagnostics are taken as they were. `tests/compiler/language/test_incremental.py`
proves the result equal to a full analysis after random edits."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from backend.compiler import ast
from backend.compiler.check import check_declarations, check_pou
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.resolve import Resolved, ResolveMemo


class Reuse:
    """Kept by one `LanguageProject` under its lock, for the analysis of its texts."""

    def __init__(self) -> None:
        self.resolve = ResolveMemo()
        self._declarations: tuple[Any, ...] | None = None
        # by identity (each entry keeps its node alive, so that no other node has its id)
        self._bodiless: dict[int, tuple[ast.Pou, ast.Pou]] = {}
        self._checked: dict[int, tuple[ast.Pou, tuple[Diagnostic, ...]]] = {}
        self._declared: tuple[Diagnostic, ...] = ()  # of `check_declarations`

    def check(self, units: list[ast.SourceUnit], resolved: Resolved) -> list[Diagnostic]:
        """`check(resolved)`, the POUs whose check cannot have changed taken as they were:
        a POU of the very same AST in a project of the same declarations."""
        declarations = self._declarations_of(units)
        same = declarations == self._declarations
        kept = self._checked if same else {}
        self._declarations, self._checked = declarations, {}
        if not same:  # the rules on data and globals see the declarations alone
            self._declared = tuple(check_declarations(resolved))
        diagnostics = list(self._declared)
        for pou in resolved.sorted_pous():
            found = kept.get(id(pou.pou))
            if found is None:
                found = (pou.pou, tuple(check_pou(resolved, pou)))
            self._checked[id(pou.pou)] = found
            diagnostics.extend(found[1])
        return diagnostics

    def _declarations_of(self, units: list[ast.SourceUnit]) -> tuple[Any, ...]:
        """All the project declares: its units with the POUs' bodies left out (and the
        direct addresses the bodies name, which declare globals)."""
        bodiless: dict[int, tuple[ast.Pou, ast.Pou]] = {}
        result = []
        for unit in units:
            pous = []
            for pou in unit.pous:
                found = self._bodiless.get(id(pou)) or (pou, replace(pou, body=()))
                bodiless[id(pou)] = found
                pous.append(found[1])
            result.append(replace(unit, pous=tuple(pous), warnings=()))
        self._bodiless = bodiless
        return tuple(result)
