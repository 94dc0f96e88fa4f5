"""A project as the language services hold it while one edits: the text of each file, as
on disk or as an editor has it, and the analysis of those texts, kept up to date.

A change re-parses only the declarations it touched (`parse_cache`), then resolves the
project anew, each declaration's qualified names and each unchanged POU's check taken from
the last analysis (`reuse`): the diagnostics are those of `analyse` on the same texts."""

from __future__ import annotations

import threading
from collections.abc import Mapping

from backend.compiler.diagnostics import Diagnostic
from backend.compiler.language.analysis import Analysis, analysed
from backend.compiler.language.parse_cache import FileParse, parse_file, parse_texts
from backend.compiler.language.reuse import Reuse


class LanguageProject:
    """The texts of one project and their analysis. The browser's sessions and `padt lsp`
    call it from several threads: a lock keeps texts and analysis together."""

    def __init__(self, texts: Mapping[str, str]) -> None:
        self._lock = threading.Lock()
        self._texts = dict(texts)
        self._parsed: dict[str, tuple[str, FileParse]] = {}  # file -> (its text, its parse)
        self._analysis: Analysis | None = None
        self._reuse = Reuse()

    def texts(self) -> dict[str, str]:
        with self._lock:
            return dict(self._texts)

    def set_text(self, file: str, text: str) -> None:
        """The file's text now: as saved, or as an editor has it (a new file too)."""
        with self._lock:
            if self._texts.get(file) != text:
                self._texts[file] = text
                self._analysis = None

    def remove(self, file: str) -> None:
        with self._lock:
            if self._texts.pop(file, None) is not None:
                self._parsed.pop(file, None)
                self._analysis = None

    def analysis(self) -> Analysis:
        """The analysis of the texts as they are now."""
        with self._lock:
            if self._analysis is None:
                parsed = parse_texts(self._texts, self._parse)
                self._analysis = analysed(self._texts, parsed, self._reuse)
            return self._analysis

    def _parse(self, file: str, text: str) -> FileParse:
        """The file's parse, kept while its text stays."""
        known = self._parsed.get(file)
        if known is None or known[0] != text:
            known = (text, parse_file(file, text))
            self._parsed[file] = known
        return known[1]

    def diagnostics(self, file: str) -> list[Diagnostic]:
        """The diagnostics of one file, by place."""
        return self.analysis().diagnostics_of(file)
