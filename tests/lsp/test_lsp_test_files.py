"""`padt lsp` on a project's test files (docs/testing.md): a test file is analysed with the
project's sources as `padt test` compiles it, so the test functions are known, offered and
explained there; the project's own files are analysed as a download compiles them, without
the tests. The real command line over stdio, a real LSP client, on a copy of the demo,
whose test/ folder holds its tank tests."""

from __future__ import annotations

import shutil
from collections.abc import AsyncIterator
from pathlib import Path

import pytest
import pytest_asyncio
from lsprotocol import types
from pytest_lsp import LanguageClient

from backend.engineering.project import demo_project_path
from tests.lsp.test_padt_lsp import (
    change,
    complete,
    diagnostics,
    open_document,
    place,
    start,
    until,
)

TESTS = "test/tank_test.st"


@pytest.fixture
def demo(tmp_path: Path) -> Path:
    return Path(shutil.copytree(demo_project_path(), tmp_path / "demo"))


@pytest_asyncio.fixture
async def client(demo: Path) -> AsyncIterator[LanguageClient]:
    client = await start(demo)
    yield client
    await client.shutdown_session()
    await client.stop()  # type: ignore[no-untyped-call]


@pytest.mark.asyncio
async def test_a_test_file_knows_the_test_functions_offers_and_explains_them(
    client: LanguageClient, demo: Path
) -> None:
    tests = demo / TESTS
    uri = open_document(client, tests)
    await until(lambda: uri in client.diagnostics, "diagnostics of the test file")
    assert not diagnostics(client, uri)  # ASSERT_EQUAL, RUN_CYCLES...: no unknown function

    at = place(tests, "ASSERT_EQUAL(500", "ASSERT_EQUAL")
    found = await client.text_document_hover_async(
        types.HoverParams(text_document=types.TextDocumentIdentifier(uri), position=at)
    )
    assert found is not None and isinstance(found.contents, types.MarkupContent)
    assert "ASSERT_EQUAL(EXPECTED, ACTUAL [, MESSAGE])" in found.contents.value
    assert "The test fails unless EXPECTED and ACTUAL" in found.contents.value

    # `ASSERT_N` typed on a line of its own: the asserts with their parameters to fill in
    end = place(tests, "RUN_CYCLES(1);", "RUN_CYCLES")
    line_end = types.Position(end.line, len("RUN_CYCLES(1);"))
    change(client, uri, 2, line_end, "\nASSERT_N")
    items = await complete(client, uri, types.Position(end.line + 1, len("ASSERT_N")))
    by_label = {item.label: item for item in items}
    near = by_label["ASSERT_NEAR"]
    assert near.insert_text_format == types.InsertTextFormat.Snippet
    assert (
        near.insert_text == "ASSERT_NEAR(${1:EXPECTED}, ${2:ACTUAL}, ${3:TOLERANCE}, ${4:MESSAGE})"
    )
    assert "ASSERT_NOT_EQUAL" in by_label

    # the program's own file is no test file: no test function offered there
    tank = demo / "tank.st"
    tank_uri = open_document(client, tank)
    typed = place(tank, "  level := tankLevel;", "level")
    change(client, tank_uri, 2, typed, "ASSERT_")
    items = await complete(client, tank_uri, types.Position(typed.line, typed.character + 7))
    assert not [item for item in items if item.label.startswith("ASSERT_")]


@pytest.mark.asyncio
async def test_a_test_file_s_error_is_its_own_and_a_program_never_sees_a_test_s_pou(
    client: LanguageClient, demo: Path
) -> None:
    tests, tank = demo / TESTS, demo / "tank.st"
    # a wrong assert in the test file: its problem, not the program's
    text = tests.read_text().replace("ASSERT_EQUAL(500,", "ASSERT_EQUAL(TRUE,", 1)
    uri = open_document(client, tests, text)
    await until(lambda: diagnostics(client, uri), "the test file's problem")
    [problem] = diagnostics(client, uri)
    assert "ASSERT_EQUAL" in problem.message and problem.range.start.line == (
        place(tests, "ASSERT_EQUAL(500", "ASSERT_EQUAL").line
    )

    # the program declares an instance of the test suite: as in a download, it is unknown
    used = tank.read_text().replace("VAR\n  level", "VAR\n  suite : TankTests;\n  level", 1)
    tank_uri = open_document(client, tank, used)
    await until(lambda: diagnostics(client, tank_uri), "the program's problem")
    assert any("TankTests" in d.message for d in diagnostics(client, tank_uri))
    assert len(diagnostics(client, uri)) == 1  # the test file's problem stays its own


@pytest.mark.asyncio
async def test_the_tests_are_found_among_the_project_s_symbols_and_references(
    client: LanguageClient, demo: Path
) -> None:
    found = await client.workspace_symbol_async(types.WorkspaceSymbolParams(query="TankTests"))
    assert [
        (s.name, s.location.uri) for s in found or [] if isinstance(s, types.SymbolInformation)
    ] == [("TankTests", (demo / TESTS).as_uri())]
    # where the program is used: its file, and the tests that read its variables
    tank = demo / "tank.st"
    uri = open_document(client, tank)
    params = types.ReferenceParams(
        context=types.ReferenceContext(True),
        text_document=types.TextDocumentIdentifier(uri),
        position=place(tank, "PROGRAM TankControl", "TankControl"),
    )
    used = await client.text_document_references_async(params)
    assert {f.uri for f in used or []} == {uri, (demo / TESTS).as_uri()}
