"""The compiler's language services on a project folder, for an editor that has some of
its files open: `padt lsp`, the REST API and the browser's editor each hold a
`ProjectLanguage` and only translate to their own wire.

The project is the folder's `.st` files as the compiler finds them (`project_sources`)
and its `padt.toml`; a document open in the editor stands for its file until it is
closed. Files are named as diagnostics name them: their path in the folder, with "/".

The test files of the folder's `test/` (docs/testing.md) are analysed as `padt test`
compiles them: together with the project's sources, which they use, in a second analysis.
A file of the project is analysed without them, as a download compiles it: it never sees
a test's POUs, nor the diagnostics they would cause."""

from __future__ import annotations

import re
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace
from functools import lru_cache
from pathlib import Path, PurePosixPath

from backend.compiler.diagnostics import Diagnostic
from backend.compiler.language.analysis import Analysis
from backend.compiler.language.completion import CompletionItem, complete
from backend.compiler.language.formatting import Formatted, format_file
from backend.compiler.language.hover import Hover, hover
from backend.compiler.language.language_project import LanguageProject
from backend.compiler.language.navigation import definition, references
from backend.compiler.language.outline import Symbol as OutlineSymbol
from backend.compiler.language.outline import outline
from backend.compiler.language.position import Location, Range, symbol_at
from backend.compiler.language.rename import RenameResult, rename
from backend.compiler.language.tokens import lex
from backend.compiler.limits import MAX_FILE_BYTES, MiB
from backend.compiler.pipeline import Parsed
from backend.compiler.source import source_bytes
from backend.compiler.test_functions import is_test_file
from backend.engineering.project import (
    PROJECT_FILE,
    ProjectError,
    compile_project,
    configured_project,
    project_sources,
)
from backend.engineering.testing.test_build import sources_of_tests

# what the services answer, for the adapters' annotations (they do not import the compiler)
__all__ = [
    "CompletionItem",
    "Diagnostic",
    "Formatted",
    "Hover",
    "LanguageError",
    "Location",
    "OutlineSymbol",
    "ProjectLanguage",
    "ProjectUnreadable",
    "Range",
    "RenameResult",
]

# what a search of the project's symbols finds inside a symbol of each kind
_NAMED_INSIDE = {
    "function_block": frozenset({"method", "property"}),
    "program": frozenset({"method", "property"}),
    "interface": frozenset({"method", "property"}),
    "global_list": frozenset({"variable"}),
}


class LanguageError(ValueError):
    """A request the services cannot answer: a file that is not the project's, a text too
    large; the message says which."""


class ProjectUnreadable(OSError):
    """The project's folder or one of its files cannot be read; the message says why."""


class _View:
    """One analysis over some of the texts (the project's sources alone, or with its
    tests), and the last one of it in which every open document it holds parsed."""

    def __init__(self, texts: dict[str, str]) -> None:
        self.project = LanguageProject(texts)
        # a file broken on disk and not open does not keep it old
        self.parsed: Analysis | None = None


