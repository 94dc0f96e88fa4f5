"""The Documentation screen as a user sees it: the document of the configuration the
resource runs (from its backup) compared with an earlier backup, downloaded as a PDF and
read back page by page; a read-only user may not make one."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from backend.engineering.backup import BackupInfo, write_backup
from backend.engineering.project import compile_project, load_project
from tests.support.browser import chromium
from tests.ui.browser_steps import (
    PASSWORD,
    Plant,
    choose,
    log_in_to_resource,
    open_as,
    open_tab,
    shoot_both,
    text_of,
    wait_until,
)

pytestmark = pytest.mark.browser


def backup_of(folder: Path, backups: Path, time_s: int) -> tuple[Path, str]:
    project = load_project([folder])
    artifact = compile_project(project).artifact
    assert artifact is not None
    path = write_backup(
        backups,
        BackupInfo(project.name, project.version, "Tank1", "load", "padt load"),
        artifact.to_json(),
        {s.name: s.text for s in project.sources},
        (folder / "padt.toml").read_text(),
        clock=lambda: time_s * 1_000_000_000,
    )
    return path, artifact.crc


def test_download_the_running_configuration_compared_with_a_backup(
    plant: Plant, tmp_path: Path
) -> None:
    older = tmp_path / "older"
    shutil.copytree(tmp_path / "project", older)
    tank = older / "tank.st"
    tank.write_text(tank.read_text().replace("T#2s", "T#3s"))
    old_backup, old_crc = backup_of(older, tmp_path / "bak", 1_700_000_000)
    _, crc = backup_of(tmp_path / "project", tmp_path / "bak", 1_700_000_100)
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_as(page, plant, "viewer")
        log_in_to_resource(page, "viewer", PASSWORD)
        open_tab(page, "Documentation")
        running = f"the configuration the resource runs (Tank1, CRC {crc})"
        choose(page, "Document of", running)
        choose(page, "Compare with", f"backup {old_backup.name}")
        shoot_both(page, "documentation")
        with page.expect_download(timeout=120_000) as download:
            page.get_by_role("button", name="Download document").click()
        saved = tmp_path / "downloaded.pdf"
        download.value.save_as(saved)
        assert download.value.suggested_filename == "Demo_tank.pdf"
        wait_until(
            "the screen says what it made",
            lambda: text_of(page, '[data-testid="docs-note"]').startswith("Demo_tank.pdf"),
        )
        shoot_both(page, "documentation-done")
    text = subprocess.run(
        ["pdftotext", "-layout", str(saved), "-"], capture_output=True, text=True, check=True
    ).stdout
    pages = text.split("\f")[:-1]
    for number, page_text in enumerate(pages, 1):
        assert "Demo tank" in page_text and f"CRC {crc}" in page_text, number
        assert f"page {number} of {len(pages)}" in page_text, number
    flat = " ".join(text.split())
    assert f"configuration CRC {old_crc} {crc}" in flat
    assert re.search(r"-13 restartDelay : TIME := T#3s; \+13 restartDelay : TIME := T#2s;", flat)


def test_a_read_only_user_may_not_make_documents(plant: Plant) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        open_as(page, plant, "guest")
        open_tab(page, "Documentation")
        button = page.get_by_role("button", name="Download document")
        button.wait_for(timeout=20_000)
        assert button.is_disabled()
        assert "needs Read+Write" in text_of(page, '[data-testid="docs-note"]')
