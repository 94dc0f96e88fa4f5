"""Finding variables of a resource by what the user remembers: a search over the paths
(`TankControl.refillDelay.ET`) and the instance tree the paths make (programs, FB
instances, structures, array elements, SFC steps: everything that has members)."""

from __future__ import annotations

from collections.abc import Iterable

MAX_SEARCH = 200  # characters of a search: a browser may send megabytes


def instances(paths: Iterable[str]) -> list[str]:
    """Every path that has members, in tree order (a parent before its children)."""
    found: set[str] = set()
    for path in paths:
        parts = path.split(".")
        for end in range(1, len(parts)):
            found.add(".".join(parts[:end]))
    return sorted(found, key=_tree_order)


def below(paths: Iterable[str], instance: str) -> list[str]:
    """The variables inside `instance`, at any depth, in tree order."""
    prefix = instance + "."
    return in_tree_order(p for p in paths if p.startswith(prefix))


def in_tree_order(paths: Iterable[str]) -> list[str]:
    return sorted(paths, key=_tree_order)


def search(paths: Iterable[str], text: str, limit: int) -> tuple[list[str], int]:
    """The paths that contain every word of `text` (any case), best first: the variable's
    own name equal to the last word, then starting with it, then the rest; at most
    `limit` of them, and how many matched in all."""
    words = text[:MAX_SEARCH].lower().split()
    if not words:
        return [], 0
    last = words[-1]
    ranked: list[tuple[int, tuple[str, ...], str]] = []
    for path in paths:
        lowered = path.lower()
        if all(word in lowered for word in words):
            name = lowered.rsplit(".", 1)[-1]
            rank = 0 if name == last else 1 if name.startswith(last) else 2
            ranked.append((rank, _tree_order(path), path))
    ranked.sort()
    return [path for _, _, path in ranked[:limit]], len(ranked)


def _tree_order(path: str) -> tuple[str, ...]:
    """Members right after their instance, case-insensitively; `a.b` before `a_b`."""
    return tuple(path.lower().split("."))