class ProjectLanguage:
    """One editor's view of one project: the files on disk, the documents it has open over
    them, and the analysis of both. Thread-safe: the UI asks from several threads."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder.resolve()
        self._lock = threading.RLock()
        self._disk = _files_of(self.folder)
        self._open: dict[str, str] = {}
        sources = {name: text for name, text in self._disk.items() if not is_test_file(name)}
        self._sources = _View(sources)
        self._with_tests = _View(dict(self._disk))

    # ---- files and documents

    def file_name(self, path: Path) -> str | None:
        """The name of a file of this folder (an .st file or padt.toml), None for anything
        outside it or of another kind."""
        try:
            relative = path.resolve().relative_to(self.folder)
        except ValueError:
            return None
        name = relative.as_posix()
        return name if name == PROJECT_FILE or name.endswith(".st") else None

    def checked_name(self, name: str) -> str:
        """`name` as a client sent it, if it names a file of the project."""
        parts = PurePosixPath(name).parts
        if not name or name.startswith("/") or ".." in parts or "\\" in name:
            raise LanguageError(f"'{name}' is no file of the project")
        with self._lock:
            if name == PROJECT_FILE or name in self._disk or name in self._open:
                return name
        raise LanguageError(f"the project has no file '{name}'")

    def _views_of(self, name: str) -> tuple[_View, ...]:
        """The analyses a file takes part in: a test file only in the one with the tests."""
        return (self._with_tests,) if is_test_file(name) else (self._sources, self._with_tests)

    def _view(self, name: str) -> _View:
        """The analysis a file is read in: as `padt test` compiles a test file, as a
        download compiles any other."""
        return self._views_of(name)[0]

    def _whole(self) -> _View:
        """The analysis of every file, the tests' too: where a search or a rename must find
        every use of a name (the project's alone while it has no tests: the same texts)."""
        with self._lock:
            tests = any(is_test_file(name) for name in {*self._disk, *self._open})
        return self._with_tests if tests else self._sources

    def open(self, name: str, text: str) -> None:
        """The editor's text of a file, from now on instead of the file's."""
        if source_bytes(text) > MAX_FILE_BYTES:
            raise LanguageError(f"{name}: the text is larger than {MAX_FILE_BYTES // MiB} MiB")
        with self._lock:
            self._open[name] = text
            if name != PROJECT_FILE:
                for view in self._views_of(name):
                    view.project.set_text(name, text)

    def close(self, name: str) -> None:
        """The editor closed the document: the file on disk counts again."""
        with self._lock:
            if self._open.pop(name, None) is None or name == PROJECT_FILE:
                return
            for view in self._views_of(name):
                if name in self._disk:
                    view.project.set_text(name, self._disk[name])
                else:
                    view.project.remove(name)

    def reread(self) -> None:
        """The files on disk changed (saved, added, deleted by another tool)."""
        disk = _files_of(self.folder)
        with self._lock:
            for name in sorted(set(self._disk) - set(disk) - set(self._open)):
                for view in self._views_of(name):
                    view.project.remove(name)
            for name, text in sorted(disk.items()):
                if name not in self._open:
                    for view in self._views_of(name):
                        view.project.set_text(name, text)
            self._disk = disk

    def text(self, name: str) -> str:
        """A file's text as the services read it."""
        with self._lock:
            if name in self._open:
                return self._open[name]
            if name == PROJECT_FILE:
                try:
                    return self._configuration_on_disk()
                except ProjectError:
                    return ""
            return self._disk.get(name, "")

    @contextmanager
    def with_text(self, name: str, text: str | None) -> Iterator[None]:
        """For one request (the REST API's): `name` with `text`, if given, then as before."""
        with self._lock:
            before = self._open.get(name)
            if text is not None:
                self.open(name, text)
            try:
                yield
            finally:
                if before is None:
                    self.close(name)
                else:
                    self.open(name, before)

    # ---- the analysis

    def analysis(self, name: str = "") -> Analysis:
        """The analysis `name` is read in (without a name: the project's sources, as a
        download compiles them), of the texts as the editor has them (re-analysed
        incrementally after a change)."""
        return self._analysed(self._view(name))

    def _analysed(self, view: _View) -> Analysis:
        analysis = view.project.analysis()
        parsed = {unit.file for unit in analysis.units}
        with self._lock:
            if parsed >= set(analysis.texts) & set(self._open):
                view.parsed = analysis
        return analysis

    def readable(self, name: str) -> Analysis:
        """The analysis to read names from at a place of `name`: while the file does not
        parse (a line half typed), the symbols of the last analysis in which every open
        document did, over the texts as they are now; the services find the place in the
        text."""
        return self._readable(self._view(name), name)

    def _readable(self, view: _View, name: str) -> Analysis:
        analysis = self._analysed(view)
        with self._lock:
            good = view.parsed
        if good is None or any(unit.file == name for unit in analysis.units):
            return analysis
        return replace(good, texts=analysis.texts)

    def diagnostics(self, name: str) -> list[Diagnostic]:
        """The diagnostics of one file, in order of position: of an .st file the language
        services', of padt.toml the compiler's on the configuration."""
        if name == PROJECT_FILE:
            return self._configuration_diagnostics()
        return self.analysis(name).diagnostics_of(name)

    def all_diagnostics(self) -> dict[str, list[Diagnostic]]:
        """The diagnostics of every file of the project, each file's in order of position."""
        with self._lock:
            found: dict[str, list[Diagnostic]] = {name: [] for name in {*self._disk, *self._open}}
        found.pop(PROJECT_FILE, None)
        for name in found:
            found[name] = self.diagnostics(name)
        if (self.folder / PROJECT_FILE).is_file() or PROJECT_FILE in self._open:
            found[PROJECT_FILE] = self._configuration_diagnostics()
        return dict(sorted(found.items()))

    def problems(self) -> list[Diagnostic]:
        """The diagnostics of the .st files, the cause before its consequences: the
        project's sources' (as a download compiles them), then those of the test files."""
        found = list(self.analysis().diagnostics)
        whole = self._whole()
        if whole is not self._sources:
            found += [d for d in self._analysed(whole).diagnostics if is_test_file(d.file)]
        return found

    def diagnostic_range(self, diagnostic: Diagnostic) -> tuple[int, int, int, int]:
        """Where an editor underlines a diagnostic: the token it points at, else the one
        character (line, col, end line, end col; the end exclusive). Only its line is
        read: after each keystroke, lexing a file of thousands of lines again would cost
        more than the diagnostics themselves."""
        line, col = diagnostic.line, diagnostic.col
        end_col = col + 1
        if diagnostic.file != PROJECT_FILE:
            lexed = lex(_line(self.text(diagnostic.file), line))
            index = lexed.index_at(1, col)
            token = lexed.tokens[index] if index < len(lexed.tokens) else None
            if token is not None and token.col == col:
                end_col = token.end_col
        return line, col, line, end_col

    def _configuration_diagnostics(self) -> list[Diagnostic]:
        with self._lock:
            text = self._open.get(PROJECT_FILE)
            if text is None and not (self.folder / PROJECT_FILE).is_file():
                return []
            analysis = self.analysis()
        try:
            if text is None:
                text = self._configuration_on_disk()
            project = configured_project(text, [], PROJECT_FILE)
        except ProjectError as exc:
            # what `padt compile` says before it compiles (no code: it is not the compiler's)
            return [Diagnostic(PROJECT_FILE, 1, 1, "error", str(exc), "")]
        parsed: Parsed = (list(analysis.units), [], set(analysis.user_pous))
        result = compile_project(project, PROJECT_FILE, parsed)
        return sorted(d for d in result.diagnostics if d.file == PROJECT_FILE)

    def _configuration_on_disk(self) -> str:
        path = self.folder / PROJECT_FILE
        try:
            if path.stat().st_size > MAX_FILE_BYTES:
                raise ProjectError(f"{PROJECT_FILE}: larger than {MAX_FILE_BYTES // MiB} MiB")
            return path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise ProjectError(f"{PROJECT_FILE}: {exc}") from None

    # ---- the services at a place of a file: lines and columns from 1, in characters

    def complete(self, name: str, line: int, col: int) -> list[CompletionItem]:
        """What may be written at the place, most relevant first."""
        name = self.checked_name(name)
        return complete(self.readable(name), name, line, col)

    def hover(self, name: str, line: int, col: int) -> Hover | None:
        """What the name at the place is: its declaration, type and comment."""
        name = self.checked_name(name)
        return hover(self.readable(name), name, line, col)

    def definition(self, name: str, line: int, col: int) -> Location | None:
        """Where the symbol at the place is declared."""
        name = self.checked_name(name)
        return definition(self.readable(name), name, line, col)

    def references(self, name: str, line: int, col: int) -> list[Location]:
        """Every place that names the symbol at the place, its declaration among them,
        in the tests too."""
        name = self.checked_name(name)
        return references(self._readable(self._whole(), name), name, line, col)

    def renamed_at(self, name: str, line: int, col: int) -> Range | None:
        """The name a rename at the place would change, None where there is none."""
        name = self.checked_name(name)
        located = symbol_at(self.readable(name), name, line, col)
        return None if located is None else located.range

    def rename(self, name: str, line: int, col: int, new_name: str) -> RenameResult:
        """The edits per file that rename the symbol at the place, checked by the compiler
        on the texts as they are (nothing is written), the tests' uses renamed too; or why it
        cannot be renamed."""
        name = self.checked_name(name)
        return rename(self._analysed(self._whole()), name, line, col, new_name)

    def formatted(self, name: str) -> Formatted:
        """The file's text indented by its blocks, keywords in upper case; or why not."""
        name = self.checked_name(name)
        return format_file(self.analysis(name), name)

    def project_symbols(self, query: str) -> list[tuple[str, OutlineSymbol]]:
        """The POUs, their methods and properties, the types and the globals of every file
        whose name holds `query` (any case), with their files, by name; the tests' too."""
        wanted = query.casefold()
        analysis = self._analysed(self._whole())
        found = []
        for name in sorted(analysis.texts):
            for symbol in outline(analysis, name):
                inner = [c for c in symbol.children if c.kind in _NAMED_INSIDE.get(symbol.kind, ())]
                for each in (symbol, *inner):
                    if each.kind != "global_list" and wanted in each.name.casefold():
                        found.append((name, each))
        return sorted(found, key=lambda item: (item[1].name.casefold(), item[0]))

    def outline(self, name: str) -> list[OutlineSymbol]:
        """What the file declares, nested, in the order it stands."""
        name = self.checked_name(name)
        return outline(self.analysis(name), name)


def _files_of(folder: Path) -> dict[str, str]:
    """The .st files of the project folder by name, as the compiler reads them, and its
    test files as `padt test` reads them."""
    try:
        sources = [*project_sources(folder), *sources_of_tests(folder)]
        return {source.name: source.text for source in sources}
    except OSError as exc:
        raise ProjectUnreadable(f"the project cannot be read: {exc}") from None


def _line(text: str, line: int) -> str:
    """Line `line` (from 1) of `text`, without its end; "" past the text."""
    starts = _line_starts(text)
    if not 0 < line <= len(starts):
        return ""
    end = starts[line] - 1 if line < len(starts) else len(text)
    return text[starts[line - 1] : end]


@lru_cache(maxsize=8)
def _line_starts(text: str) -> tuple[int, ...]:
    """Where each line of `text` starts (the diagnostics of one text ask many times)."""
    return (0, *(match.end() for match in re.finditer("\n", text)))
