"""What every browser of one UI server shares: the resources on the bus, the PADT accounts
the users log in with, the router's address (shown in the status bar), the users' watch
lists, the projects the PADT knows (by name, each a folder: a `ProjectShelf`, which also holds
the audit log of their changes), where the backups of what was loaded go, and the users'
workspace layouts and online test fields on drawn logic (kept beside the watch lists unless
given), and the unit test runs under way."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from backend.engineering.backup import DEFAULT_BACKUP_DIR
from backend.engineering.logic_fields import LogicFields
from backend.engineering.padt_accounts import PadtAccounts
from backend.engineering.project_shelf import ProjectShelf
from backend.engineering.resource_directory import ResourceDirectory
from backend.engineering.testing.project_tests import UnitTestRuns
from backend.engineering.user_layouts import UserLayouts
from backend.engineering.watch_lists import WatchLists


@dataclass(frozen=True)
class UiContext:
    directory: ResourceDirectory
    accounts: PadtAccounts
    router: str
    watch_lists: WatchLists
    projects: Mapping[str, Path] = field(default_factory=dict)  # name -> project folder
    backup_dir: Path = DEFAULT_BACKUP_DIR
    layouts: UserLayouts | None = None
    logic_fields: LogicFields | None = None
    # the unit test runs of this UI server: a bound on the runs at once of all its browsers
    test_runs: UnitTestRuns = field(default_factory=UnitTestRuns)

    def __post_init__(self) -> None:
        if self.layouts is None:
            where = self.watch_lists.path.with_name("layouts.json")
            object.__setattr__(self, "layouts", UserLayouts(where))
        if self.logic_fields is None:
            where = self.watch_lists.path.with_name("logic-fields.json")
            object.__setattr__(self, "logic_fields", LogicFields(where))
        # a plain mapping (tests, tools) is a shelf with no folder for new projects and no
        # audit log: its projects can be read, not changed
        if not isinstance(self.projects, ProjectShelf):
            object.__setattr__(self, "projects", ProjectShelf(self.projects))

    @property
    def user_layouts(self) -> UserLayouts:
        assert self.layouts is not None  # made so by __post_init__
        return self.layouts

    @property
    def fields(self) -> LogicFields:
        assert self.logic_fields is not None  # made so by __post_init__
        return self.logic_fields

    @property
    def shelf(self) -> ProjectShelf:
        """The projects as the project services take them."""
        assert isinstance(self.projects, ProjectShelf)  # made so by __post_init__
        return self.projects
