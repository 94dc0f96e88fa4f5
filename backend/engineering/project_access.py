"""Who edits a project, and whether their PADT level allows it. Checked by every project
service itself, whichever adapter calls it: read-only may look, read-write may change."""

from __future__ import annotations

from dataclasses import dataclass

from backend.engineering.padt_levels import PADT_LEVELS
from runtime.contract.refusal import Refusal

READ = PADT_LEVELS[0]
WRITE = PADT_LEVELS[1]


@dataclass(frozen=True)
class Editor:
    """A PADT user as the services see them: the name the audit log records, and the
    level of their PADT session."""

    user: str
    level: str


def require(editor: Editor, needed: str) -> None:
    """Refused (`forbidden`) unless the editor's level is at least `needed`."""
    if editor.level not in PADT_LEVELS or PADT_LEVELS.index(editor.level) < PADT_LEVELS.index(
        needed
    ):
        raise Refusal(
            "forbidden",
            f"{editor.user} is {editor.level or 'without a level'} on this PADT; "
            f"this needs {needed}",
        )
