"""Parses kept for the process: every editor session and `padt lsp` client shares them,
so a second session on the same project parses nothing, and a keystroke re-parses only
the declaration it changed (see `chunks` and `cuts`).

Two levels, each bounded by the size of the texts it holds (least recently used first
out): the parse tree of a chunk's text (of no file, at no line), and the AST items of a
chunk placed in a file at a line, made from that tree; a line typed above a chunk only
places its tree anew, which costs about a quarter of its parse. The result is the same as
`parse_source` on the whole file: `tests/compiler/language/test_incremental.py` compares."""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass
from typing import Generic, TypeVar

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.diagnostics import CompileError, Diagnostic
from backend.compiler.language.cuts import cut
from backend.compiler.limits import MAX_PROJECT_TOKENS
from backend.compiler.parse import Piece, SyntaxTree, piece_of, placed, syntax_tree, unit_of
from backend.compiler.pipeline import Parsed, parse_project, with_standard_library
from backend.compiler.source import ProjectSize, SourceFile

# characters of text whose parses each level keeps: the parses of all of OSCAT (0.45 M
# characters, 0.33 M in distinct chunks) take 38 MB, trees and ASTs together, so each
# level at its bound takes some 80 MB
TREE_CACHE_CHARS = 2_000_000
PIECE_CACHE_CHARS = 2_000_000

K = TypeVar("K", bound=Hashable)
V = TypeVar("V")


class _SizedCache(Generic[K, V]):
    """A least-recently-used cache bounded by the total size its entries are given."""

    def __init__(self, capacity: int) -> None:
        self._capacity = capacity
        self._entries: OrderedDict[K, tuple[V, int]] = OrderedDict()
        self._size = 0
        self._lock = threading.Lock()

    def get(self, entry_key: K, size: int, make: Callable[[], V]) -> V:
        with self._lock:
            found = self._entries.get(entry_key)
            if found is not None:
                self._entries.move_to_end(entry_key)
                return found[0]
        value = make()  # outside the lock: two threads may make the same value, both right
        if size > self._capacity:
            return value  # kept by nobody once used: one text must not take all the room
        with self._lock:
            if entry_key not in self._entries:
                self._entries[entry_key] = (value, size)
                self._size += size
            while self._size > self._capacity:
                _, (_, dropped) = self._entries.popitem(last=False)
                self._size -= dropped
        return value


_TREES: _SizedCache[str, SyntaxTree] = _SizedCache(TREE_CACHE_CHARS)
_PIECES: _SizedCache[tuple[str, int, str], Piece] = _SizedCache(PIECE_CACHE_CHARS)


@dataclass(frozen=True)
class FileParse:
    """One file parsed: its unit, or the diagnostics that left it none; with the tokens
    it took."""

    unit: ast.SourceUnit | None
    diagnostics: tuple[Diagnostic, ...]
    tokens: int


def parse_file(file: str, text: str) -> FileParse:
    """`parse_source(file, text)` from the cached parses of the text's chunks."""
    parts = cut(text)  # after a keystroke, cut again only in the declaration it changed
    trees = [_TREES.get(chunk.text, len(chunk.text), _tree_maker(chunk.text)) for chunk in parts]
    tokens = sum(tree.tokens for tree in trees)
    for chunk, tree in zip(parts, trees, strict=True):
        if tree.error is not None:  # the first syntax error stops a file's parse
            return FileParse(None, (placed(tree.error, file, chunk.line_offset),), tokens)
    pieces = [
        _PIECES.get(
            (file, chunk.line_offset, chunk.text),
            len(chunk.text),
            _piece_maker(file, tree, chunk.line_offset),
        )
        for chunk, tree in zip(parts, trees, strict=True)
    ]
    try:
        unit = unit_of(file, pieces)
    except CompileError as exc:
        return FileParse(None, tuple(exc.diagnostics), tokens)
    return FileParse(unit, unit.warnings, tokens)


def _tree_maker(text: str) -> Callable[[], SyntaxTree]:
    return lambda: syntax_tree(text)


def _piece_maker(file: str, tree: SyntaxTree, line_offset: int) -> Callable[[], Piece]:
    return lambda: piece_of(file, tree, line_offset)


def parse_texts(texts: Mapping[str, str], parse: Callable[[str, str], FileParse]) -> Parsed:
    """What `parse_project` gives for the files `texts` (in order of name), each file
    parsed by `parse(name, text)` (`parse_file`, or a memo of it). Where the project is too
    large the limits cut in as in `parse_project`: it is then parsed as that does."""
    names = sorted(texts)
    size = ProjectSize()
    if any(size.add(texts[name]) is not None for name in names):
        return parse_project([SourceFile(name, texts[name]) for name in names])
    parsed = [parse(name, texts[name]) for name in names]
    if sum(p.tokens for p in parsed) > MAX_PROJECT_TOKENS:
        return parse_project([SourceFile(name, texts[name]) for name in names])
    units = [p.unit for p in parsed if p.unit is not None]
    diagnostics = [d for p in parsed for d in p.diagnostics]
    user_pous = {key(pou.name) for unit in units for pou in unit.pous}
    return with_standard_library(units), diagnostics, user_pous
