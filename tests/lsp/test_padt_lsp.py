"""`padt lsp` as an editor meets it: the real command line started as a subprocess, a real
LSP client (pytest-lsp) speaking to it over stdio, on a copy of the demo project and on
OSCAT files. What is asserted is what the editor would show."""

from __future__ import annotations

import asyncio
import shutil
import sys
from collections.abc import AsyncIterator, Callable, Sequence
from pathlib import Path

import pytest
import pytest_asyncio
from lsprotocol import types
from pygls.exceptions import JsonRpcException
from pytest_lsp import ClientServerConfig, LanguageClient, client_capabilities

from backend.engineering.project import demo_project_path

TIMEOUT_S = 120.0  # a loaded machine analyses slowly; the loops below end when it is there


async def until(condition: Callable[[], object], what: str) -> None:
    loop = asyncio.get_running_loop()
    deadline = loop.time() + TIMEOUT_S
    while not condition():
        assert loop.time() < deadline, f"no {what} within {TIMEOUT_S} s"
        await asyncio.sleep(0.05)


async def start(folder: Path, *, root: Path | None = None) -> LanguageClient:
    command = [sys.executable, "-m", "padt.cli", "lsp"]
    command += [] if root is not None else [str(folder)]
    client = await ClientServerConfig(command).start()
    assert isinstance(client, LanguageClient)
    await client.initialize_session(
        types.InitializeParams(
            capabilities=client_capabilities("visual-studio-code"),
            root_uri=(root or folder).as_uri(),
        )
    )
    return client


VALVE = """FUNCTION_BLOCK Valve
VAR_INPUT
  command : BOOL;  (* open the valve *)
END_VAR
VAR_OUTPUT
  isOpen : BOOL;
END_VAR
isOpen := command;
END_FUNCTION_BLOCK
"""
# a comment of characters of two and four UTF-8 bytes and of two UTF-16 units before names
WIDE = "(* Füllstand ≥ 5 m³ 😀 *) "


@pytest.fixture
def demo(tmp_path: Path) -> Path:
    """The demo project with a second file: a function block the program uses, called on a
    line after a comment of wide characters."""
    folder = Path(shutil.copytree(demo_project_path(), tmp_path / "demo"))
    (folder / "valve.st").write_text(VALVE)
    tank = folder / "tank.st"
    text = tank.read_text().replace("VAR\n  level", "VAR\n  inlet : Valve;\n  level", 1)
    text = text.replace("END_PROGRAM", f"{WIDE}inlet(command := pump);\nEND_PROGRAM", 1)
    tank.write_text(text)
    return folder


