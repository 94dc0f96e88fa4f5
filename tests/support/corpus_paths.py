"""Where the shared third-party corpus lives, and the rule for its absence."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.conftest import REPO

CORPUS = REPO.parent / "shared" / "corpus"


def corpus_dir(name: str) -> Path:
    """The corpus folder; skips the test when it is absent, except in CI, where it must exist."""
    folder = CORPUS / name
    if not folder.is_dir():
        if os.environ.get("CI") == "true":
            pytest.fail(f"corpus folder {folder} is missing (CI never skips corpus tests)")
        pytest.skip(f"corpus folder {folder} is absent: put shared/corpus beside the repo")
    return folder


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
