"""`padt lsp` as an editor meets it: the real command line started as a subprocess, a real
LSP client (pytest-lsp) speaking to it over stdio, on a copy of the demo project and on
OSCAT files. What is asserted is what the editor would show."""

from __future__ import annotations

import asyncio
import shutil
import subprocess
import sys
from collections.abc import AsyncIterator, Callable, Sequence
from pathlib import Path

import pytest
import pytest_asyncio
from lsprotocol import types
from pygls.exceptions import JsonRpcException
from pytest_lsp import (
    ClientServerConfig,
    LanguageClient,
    client_capabilities,
    make_test_lsp_client,
)

from backend.engineering.project import demo_project_path
from tests.conftest import free_port
from tests.support.corpus_paths import corpus_dir

TIMEOUT_S = 120.0  # a loaded machine analyses slowly; the loops below end when it is there


async def until(condition: Callable[[], object], what: str) -> None:
    loop = asyncio.get_running_loop()
    deadline = loop.time() + TIMEOUT_S
    while not condition():
        assert loop.time() < deadline, f"no {what} within {TIMEOUT_S} s"
        await asyncio.sleep(0.05)


# what each client was asked to watch (client/registerCapability), by the client's id
WATCHED: dict[int, list[types.Registration]] = {}


def watching_client() -> LanguageClient:
    """pytest-lsp's client, answering the server's request to watch files as VS Code does."""
    client = make_test_lsp_client()
    WATCHED[id(client)] = []

    @client.feature(types.CLIENT_REGISTER_CAPABILITY)  # type: ignore[untyped-decorator]
    def registered(params: types.RegistrationParams) -> None:
        WATCHED[id(client)].extend(params.registrations)

    return client


async def start(folder: Path, *, given: bool = True) -> LanguageClient:
    """`padt lsp` on stdio, for the project given on its command line or else as the
    editor's workspace folder."""
    command = [sys.executable, "-m", "padt.cli", "lsp", *([str(folder)] if given else [])]
    client = await ClientServerConfig(command, client_factory=watching_client).start()
    assert isinstance(client, LanguageClient)
    await initialize(client, folder)
    return client


async def initialize(client: LanguageClient, folder: Path) -> types.InitializeResult:
    return await client.initialize_session(
        types.InitializeParams(
            capabilities=client_capabilities("visual-studio-code"),
            workspace_folders=[types.WorkspaceFolder(folder.as_uri(), folder.name)],
        )
    )


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


@pytest.mark.asyncio
async def test_the_workspace_folder_is_the_project_and_padt_toml_gets_its_own_diagnostics(
    demo: Path,
) -> None:
    client = await start(demo, given=False)
    try:
        config = demo / "padt.toml"
        text = config.read_text().replace('pou = "TankControl"', 'pou = "TankControll"')
        uri = open_document(client, config, text)
        await until(lambda: diagnostics(client, uri), "a diagnostic of padt.toml")
        [found] = diagnostics(client, uri)
        assert found.code == "E0601" and "no PROGRAM 'TankControll'" in found.message
        # a file outside the project is not analysed, and a request on it is refused
        outside = demo.parent / "elsewhere.st"
        outside.write_text("PROGRAM X\nVAR a : INT; END_VAR\na := TRUE;\nEND_PROGRAM\n")
        other = open_document(client, outside)
        with pytest.raises(JsonRpcException, match="no file of the project"):
            await client.text_document_hover_async(
                types.HoverParams(types.TextDocumentIdentifier(other), types.Position(2, 0))
            )
        assert other not in client.diagnostics
    finally:
        await client.shutdown_session()
        await client.stop()  # type: ignore[no-untyped-call]


@pytest.mark.asyncio
async def test_what_the_server_offers(demo: Path) -> None:
    client = await ClientServerConfig(
        [sys.executable, "-m", "padt.cli", "lsp", str(demo)], client_factory=watching_client
    ).start()
    assert isinstance(client, LanguageClient)
    try:
        offered = (await initialize(client, demo)).capabilities
        sync = offered.text_document_sync
        assert isinstance(sync, types.TextDocumentSyncOptions)
        assert sync.change == types.TextDocumentSyncKind.Incremental and sync.open_close
        assert offered.position_encoding == types.PositionEncodingKind.Utf16
        assert offered.completion_provider is not None
        assert list(offered.completion_provider.trigger_characters or ()) == [".", "#"]
        assert offered.rename_provider == types.RenameOptions(prepare_provider=True)
        for provider in (
            offered.hover_provider,
            offered.definition_provider,
            offered.references_provider,
            offered.document_symbol_provider,
            offered.workspace_symbol_provider,
            offered.document_formatting_provider,
        ):
            assert provider
    finally:
        await client.shutdown_session()
        await client.stop()  # type: ignore[no-untyped-call]


