"""`padt lsp`: a Language Server for padt projects, over stdio or TCP.

It only translates: LSP requests become calls of the language services on the project
(`backend/engineering/language_service.py`), their answers LSP results; positions cross in
one place (`padt/lsp_positions.py`). The project is PROJECT_DIR, or else the client's
workspace folder: every .st file in it, and its padt.toml. docs/editors.md tells how to
use it from VS Code and Neovim."""

from __future__ import annotations

import asyncio
import logging
import re
import sys
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import TypeVar

from lsprotocol import types
from pygls.exceptions import JsonRpcException
from pygls.lsp.server import LanguageServer
from pygls.uris import from_fs_path, to_fs_path

from backend.compiler.diagnostics import Diagnostic
from backend.compiler.language.completion import CompletionItem
from backend.compiler.language.outline import Symbol as OutlineSymbol
from backend.compiler.language.position import Location
from backend.engineering.language_service import (
    LanguageError,
    ProjectLanguage,
    ProjectUnreadable,
)
from padt.lsp_positions import UTF16, Lines, edited

log = logging.getLogger("padt.lsp")

# after the last keystroke, so that diagnostics follow typing without analysing every key
DEBOUNCE_S = 0.1
SEVERITY = {
    "error": types.DiagnosticSeverity.Error,
    "warning": types.DiagnosticSeverity.Warning,
    "note": types.DiagnosticSeverity.Information,
}

COMPLETION_KINDS = {
    "variable": types.CompletionItemKind.Variable,
    "member": types.CompletionItemKind.Field,
    "function": types.CompletionItemKind.Function,
    "function_block": types.CompletionItemKind.Class,
    "method": types.CompletionItemKind.Method,
    "property": types.CompletionItemKind.Property,
    "type": types.CompletionItemKind.Struct,
    "enum_value": types.CompletionItemKind.EnumMember,
    "keyword": types.CompletionItemKind.Keyword,
    "snippet": types.CompletionItemKind.Snippet,
}
SYMBOL_KINDS = {
    "program": types.SymbolKind.Module,
    "function_block": types.SymbolKind.Class,
    "function": types.SymbolKind.Function,
    "interface": types.SymbolKind.Interface,
    "method": types.SymbolKind.Method,
    "property": types.SymbolKind.Property,
    "struct": types.SymbolKind.Struct,
    "type": types.SymbolKind.Class,
    "variable": types.SymbolKind.Variable,
    "global_list": types.SymbolKind.Namespace,
    "configuration": types.SymbolKind.Package,
    "resource": types.SymbolKind.Object,
}
_PLACEHOLDER = re.compile(r"\$\{\d+(?::([^}]*))?\}|\$\d+")
_REQUEST_FAILED = types.LSPErrorCodes.RequestFailed.value

R = TypeVar("R")


