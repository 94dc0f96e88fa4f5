"""What every browser of one UI server shares: the resources on the bus, the PADT accounts
the users log in with, the router's address (shown in the status bar), and the projects
the PADT knows (by name: their folders)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from backend.engineering.padt_accounts import PadtAccounts
from backend.engineering.resource_directory import ResourceDirectory


@dataclass(frozen=True)
class UiContext:
    directory: ResourceDirectory
    accounts: PadtAccounts
    router: str
    projects: dict[str, Path] = field(default_factory=dict)