@pytest.mark.asyncio
async def test_over_tcp(demo: Path) -> None:
    port = free_port()
    command = [sys.executable, "-m", "padt.cli", "lsp", "--tcp", str(port), str(demo)]
    server = subprocess.Popen(command)
    client = watching_client()
    try:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + TIMEOUT_S
        while True:
            try:
                await client.start_tcp("127.0.0.1", port)
                break
            except OSError:
                assert server.poll() is None and loop.time() < deadline, "no TCP server"
                await asyncio.sleep(0.1)
        await initialize(client, demo)
        tank = demo / "tank.st"
        uri = open_document(client, tank)
        at = place(tank, "  level := tankLevel", "tankLevel")
        found = await client.text_document_definition_async(
            types.DefinitionParams(types.TextDocumentIdentifier(uri), at)
        )
        assert isinstance(found, types.Location) and found.uri == uri
        await client.shutdown_session()
        assert server.wait(timeout=TIMEOUT_S) == 0
    finally:
        if server.poll() is None:
            server.kill()
            server.wait()
        await client.stop()  # type: ignore[no-untyped-call]


@pytest.mark.asyncio
async def test_an_oscat_file_of_4888_lines(tmp_path: Path) -> None:
    source = corpus_dir("oscat") / "st" / "BUILDING_1.0.st"
    folder = tmp_path / "oscat"
    folder.mkdir()
    building = Path(shutil.copy(source, folder / source.name))
    client = await start(folder)
    try:
        uri = open_document(client, building)
        await until(lambda: diagnostics(client, uri), "the diagnostics of BUILDING")
        severities = {d.severity for d in diagnostics(client, uri)}
        assert types.DiagnosticSeverity.Error not in severities  # it compiles, with warnings

        # BLIND_SHADE's TOF instance, where it is called: what it is, where it is declared,
        # where it is named and its rename (the same name in BLIND_SHADE_S is another one)
        call = place(building, "  sun_delay(IN := sun, PT := shade_delay);", "sun_delay")
        document = types.TextDocumentIdentifier(uri)
        hovered = await client.text_document_hover_async(types.HoverParams(document, call))
        assert hovered is not None and isinstance(hovered.contents, types.MarkupContent)
        assert "sun_delay : TOF" in hovered.contents.value
        declared = await client.text_document_definition_async(
            types.DefinitionParams(document, call)
        )
        assert isinstance(declared, types.Location)
        assert declared.range.start == place(building, "    sun_delay : TOF;", "sun_delay")
        named = await client.text_document_references_async(
            types.ReferenceParams(
                context=types.ReferenceContext(True), text_document=document, position=call
            )
        )
        lines = [found.range.start.line for found in named or []]
        assert lines == [declared.range.start.line, call.line, call.line + 2]
        renamed = await client.text_document_rename_async(
            types.RenameParams(text_document=document, position=call, new_name="shadeDelay")
        )
        assert renamed is not None and renamed.changes is not None
        assert [edit.range.start.line for edit in renamed.changes[uri]] == lines

        # below the call: `sun_delay.`, its members
        end = types.Position(call.line, len("  sun_delay(IN := sun, PT := shade_delay);"))
        change(client, uri, 2, end, "\n  sun_delay.")
        dot = types.Position(call.line + 1, len("  sun_delay."))
        labels = {item.label for item in await complete(client, uri, dot)}
        assert {"IN", "PT", "Q", "ET"} <= labels

        # errors typed there: underlined on their line (an earlier state of the text, with
        # the line half typed, may be published before)
        change(client, uri, 3, dot, "Q := 5;")

        def errors() -> list[int]:
            found = diagnostics(client, uri)
            return [
                d.range.start.line for d in found if d.severity == types.DiagnosticSeverity.Error
            ]

        await until(lambda: set(errors()) == {dot.line}, "the errors typed, alone")
        codes = {d.code for d in diagnostics(client, uri) if d.range.start.line == dot.line}
        assert codes == {"E0305", "E0209"}  # Q is the TOF's output, and BOOL
    finally:
        await client.shutdown_session()
        await client.stop()  # type: ignore[no-untyped-call]


