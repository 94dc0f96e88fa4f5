"""What every browser of one UI server shares: the resources on the bus, the PADT accounts
the users log in with, the users' watch lists, and the router's address (shown in the
status bar)."""

from __future__ import annotations

from dataclasses import dataclass

from backend.engineering.padt_accounts import PadtAccounts
from backend.engineering.resource_directory import ResourceDirectory
from backend.engineering.watch_lists import WatchLists


@dataclass(frozen=True)
class UiContext:
    directory: ResourceDirectory
    accounts: PadtAccounts
    router: str
    watch_lists: WatchLists