class PadtLanguageServer(LanguageServer):
    """The server and what it holds for its one client: the project, the documents the
    client has open as the client has them, and what it was last told of diagnostics.

    Every call of the services runs on one worker thread, in the order the client's
    messages came: a change is taken before the requests after it, and the event loop
    never waits for an analysis (the services hold a lock while they analyse)."""

    def __init__(self, folder: Path | None) -> None:
        super().__init__("padt", _version())
        self.given_folder = folder
        self.project: ProjectLanguage | None = None
        self.worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="padt-lsp")
        self.documents: dict[str, str] = {}  # open document -> its text
        self.versions: dict[str, int] = {}  # open document -> its version
        self.published: set[str] = set()  # files last published with diagnostics
        self.generation = 0  # counts changes, so that only the newest state is published
        self.diagnosing: asyncio.Task[None] | None = None

    @property
    def encoding(self) -> str:
        encoding = self.workspace.position_encoding
        return str(getattr(encoding, "value", encoding) or UTF16)

    def language(self) -> ProjectLanguage:
        if self.project is None:
            raise JsonRpcException("the server is not initialised", code=-32002)
        return self.project

    def name_of(self, uri: str) -> str | None:
        """The project's name of a document, None for one outside the project."""
        path = to_fs_path(uri)
        return None if path is None else self.language().file_name(Path(path))

    def uri_of(self, name: str) -> str:
        return str(from_fs_path(str(self.language().folder / name)))

    def text(self, name: str) -> str:
        """A file's text as the client has it (an open document), else as the services."""
        found = self.documents.get(name)
        return self.language().text(name) if found is None else found

    def lines(self, name: str) -> Lines:
        return Lines.of(self.text(name))

    def file(self, uri: str) -> str:
        """The project's name of a document a request is about."""
        name = self.name_of(uri)
        if name is None:
            raise JsonRpcException(f"{uri} is no file of the project", code=_REQUEST_FAILED)
        return name

    def place(self, uri: str, position: types.Position) -> tuple[str, int, int]:
        """The file, line and column (from 1, in characters) of an LSP place."""
        name = self.file(uri)
        return name, *self.lines(name).place(position, self.encoding)

    def snippet_support(self) -> bool:
        completion = self.client_capabilities.text_document and (
            self.client_capabilities.text_document.completion
        )
        item = completion and completion.completion_item
        return bool(item and item.snippet_support)

    def locations(self, found: list[Location]) -> list[types.Location]:
        """The services' locations as LSP's, each file's text split once."""
        lines: dict[str, Lines] = {}
        located = []
        for location in found:
            text = lines.setdefault(location.file, self.lines(location.file))
            place = text.range(*location.range, self.encoding)
            located.append(types.Location(self.uri_of(location.file), place))
        return located

    async def answer(self, call: Callable[[], R]) -> R:
        """A service's answer, computed off the event loop (an analysis of a large project
        takes a while; notifications keep arriving meanwhile); a request the service
        refuses is a failed request with its reason."""
        try:
            return await asyncio.get_running_loop().run_in_executor(self.worker, call)
        except LanguageError as exc:
            raise JsonRpcException(str(exc), code=_REQUEST_FAILED) from None
        except Exception as exc:  # a fault of ours: said, logged, and the server goes on
            log.exception("padt lsp: a request failed")
            raise JsonRpcException(f"padt lsp failed: {exc!r}", code=_REQUEST_FAILED) from None

    async def watch_files(self) -> None:
        """Ask the client to tell of .st files and padt.toml changed, made or deleted by
        other tools (a client that cannot is told nothing; saves still count)."""
        workspace = self.client_capabilities.workspace
        watched = workspace and workspace.did_change_watched_files
        if not (watched and watched.dynamic_registration):
            return
        options = types.DidChangeWatchedFilesRegistrationOptions(
            [types.FileSystemWatcher(pattern) for pattern in ("**/*.st", "**/padt.toml")]
        )
        registration = types.Registration(
            "padt-files", types.WORKSPACE_DID_CHANGE_WATCHED_FILES, options
        )
        try:
            await self.client_register_capability_async(types.RegistrationParams([registration]))
        except Exception as exc:  # the client's refusal: the files are read again on saves
            log.warning("padt lsp: the client does not watch files: %s", exc)

    def take(self, name: str, text: str, version: int) -> None:
        """An open document's text, handed to the services in turn."""
        self.documents[name] = text
        self.versions[name] = version
        loop = asyncio.get_running_loop()

        def hand_over() -> None:
            try:
                self.language().open(name, text)
            except LanguageError as exc:  # left as the file is on disk, until opened again
                loop.call_soon_threadsafe(self.refused, name, str(exc))

        self.in_turn(hand_over)

    def refused(self, name: str, reason: str) -> None:
        self.documents.pop(name, None)
        self.versions.pop(name, None)
        self.in_turn(lambda: self.language().close(name))
        self.window_show_message(types.ShowMessageParams(types.MessageType.Error, reason))

    def in_turn(self, call: Callable[[], object]) -> None:
        """A change for the services, after the calls before it; then the diagnostics."""

        def logged() -> None:
            try:
                call()
            except Exception:  # a fault of ours: logged, and the server goes on
                log.exception("padt lsp: a change failed")

        self.worker.submit(logged)
        self.changed()

    # ---- diagnostics, published after each change once typing pauses

    def changed(self) -> None:
        self.generation += 1
        if self.diagnosing is None:
            self.diagnosing = asyncio.ensure_future(self._diagnose())

    async def _diagnose(self) -> None:
        try:
            while True:
                generation = self.generation
                await asyncio.sleep(DEBOUNCE_S)
                if generation != self.generation:
                    continue  # still typing
                try:
                    loop = asyncio.get_running_loop()
                    found = await loop.run_in_executor(self.worker, self._diagnostics)
                except Exception:  # a fault of ours: logged; the next change tries again
                    log.exception("padt lsp: the diagnostics failed")
                    return
                if generation == self.generation:  # else the texts changed meanwhile
                    self._publish(found)
                    return
        finally:
            self.diagnosing = None

    def _diagnostics(self) -> dict[str, list[types.Diagnostic]]:
        found = self.language().all_diagnostics()
        return {name: self._lsp_diagnostics(name, items) for name, items in found.items()}

    def _lsp_diagnostics(self, name: str, items: list[Diagnostic]) -> list[types.Diagnostic]:
        if not items:
            return []
        lines = Lines.of(self.language().text(name))  # the text analysed
        return [
            types.Diagnostic(
                range=lines.range(*self.language().diagnostic_range(d), self.encoding),
                message=d.message,
                severity=SEVERITY[d.severity],
                code=d.code or None,
                source="padt",
            )
            for d in items
        ]

    def _publish(self, found: dict[str, list[types.Diagnostic]]) -> None:
        told = {name for name, items in found.items() if items}
        for name in sorted(told | self.published | set(self.versions)):
            params = types.PublishDiagnosticsParams(
                self.uri_of(name), found.get(name, []), self.versions.get(name)
            )
            self.text_document_publish_diagnostics(params)
        self.published = told


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("padt")
    except PackageNotFoundError:
        return "0"