@pytest.mark.asyncio
async def test_formatting_indents_and_upper_cases_keywords(
    client: LanguageClient, demo: Path
) -> None:
    valve = demo / "valve.st"
    messy = VALVE.replace("  command", "command").replace(
        "END_VAR\nVAR_OUTPUT", "end_var\nVAR_OUTPUT"
    )
    uri = open_document(client, valve, messy)
    edits = await client.text_document_formatting_async(
        types.DocumentFormattingParams(
            text_document=types.TextDocumentIdentifier(uri),
            options=types.FormattingOptions(tab_size=2, insert_spaces=True),
        )
    )
    assert edits is not None
    assert sorted((e.range.start.line, e.new_text) for e in edits) == [
        (2, "  command : BOOL;  (* open the valve *)"),
        (3, "END_VAR"),
    ]
    broken = types.DidChangeTextDocumentParams(
        types.VersionedTextDocumentIdentifier(uri=uri, version=2),
        [types.TextDocumentContentChangeWholeDocument(text="FUNCTION_BLOCK Valve\nVAR_INPUT")],
    )
    client.text_document_did_change(broken)
    with pytest.raises(JsonRpcException, match="does not parse"):
        await client.text_document_formatting_async(
            types.DocumentFormattingParams(
                text_document=types.TextDocumentIdentifier(uri),
                options=types.FormattingOptions(tab_size=2, insert_spaces=True),
            )
        )


FEEDER = """FUNCTION_BLOCK Feeder
VAR_INPUT on : BOOL; END_VAR
END_FUNCTION_BLOCK
VAR_GLOBAL feederSpeed : INT; END_VAR
"""


@pytest.mark.asyncio
async def test_a_file_made_by_another_tool_joins_the_project(demo: Path) -> None:
    client = await start(demo)
    watched = WATCHED[id(client)]
    try:
        await until(lambda: watched, "a request to watch the project's files")
        [registration] = watched
        assert registration.method == types.WORKSPACE_DID_CHANGE_WATCHED_FILES
        tank = demo / "tank.st"
        text = tank.read_text().replace("  inlet : Valve;", "  inlet : Valve;\n  feed : Feeder;")
        uri = open_document(client, tank, text)
        await until(lambda: diagnostics(client, uri), "the unknown type's diagnostic")
        assert "Feeder" in diagnostics(client, uri)[0].message
        # another tool saves a draft that does not parse, then the function block
        for name, source in (
            ("draft.st", "PROGRAM Draft\nx :=\n"),
            ("feeder.st", FEEDER),
        ):
            (demo / name).write_text(source)
            client.workspace_did_change_watched_files(
                types.DidChangeWatchedFilesParams(
                    [types.FileEvent((demo / name).as_uri(), types.FileChangeType.Created)]
                )
            )
        await until(lambda: not diagnostics(client, uri), "tank.st clean with Feeder known")
        assert diagnostics(client, (demo / "draft.st").as_uri())  # its syntax error

        # `feed.` typed: the line does not parse, the draft never did; Feeder's input
        end = place(tank, WIDE, ";")
        line = text.splitlines()[end.line]
        at = types.Position(end.line, len(line.encode("utf-16-le")) // 2)
        change(client, uri, 2, at, "\nfeed.")
        labels = [
            item.label for item in await complete(client, uri, types.Position(at.line + 1, 5))
        ]
        assert labels == ["on"]
        # and a global of the new file, in the scope of the POU whose line is half typed
        change(client, uri, 3, types.Position(at.line + 1, 5), "on;\nfeederS")
        items = await complete(client, uri, types.Position(at.line + 2, 7))
        assert items and items[0].label == "feederSpeed"
    finally:
        await client.shutdown_session()
        await client.stop()  # type: ignore[no-untyped-call]


async def own_symbols(client: LanguageClient, query: str) -> list[types.SymbolInformation]:
    """The symbols of the project's sources whose names hold `query`; not those of the
    demo's tests (test_lsp_test_files.py has them)."""
    found = await client.workspace_symbol_async(types.WorkspaceSymbolParams(query=query))
    assert found is not None
    return [
        s
        for s in found
        if isinstance(s, types.SymbolInformation) and "/test/" not in s.location.uri
    ]


@pytest.mark.asyncio
async def test_symbols_of_the_whole_project(client: LanguageClient, demo: Path) -> None:
    found = await own_symbols(client, "v")
    named = [(s.name, s.location.uri.rsplit("/", 1)[1]) for s in found]
    # the globals, POUs and types whose names hold it; no local variable (level)
    assert named == [("tankLevel", "tank.st"), ("Valve", "valve.st")]
    [valve] = [s for s in found if s.name == "Valve"]
    assert valve.kind == types.SymbolKind.Class and isinstance(valve.location, types.Location)
    assert valve.location.range.start == types.Position(0, len("FUNCTION_BLOCK "))
    everything = await own_symbols(client, "")
    assert [s.name for s in everything] == [
        "pumpCommand",
        "pumpRunning",
        "TankControl",
        "tankLevel",
        "Valve",
    ]
