"""The execution order of a drawing's elements, by the rules of IEC 61131-3 for networks.

An element is evaluated once every element it takes a wire from is (data flow); among
those ready, the one with an explicit execution order (TC6 `executionOrderId`) goes first,
then the one higher on the sheet, then the one further left. A loop in the data flow is a
feedback path: when nothing is ready, the first element by that rule is evaluated with the
values its unevaluated sources had at their last evaluation.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Iterable

from backend.compiler.graphics.model import Element


def sheet_key(element: Element) -> tuple[int, float, float, int]:
    """The order of elements that the data flow leaves free."""
    return (element.order, element.at.y, element.at.x, element.id)


def evaluation_order(
    elements: Iterable[Element], depends_on: Callable[[Element], set[int]]
) -> tuple[list[Element], set[tuple[int, int]]]:
    """`elements` in the order they are evaluated, and the feedback wires among them:
    (consumer, source) pairs evaluated before their source in a cycle."""
    nodes = {e.id: e for e in elements}
    needs = {e.id: depends_on(e) & nodes.keys() for e in nodes.values()}
    feeds: dict[int, set[int]] = {i: set() for i in nodes}
    for consumer, sources in needs.items():
        for source in sources:
            feeds[source].add(consumer)
    waiting = {i: len(s) for i, s in needs.items()}
    ready = [(sheet_key(nodes[i]), i) for i, n in waiting.items() if n == 0]
    heapq.heapify(ready)
    done: set[int] = set()
    result: list[Element] = []
    feedback: set[tuple[int, int]] = set()
    while len(done) < len(nodes):
        if not ready:
            # a loop: break it at its first element on the sheet
            first = min((i for i in nodes if i not in done), key=lambda i: sheet_key(nodes[i]))
            feedback |= {(first, s) for s in needs[first] if s not in done}
            waiting[first] = 0
            heapq.heappush(ready, (sheet_key(nodes[first]), first))
        _, current = heapq.heappop(ready)
        if current in done:
            continue
        done.add(current)
        result.append(nodes[current])
        for consumer in feeds[current]:
            if consumer in done:
                continue
            waiting[consumer] -= 1
            if waiting[consumer] == 0:
                heapq.heappush(ready, (sheet_key(nodes[consumer]), consumer))
    return result, feedback
