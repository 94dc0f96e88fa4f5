"""The printable documentation over the REST API, on a real HTTP port: a project's PDF and
HTML, compared with another project served or a backup, and the refusals."""

from __future__ import annotations

import subprocess
from collections.abc import Iterator

import pytest

from backend.engineering.backup import BackupInfo, write_backup
from backend.engineering.project import compile_project, load_project
from tests.api.test_rest_api import error
from tests.support.rest_plant import Plant, plant

ROUTE = "/api/projects/{}/documentation"


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Plant]:
    with plant(tmp_path_factory.mktemp("rest-docs")) as found:
        yield found


def pdf_text(data: bytes) -> str:
    return subprocess.run(
        ["pdftotext", "-layout", "-", "-"], input=data, capture_output=True, check=True
    ).stdout.decode()


def test_pdf_and_html_of_a_project(site: Plant) -> None:
    token = site.token("builder")
    reply = site.call("GET", ROUTE.format("plant"), token)
    assert reply.status_code == 200, reply.text
    assert reply.headers["content-type"] == "application/pdf"
    assert reply.headers["content-disposition"] == 'attachment; filename="Plant.pdf"'
    crc = compile_project(load_project([site.projects / "plant"])).artifact.crc  # type: ignore[union-attr]
    pages = pdf_text(reply.content).split("\f")[:-1]
    assert all(f"CRC {crc}" in page and "Plant" in page for page in pages)
    html = site.call("GET", ROUTE.format("plant"), token, params={"format": "html"})
    assert html.headers["content-type"].startswith("text/html")
    assert f"Configuration CRC <code>{crc}</code>" in html.text


def test_compared_with_a_project_and_with_a_backup(site: Plant) -> None:
    token = site.token("builder")
    reply = site.call("GET", ROUTE.format("plant_v2"), token, params={"compare": "plant"})
    text = " ".join(pdf_text(reply.content).split())
    assert "Version comparison" in text and "variable P.m added" in text
    project = load_project([site.projects / "plant"])
    artifact = compile_project(project).artifact
    assert artifact is not None
    backup = write_backup(
        site.backups,
        BackupInfo("Plant", "1", "Plant", "load", "padt load"),
        artifact.to_json(),
        {s.name: s.text for s in project.sources},
        (site.projects / "plant" / "padt.toml").read_text(),
    )
    reply = site.call("GET", ROUTE.format("plant_v2"), token, params={"compare": backup.name})
    assert reply.status_code == 200, reply.text
    assert f"configuration CRC {artifact.crc}" in " ".join(pdf_text(reply.content).split())


def test_refusals(site: Plant) -> None:
    builder = site.token("builder")
    reader = site.token("reader")
    assert "read-only" in error(site.call("GET", ROUTE.format("plant"), reader), 403, "forbidden")
    error(site.call("GET", ROUTE.format("nothing"), builder), 404, "unknown_project")
    for name in ("../padt-accounts.json", "/etc/passwd", "..zip", "x/../y.zip"):
        reply = site.call("GET", ROUTE.format("plant"), builder, params={"compare": name})
        assert "neither a project nor a backup" in error(reply, 422, "project"), name
    missing = site.call("GET", ROUTE.format("plant"), builder, params={"compare": "gone.zip"})
    assert "there is no backup 'gone.zip'" in error(missing, 422, "project")
    bad_format = site.call("GET", ROUTE.format("plant"), builder, params={"format": "doc"})
    assert bad_format.status_code == 400