def place(path: Path, line_text: str, word: str, nth: int = 0) -> types.Position:
    """The LSP position (UTF-16) of `word` in the first line that starts with `line_text`."""
    lines = path.read_text().splitlines()
    line = next(i for i, text in enumerate(lines) if text.startswith(line_text))
    before = lines[line][: lines[line].index(word)]
    return types.Position(line, len(before.encode("utf-16-le")) // 2)


@pytest_asyncio.fixture
async def client(demo: Path) -> AsyncIterator[LanguageClient]:
    client = await start(demo)
    yield client
    await client.shutdown_session()
    await client.stop()  # type: ignore[no-untyped-call]


def open_document(client: LanguageClient, path: Path, text: str | None = None) -> str:
    uri = path.as_uri()
    item = types.TextDocumentItem(uri, "iec-st", 1, path.read_text() if text is None else text)
    client.text_document_did_open(types.DidOpenTextDocumentParams(item))
    return uri


def diagnostics(client: LanguageClient, uri: str) -> Sequence[types.Diagnostic]:
    return client.diagnostics.get(uri, [])


@pytest.mark.asyncio
async def test_the_demo_is_clean_and_a_type_error_is_underlined_where_it_is(
    client: LanguageClient, demo: Path
) -> None:
    tank = demo / "tank.st"
    uri = open_document(client, tank)
    await until(lambda: uri in client.diagnostics, "diagnostics of tank.st")
    assert not diagnostics(client, uri)
    line = tank.read_text().splitlines().index("  level := tankLevel;")
    change = types.TextDocumentContentChangePartial(
        range=types.Range(types.Position(line, 11), types.Position(line, 20)), text="TRUE"
    )
    client.text_document_did_change(
        types.DidChangeTextDocumentParams(
            types.VersionedTextDocumentIdentifier(uri=uri, version=2), [change]
        )
    )
    await until(lambda: diagnostics(client, uri), "a diagnostic after the change")
    [found] = diagnostics(client, uri)
    assert found.code == "E0209" and found.source == "padt"
    assert found.severity == types.DiagnosticSeverity.Error
    assert "cannot assign BOOL to INT" in found.message
    assert found.range == types.Range(types.Position(line, 11), types.Position(line, 15))


@pytest.mark.asyncio
async def test_definition_and_references_across_files(client: LanguageClient, demo: Path) -> None:
    tank, valve = demo / "tank.st", demo / "valve.st"
    uri = open_document(client, tank)
    call = place(tank, WIDE, "inlet")
    assert call.character == len(WIDE) + 1  # the emoji is two units of UTF-16
    document = types.TextDocumentIdentifier(uri)
    found = await client.text_document_definition_async(types.DefinitionParams(document, call))
    declared = place(tank, "  inlet : Valve", "inlet")
    end = types.Position(declared.line, declared.character + len("inlet"))
    assert found == types.Location(uri, types.Range(declared, end))

    command = place(tank, WIDE, "command")
    found = await client.text_document_definition_async(types.DefinitionParams(document, command))
    declared = place(valve, "  command", "command")
    end = types.Position(declared.line, declared.character + len("command"))
    assert found == types.Location(valve.as_uri(), types.Range(declared, end))

    used = place(tank, "  inlet : Valve", "Valve")
    params = types.ReferenceParams(
        context=types.ReferenceContext(True), text_document=document, position=used
    )
    found = await client.text_document_references_async(params)
    assert found is not None
    assert sorted((f.uri, f.range.start.line) for f in found) == [
        (uri, used.line),
        (valve.as_uri(), 0),
    ]
    without = types.ReferenceParams(
        context=types.ReferenceContext(False), text_document=document, position=used
    )
    found = await client.text_document_references_async(without)
    assert [f.uri for f in found or []] == [uri]


def change(client: LanguageClient, uri: str, version: int, at: types.Position, text: str) -> None:
    """Text typed at a place, as an editor sends it (an incremental change)."""
    edit = types.TextDocumentContentChangePartial(range=types.Range(at, at), text=text)
    client.text_document_did_change(
        types.DidChangeTextDocumentParams(
            types.VersionedTextDocumentIdentifier(uri=uri, version=version), [edit]
        )
    )


async def complete(
    client: LanguageClient, uri: str, at: types.Position
) -> list[types.CompletionItem]:
    found = await client.text_document_completion_async(
        types.CompletionParams(text_document=types.TextDocumentIdentifier(uri), position=at)
    )
    assert isinstance(found, types.CompletionList)
    return list(found.items)


@pytest.mark.asyncio
async def test_completion_of_a_prefix_and_of_an_instance_s_members(
    client: LanguageClient, demo: Path
) -> None:
    tank = demo / "tank.st"
    uri = open_document(client, tank)
    await until(lambda: uri in client.diagnostics, "the first diagnostics")
    # a new line typed after the wide comment: `tankL`, then the completion list
    end = place(tank, WIDE, ";")
    at = types.Position(end.line, end.character + 1)
    change(client, uri, 2, at, " tankL")
    typed = types.Position(at.line, at.character + len(" tankL"))
    items = await complete(client, uri, typed)
    first = items[0]
    assert first.label == "tankLevel" and first.kind == types.CompletionItemKind.Variable
    assert first.detail is not None and "INT" in first.detail

    # `refillDelay.`: the TON's inputs and outputs, while the line does not parse
    change(client, uri, 3, typed, " refillDelay.")
    dot = types.Position(typed.line, typed.character + len(" refillDelay."))
    labels = {item.label for item in await complete(client, uri, dot)}
    assert {"IN", "PT", "Q", "ET"} <= labels

    # a standard function with its parameters, and IF, as snippets to fill in
    change(client, uri, 4, dot, "Q;\nLIMI")
    items = await complete(client, uri, types.Position(dot.line + 1, 4))
    assert items[0].label == "LIMIT"
    assert items[0].insert_text_format == types.InsertTextFormat.Snippet
    assert items[0].insert_text == "LIMIT(${1:MN}, ${2:IN}, ${3:MX})"
    change(client, uri, 5, types.Position(dot.line + 1, 4), "\nIF")
    items = await complete(client, uri, types.Position(dot.line + 2, 2))
    [snippet] = [item for item in items if item.kind == types.CompletionItemKind.Snippet]
    assert snippet.label == "IF" and "END_IF;" in (snippet.insert_text or "")


@pytest.mark.asyncio
async def test_hover_shows_type_declaration_and_comment(client: LanguageClient, demo: Path) -> None:
    tank = demo / "tank.st"
    uri = open_document(client, tank)
    at = place(tank, "  level := tankLevel", "tankLevel")
    found = await client.text_document_hover_async(
        types.HoverParams(text_document=types.TextDocumentIdentifier(uri), position=at)
    )
    assert found is not None and isinstance(found.contents, types.MarkupContent)
    assert found.contents.kind == types.MarkupKind.Markdown
    text = found.contents.value
    assert "tankLevel" in text and "INT" in text and "the plant's level in litres" in text
    assert found.range == types.Range(at, types.Position(at.line, at.character + 9))


@pytest.mark.asyncio
async def test_outline_of_a_file(client: LanguageClient, demo: Path) -> None:
    tank = demo / "tank.st"
    uri = open_document(client, tank)
    found = await client.text_document_document_symbol_async(
        types.DocumentSymbolParams(text_document=types.TextDocumentIdentifier(uri))
    )
    assert found is not None
    symbols = [s for s in found if isinstance(s, types.DocumentSymbol)]
    assert [s.name for s in symbols][:1] == ["TankControl"]
    program = symbols[0]
    assert program.kind == types.SymbolKind.Module
    children = {child.name: child for child in program.children or []}
    assert {"inlet", "level", "refillDelay"} <= set(children)
    assert children["inlet"].selection_range.start == place(tank, "  inlet : Valve", "inlet")


@pytest.mark.asyncio
async def test_rename_across_files_and_a_refused_one(client: LanguageClient, demo: Path) -> None:
    tank, valve = demo / "tank.st", demo / "valve.st"
    uri = open_document(client, tank)
    document = types.TextDocumentIdentifier(uri)
    at = place(tank, WIDE, "command")  # the input of Valve, named in the call after 😀
    ready = await client.text_document_prepare_rename_async(
        types.PrepareRenameParams(text_document=document, position=at)
    )
    assert ready == types.Range(at, types.Position(at.line, at.character + len("command")))
    found = await client.text_document_rename_async(
        types.RenameParams(text_document=document, position=at, new_name="openIt")
    )
    assert found is not None and found.changes is not None
    assert {u: len(edits) for u, edits in found.changes.items()} == {
        uri: 1,
        valve.as_uri(): 2,  # its declaration and `isOpen := command;`
    }
    [edit] = found.changes[uri]
    assert edit.new_text == "openIt" and edit.range.start == at
    # nothing is written: the edits are the client's to apply
    assert "command" in valve.read_text()

    with pytest.raises(JsonRpcException, match="'IF' is a keyword of the language"):
        await client.text_document_rename_async(
            types.RenameParams(text_document=document, position=at, new_name="IF")
        )