def make_server(folder: Path | None) -> PadtLanguageServer:
    server = PadtLanguageServer(folder)

    @server.feature(types.INITIALIZE)
    def initialize(ls: PadtLanguageServer, params: types.InitializeParams) -> None:
        try:
            ls.project = ProjectLanguage(ls.given_folder or _workspace_folder(params))
        except ProjectUnreadable as exc:
            raise JsonRpcException(str(exc), code=_REQUEST_FAILED) from None
        log.info("padt lsp: project %s", ls.project.folder)

    @server.feature(types.INITIALIZED)
    async def initialized(ls: PadtLanguageServer, params: types.InitializedParams) -> None:
        ls.changed()  # the project's diagnostics before anything is opened
        await ls.watch_files()

    @server.feature(types.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls: PadtLanguageServer, params: types.DidOpenTextDocumentParams) -> None:
        name = ls.name_of(params.text_document.uri)
        if name is not None:
            ls.take(name, params.text_document.text, params.text_document.version)

    @server.feature(types.TEXT_DOCUMENT_DID_CHANGE)
    def did_change(ls: PadtLanguageServer, params: types.DidChangeTextDocumentParams) -> None:
        name = ls.name_of(params.text_document.uri)
        if name is None or name not in ls.documents:
            return
        text = ls.documents[name]
        for change in params.content_changes:
            text = edited(text, change, ls.encoding)
        ls.take(name, text, params.text_document.version)

    @server.feature(types.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls: PadtLanguageServer, params: types.DidCloseTextDocumentParams) -> None:
        name = ls.name_of(params.text_document.uri)
        if name is None or ls.documents.pop(name, None) is None:
            return
        ls.versions.pop(name, None)
        ls.in_turn(lambda: ls.language().close(name))

    @server.feature(types.TEXT_DOCUMENT_DID_SAVE)
    def did_save(ls: PadtLanguageServer, params: types.DidSaveTextDocumentParams) -> None:
        ls.in_turn(ls.language().reread)

    @server.feature(types.WORKSPACE_DID_CHANGE_WATCHED_FILES)
    def files_changed(ls: PadtLanguageServer, params: types.DidChangeWatchedFilesParams) -> None:
        ls.in_turn(ls.language().reread)  # another tool changed, added or deleted files

    @server.feature(
        types.TEXT_DOCUMENT_COMPLETION, types.CompletionOptions(trigger_characters=[".", "#"])
    )
    async def completion(
        ls: PadtLanguageServer, params: types.CompletionParams
    ) -> types.CompletionList:
        name, line, col = ls.place(params.text_document.uri, params.position)
        found = await ls.answer(lambda: ls.language().complete(name, line, col))
        snippets = ls.snippet_support()
        return types.CompletionList(
            is_incomplete=False, items=[_completion_item(item, snippets) for item in found]
        )

    @server.feature(types.TEXT_DOCUMENT_HOVER)
    async def hover(ls: PadtLanguageServer, params: types.HoverParams) -> types.Hover | None:
        name, line, col = ls.place(params.text_document.uri, params.position)
        found = await ls.answer(lambda: ls.language().hover(name, line, col))
        if found is None:
            return None
        return types.Hover(
            contents=types.MarkupContent(types.MarkupKind.Markdown, found.markdown),
            range=ls.lines(name).range(*found.range, ls.encoding),
        )

    @server.feature(types.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    async def document_symbols(
        ls: PadtLanguageServer, params: types.DocumentSymbolParams
    ) -> list[types.DocumentSymbol]:
        name = ls.name_of(params.text_document.uri)
        if name is None:
            return []
        found = await ls.answer(lambda: ls.language().outline(name))
        lines = ls.lines(name)
        return [_document_symbol(symbol, lines, ls.encoding) for symbol in found]

    @server.feature(types.TEXT_DOCUMENT_PREPARE_RENAME)
    async def prepare_rename(
        ls: PadtLanguageServer, params: types.PrepareRenameParams
    ) -> types.Range | None:
        name, line, col = ls.place(params.text_document.uri, params.position)
        found = await ls.answer(lambda: ls.language().renamed_at(name, line, col))
        return None if found is None else ls.lines(name).range(*found, ls.encoding)

    @server.feature(types.TEXT_DOCUMENT_RENAME, types.RenameOptions(prepare_provider=True))
    async def rename(ls: PadtLanguageServer, params: types.RenameParams) -> types.WorkspaceEdit:
        name, line, col = ls.place(params.text_document.uri, params.position)
        found = await ls.answer(lambda: ls.language().rename(name, line, col, params.new_name))
        if found.refusal:
            raise JsonRpcException(found.refusal, code=_REQUEST_FAILED)
        changes = {}
        for edits in found.files:
            lines = ls.lines(edits.file)
            changes[ls.uri_of(edits.file)] = [
                types.TextEdit(lines.range(*edit.range, ls.encoding), edit.new_text)
                for edit in edits.edits
            ]
        return types.WorkspaceEdit(changes=changes)

    @server.feature(types.TEXT_DOCUMENT_FORMATTING)
    async def formatting(
        ls: PadtLanguageServer, params: types.DocumentFormattingParams
    ) -> list[types.TextEdit]:
        name = ls.file(params.text_document.uri)
        found = await ls.answer(lambda: ls.language().formatted(name))
        if found.refusal:
            raise JsonRpcException(found.refusal, code=_REQUEST_FAILED)
        return _line_edits(ls.lines(name), found.text, ls.encoding)

    @server.feature(types.WORKSPACE_SYMBOL)
    async def project_symbols(
        ls: PadtLanguageServer, params: types.WorkspaceSymbolParams
    ) -> list[types.SymbolInformation]:
        found = await ls.answer(lambda: ls.language().project_symbols(params.query))
        lines: dict[str, Lines] = {}
        return [
            types.SymbolInformation(
                name=symbol.name,
                kind=SYMBOL_KINDS.get(symbol.kind, types.SymbolKind.Variable),
                location=types.Location(
                    ls.uri_of(name),
                    lines.setdefault(name, ls.lines(name)).range(
                        *symbol.selection_range, ls.encoding
                    ),
                ),
                container_name=symbol.detail or None,
            )
            for name, symbol in found
        ]

    @server.feature(types.TEXT_DOCUMENT_DEFINITION)
    async def definition(
        ls: PadtLanguageServer, params: types.DefinitionParams
    ) -> types.Location | None:
        name, line, col = ls.place(params.text_document.uri, params.position)
        found = await ls.answer(lambda: ls.language().definition(name, line, col))
        return None if found is None else ls.locations([found])[0]

    @server.feature(types.TEXT_DOCUMENT_REFERENCES)
    async def references(
        ls: PadtLanguageServer, params: types.ReferenceParams
    ) -> list[types.Location]:
        name, line, col = ls.place(params.text_document.uri, params.position)
        found = await ls.answer(lambda: ls.language().references(name, line, col))
        if not params.context.include_declaration:
            declared = await ls.answer(lambda: ls.language().definition(name, line, col))
            found = [location for location in found if location != declared]
        return ls.locations(found)

    return server


def _completion_item(item: CompletionItem, snippets: bool) -> types.CompletionItem:
    snippet = item.snippet and snippets
    documentation = item.documentation or None
    return types.CompletionItem(
        label=item.label,
        kind=COMPLETION_KINDS.get(item.kind, types.CompletionItemKind.Text),
        detail=item.detail or None,
        documentation=documentation
        and types.MarkupContent(types.MarkupKind.Markdown, documentation),
        insert_text=item.insert_text if snippet or not item.snippet else _plain(item.insert_text),
        insert_text_format=(
            types.InsertTextFormat.Snippet if snippet else types.InsertTextFormat.PlainText
        ),
    )


def _plain(snippet: str) -> str:
    """A snippet as plain text, for a client without snippets: each placeholder its default."""
    return _PLACEHOLDER.sub(lambda match: match.group(1) or "", snippet)


def _document_symbol(symbol: OutlineSymbol, lines: Lines, encoding: str) -> types.DocumentSymbol:
    return types.DocumentSymbol(
        name=symbol.name,
        kind=SYMBOL_KINDS.get(symbol.kind, types.SymbolKind.Variable),
        range=lines.range(*symbol.range, encoding),
        selection_range=lines.range(*symbol.selection_range, encoding),
        detail=symbol.detail or None,
        children=[_document_symbol(child, lines, encoding) for child in symbol.children],
    )


def _line_edits(before: Lines, after: str, encoding: str) -> list[types.TextEdit]:
    """The edits from one text to another, a line each where they differ (formatting keeps
    the lines; should their number differ, the whole text at once)."""
    new = Lines.of(after)
    count = len(before.starts)
    if len(new.starts) != count:
        end = before.position(count, len(before.line(count - 1)) + 1, encoding)
        return [types.TextEdit(types.Range(types.Position(0, 0), end), after)]
    return [
        types.TextEdit(
            before.range(n + 1, 1, n + 1, len(before.line(n)) + 1, encoding), new.line(n)
        )
        for n in range(count)
        if before.line(n) != new.line(n)
    ]


def _workspace_folder(params: types.InitializeParams) -> Path:
    """The client's workspace: its first folder, else its root, else here."""
    uris = [folder.uri for folder in params.workspace_folders or []]
    uris.append(params.root_uri or "")
    for uri in uris:
        path = to_fs_path(uri) if uri else None
        if path is not None and Path(path).is_dir():
            return Path(path)
    if params.root_path and Path(params.root_path).is_dir():
        return Path(params.root_path)
    return Path.cwd()


def serve(folder: Path | None, tcp: tuple[str, int] | None) -> int:
    """Serve one client until it exits: on stdin/stdout, or on a TCP port."""
    logging.basicConfig(stream=sys.stderr, level=logging.WARNING)
    server = make_server(folder)
    if tcp is None:
        server.start_io()
    else:
        server.start_tcp(*tcp)
    return 0
