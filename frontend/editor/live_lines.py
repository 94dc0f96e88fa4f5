"""The live values beside the lines of the editor, when online: for the file in view, if it
is a source of the configuration the selected resource runs (a project the PADT knows
compiles to the resource's CRC), and the open text is that source line for line, the
variables each line in view names, with their values, as a debugger shows them.

Only the lines in view are looked at and only their variables watched (`wanted`)."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from backend.engineering.sources import (
    ConfigurationSources,
    Shown,
    find_sources,
    instances,
    line_variables,
)
from frontend.editor.document import Document
from frontend.resource_feed import ResourceFeed, latest_reading
from runtime.contract.values import array_shape, format_for_display

log = logging.getLogger("padt.ui")
MAX_LINES = 400  # lines in view looked at (a tall window shows ~100)


class SourceLookup:
    """The sources of the configuration the resource runs, looked up again (compiling the
    projects, off the refresher's thread) whenever its CRC changes."""

    def __init__(
        self, find: Callable[[str, Mapping[str, Path]], ConfigurationSources | None]
    ) -> None:
        self._find = find
        self._lock = threading.Lock()
        self.crc = ""
        self.done = False
        self.result: ConfigurationSources | None = None

    def ask(self, crc: str, projects: Mapping[str, Path]) -> None:
        with self._lock:
            if crc == self.crc:
                return
            self.crc, self.done, self.result = crc, False, None
        threading.Thread(target=self._look, args=(crc, dict(projects)), daemon=True).start()

    def _look(self, crc: str, projects: Mapping[str, Path]) -> None:
        try:
            found = self._find(crc, projects)
        except Exception:  # a project the compiler chokes on is not the running one
            log.exception("looking for the source of configuration %s failed", crc)
            found = None
        with self._lock:
            if crc == self.crc:  # not overtaken by another configuration meanwhile
                self.result, self.done = found, True

    def answer(self) -> tuple[bool, ConfigurationSources | None]:
        with self._lock:
            return self.done, self.result

    def found_or_why(
        self, crc: str, projects: Mapping[str, Path], instead: str
    ) -> tuple[ConfigurationSources | None, str]:
        """The sources of configuration `crc` (asked for if need be), or what a screen says
        while there are none (`instead`: what it does then, "no source is shown")."""
        self.ask(crc, projects)
        done, sources = self.answer()
        if not done:
            return None, (
                f"Looking for the source of configuration {crc} among the projects this PADT "
                "knows ..."
            )
        if sources is None:
            known = ", ".join(sorted(projects)) or "none"
            return None, (
                f"The source of configuration {crc} is not among the projects this PADT knows "
                f"({known}): {instead} rather than one that may differ from what runs."
            )
        return sources, ""


def value_text(shown: Shown, values: dict[str, Any], types: dict[str, str]) -> str | None:
    """A variable's value as the screens show it; None when not (yet) delivered."""
    if shown.path not in values:
        return None
    value, type_name = values[shown.path], types.get(shown.path, "")
    if shown.element is None:
        return format_for_display(value, type_name)
    shape = array_shape(type_name)  # an element of an array of values: one variable
    if shape is None or not isinstance(value, list):
        return None
    indices = shape.indices()
    if shown.element not in indices or len(value) != len(indices):
        return None
    return format_for_display(value[indices.index(shown.element)], shape.element)


@dataclass(frozen=True)
class _Layout:
    key: tuple[object, ...]
    lines: dict[int, list[Shown]]


class LiveLines:
    """State: the file and lines in view, and what they name in the running resource."""

    def __init__(self) -> None:
        self.lookup = SourceLookup(find_sources)
        self.file = ""
        self.first, self.last = 1, 0
        self._layout = _Layout((), {})
        self._sent: tuple[str, list[dict[str, Any]]] | None = None
        self._values: dict[str, str] = {}  # name as written -> its value, of the lines shown

    def view(self, file: str, first: int, last: int) -> None:
        self.file, self.first, self.last = file, first, min(last, first + MAX_LINES)

    def wanted(self) -> list[str]:
        return sorted({s.path for line in self._layout.lines.values() for s in line})

    def value_of(self, name: str) -> str | None:
        return self._values.get(name.upper())

    def refresh(
        self,
        feed: ResourceFeed | None,
        project: str | None,
        projects: Mapping[str, Path],
        documents: dict[str, Document],
    ) -> tuple[str, list[dict[str, Any]]] | None:
        """What the page should show beside the lines now, when it differs from what it was
        sent last (None otherwise)."""
        document = documents.get(self.file)
        items: list[dict[str, Any]] = []
        self._values = {}
        if feed is not None and document is not None and project is not None:
            items = self._items(feed, project, projects, document)
        now = (self.file, items)
        if now == self._sent:
            return None
        self._sent = now
        return now

    def _items(
        self,
        feed: ResourceFeed,
        project: str,
        projects: Mapping[str, Path],
        document: Document,
    ) -> list[dict[str, Any]]:
        status, values, types, quality = latest_reading(feed)
        if status is None or not status.crc or not types:
            self._layout = _Layout((), {})
            return []
        self.lookup.ask(status.crc, projects)
        done, sources = self.lookup.answer()
        if not done or sources is None or sources.project != project:
            self._layout = _Layout((), {})
            return []
        key = (sources.crc, document.file, document.version, self.first, self.last, id(types))
        if self._layout.key != key:
            self._layout = _Layout(key, _lines(sources, document, self.first, self.last, types))
        items = []
        for number, shown in sorted(self._layout.lines.items()):
            parts, each, worst = [], [], "live"
            for s in shown:
                text = value_text(s, values, types)
                how = quality.get(s.path, "live") if text is not None else "stale"
                if how != "live":
                    worst = "forced" if "forced" in (how, worst) else how
                shown_text = text if text is not None else "..."
                parts.append(f"{s.label} = {shown_text}")
                each.append([s.label, shown_text, how])  # the bottom panel's Live values
                self._values[s.label.upper()] = shown_text
            line = {"line": number, "text": "  ".join(parts), "quality": worst, "values": each}
            items.append(line)
        return items


def _lines(
    sources: ConfigurationSources,
    document: Document,
    first: int,
    last: int,
    types: dict[str, str],
) -> dict[int, list[Shown]]:
    """The variables of each line in view, of the first instance of each POU of the file
    whose running source is the open text line for line."""
    found: dict[int, list[Shown]] = {}
    seen: set[str] = set()
    for instance in instances(sources, types):
        source = sources.source_of(instance)
        if source is None or source.file != document.file or source.name in seen:
            continue
        seen.add(source.name)  # an FB's first instance speaks for it
        lines = document.lines[source.first_line - 1 : source.last_line]
        if tuple(lines) != source.lines:
            continue  # edited since it was loaded: the lines no longer match
        top, bottom = max(first, source.first_line), min(last, source.last_line)
        if top <= bottom:
            found.update(line_variables(source, instance, top, bottom, types))
    return found
