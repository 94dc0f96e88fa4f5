"""A text cut into its top-level declarations (`chunks`) as an editor changes it: a text
that differs from one cut lately inside one declaration, past that declaration's first
line, is cut again only there; everything else keeps its cut. The result is always what
`chunks` gives for the whole text."""

from __future__ import annotations

import threading
from bisect import bisect_right
from collections import OrderedDict

from backend.compiler.language.chunks import Chunk, chunks

_KEPT = 64  # texts whose cuts are kept
_KEPT_SIZE = 16 * 1024 * 1024  # and their characters at most, together
_COMPARED = 4  # the latest of them a new text is compared with


class _Cuts:
    """The cuts of the texts asked about lately (the services ask from several threads)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._recent: OrderedDict[str, tuple[Chunk, ...]] = OrderedDict()
        self._size = 0  # the characters of the texts kept

    def of(self, text: str) -> tuple[Chunk, ...]:
        with self._lock:
            found = self._recent.get(text)
            if found is not None:
                self._recent.move_to_end(text)
                return found
            latest = list(self._recent.items())[-_COMPARED:]
        result = None
        for old_text, old_cut in reversed(latest):
            result = _recut(old_text, old_cut, text)
            if result is not None:
                break
        if result is None:
            result = tuple(chunks(text)) or (Chunk(0, text),)
        with self._lock:
            if text not in self._recent:
                self._recent[text] = result
                self._size += len(text)
            while len(self._recent) > _KEPT or (self._size > _KEPT_SIZE and self._recent):
                dropped, _ = self._recent.popitem(last=False)
                self._size -= len(dropped)
        return result


_CUTS = _Cuts()


def cut(text: str) -> tuple[Chunk, ...]:
    """`chunks(text)`, never empty, cut again only where the text changed."""
    return _CUTS.of(text)


def _recut(old: str, old_cut: tuple[Chunk, ...], new: str) -> tuple[Chunk, ...] | None:
    """The cut of `new` from the cut of `old`, when they differ inside one chunk past its
    first line; None otherwise (the whole text is cut then)."""
    prefix = _common_prefix(old, new)
    suffix = _common_suffix(old, new, min(len(old), len(new)) - prefix)
    if not _lexically_local(old, new, prefix, suffix):
        return None
    starts = [0]
    for chunk in old_cut:
        starts.append(starts[-1] + len(chunk.text))
    index = bisect_right(starts, prefix) - 1
    if index >= len(old_cut):
        return None
    begin, end = starts[index], starts[index + 1]
    first_line = old_cut[index].text.find("\n")
    if first_line < 0 or prefix <= begin + first_line or len(old) - suffix > end:
        return None  # the chunk's first line or the next chunk changed
    piece = new[begin : end + len(new) - len(old)]
    following = old_cut[index + 1].text if index + 1 < len(old_cut) else ""
    again = chunks(piece + following)
    if following:
        if not again or again[-1].text != following:
            return None  # the change reaches past its chunk (a declaration left open)
        again = again[:-1]
    if not again:
        return None
    lines_before = old_cut[index].line_offset
    moved = piece.count("\n") - old_cut[index].text.count("\n")
    return (
        *old_cut[:index],
        *(Chunk(chunk.line_offset + lines_before, chunk.text) for chunk in again),
        *(Chunk(chunk.line_offset + moved, chunk.text) for chunk in old_cut[index + 1 :]),
    )


# what may open or close a comment, a string or a pragma: a change that makes or breaks one
# may hide or show keywords far from it
_DELIMITERS = ("(*", "*)", "/*", "*/", "//")
_QUOTES = ("'", '"', "{", "}", "$")


def _lexically_local(old: str, new: str, prefix: int, suffix: int) -> bool:
    """Whether the change (the text between the common prefix and suffix) makes or breaks
    no comment, string or pragma: then it changes how its own chunk reads at most."""
    for text in (old, new):
        end = len(text) - suffix
        changed = text[prefix:end]
        around = text[max(prefix - 1, 0) : end + 1]
        if any(q in changed for q in _QUOTES) or any(d in around for d in _DELIMITERS):
            return False
    return True


def _common_prefix(a: str, b: str) -> int:
    """How many first characters `a` and `b` share (halving: each step one comparison of
    slices, which Python makes at memory speed)."""
    low, high = 0, min(len(a), len(b))
    while low < high:
        mid = (low + high + 1) // 2
        if a[:mid] == b[:mid]:
            low = mid
        else:
            high = mid - 1
    return low


def _common_suffix(a: str, b: str, limit: int) -> int:
    """How many last characters `a` and `b` share, at most `limit`."""
    low, high = 0, limit
    while low < high:
        mid = (low + high + 1) // 2
        if a[len(a) - mid :] == b[len(b) - mid :]:
            low = mid
        else:
            high = mid - 1
    return low
