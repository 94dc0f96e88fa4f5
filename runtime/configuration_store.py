"""Where a resource keeps the configuration it runs, for the next power-up (its state
folder): written whole or not at all, owner-only (it holds the accounts' verifiers).

Storing comes in two steps, so that a configuration is taken only when it can be kept: the
text is written to a temporary file and synced first (`stage`; a full or unwritable folder
is a refusal then, with nothing changed), and put in place only once the resource has
taken the configuration (`Staged.commit`, a rename)."""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from runtime.contract.artifact import Artifact
from runtime.contract.private_files import staged_private
from runtime.contract.refusal import Refusal
from runtime.contract.state_folder import artifact_path


class Staged:
    def __init__(self, temporary: Path, path: Path) -> None:
        self._temporary, self._path = temporary, path

    def commit(self) -> bool:
        """Put it in place; False when even that failed (the resource runs the
        configuration all the same, and says so)."""
        try:
            os.replace(self._temporary, self._path)
        except OSError:
            self.discard()
            return False
        return True

    def discard(self) -> None:
        with contextlib.suppress(OSError):
            os.unlink(self._temporary)


class ConfigurationStore:
    def __init__(self, state_dir: Path) -> None:
        self.path = artifact_path(state_dir)
        # what a crash in the middle of storing left behind
        for leftover in self.path.parent.glob(f".{self.path.name}.*"):
            with contextlib.suppress(OSError):
                leftover.unlink()

    def stage(self, artifact: Artifact) -> Staged:
        """The configuration written beside its place; Refusal `storage` when it cannot be
        (nothing is left behind then)."""
        try:
            temporary = staged_private(self.path, artifact.to_json().encode("ascii"))
        except OSError as exc:
            where = self.path.parent
            raise Refusal(
                "storage", f"the configuration cannot be kept in {where}: {exc.strerror or exc}"
            ) from None
        return Staged(temporary, self.path)
