"""Where the shared third-party corpus (and the peers) live, and the rule for their absence."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.conftest import REPO

SHARED = REPO.parent / "shared"
CORPUS = SHARED / "corpus"


def shared_dir(folder: Path) -> Path:
    """A folder of ../shared; skips the test when it is absent, except in CI, where it must
    exist."""
    if not folder.is_dir():
        if os.environ.get("CI") == "true":
            pytest.fail(f"folder {folder} is missing (CI never skips tests of ../shared)")
        pytest.skip(f"folder {folder} is absent: put shared/ beside the repo")
    return folder


def corpus_dir(name: str) -> Path:
    """The corpus folder; skips the test when it is absent, except in CI, where it must exist."""
    return shared_dir(CORPUS / name)


def known_failures(name: str) -> dict[str, str]:
    """`tests/compiler/corpus/<name>`: one `path<TAB>reason` per line; # starts a comment."""
    entries: dict[str, str] = {}
    for line in (REPO / "tests" / "compiler" / "corpus" / name).read_text().splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        path, _, reason = line.partition("\t")
        assert reason.strip(), f"{name}: {path} has no reason"
        entries[path.strip()] = reason.strip()
    return entries
