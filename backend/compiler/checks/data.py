"""What data holds, over the whole project: no function block holds an instance of itself,
nothing nests deeper than MAX_DATA_DEPTH, no array holds more than MAX_ARRAY_VALUES values,
and neither a call nor the instances of a resource more than MAX_DATA_VALUES.

Structures and function blocks (and programs) are the holders; arrays add a level around
what they hold. Values count the memory a resource gives to data: one per elementary value,
a string one per started 64 characters it can hold, and every structure or instance at
least one. The holders are visited in the order of their strongly connected components,
without recursion, so that chains of any length are safe.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.limits import MAX_ARRAY_VALUES, MAX_DATA_DEPTH, MAX_DATA_VALUES
from backend.compiler.resolve import PouSymbols, Resolved, Variable
from backend.compiler.types import ArrayType, ElementaryType, FbType, StructType, Type

Holder = tuple[str, str]  # ("POU", key) or ("STRUCT", key)
STRING_VALUE = 64  # characters of a string that count as one value


@dataclass(frozen=True)
class Held:
    """A holder's nesting (itself included) and values; None for both when it holds itself,
    directly or further down, or holds a block that does."""

    depth: int | None
    values: int | None


class DataSizes:
    """The nesting and the values of every type of a resolved project, each found once."""

    def __init__(self, resolved: Resolved) -> None:
        self.resolved = resolved
        self.members: dict[Holder, list[Variable]] = {
            ("STRUCT", name): info.members for name, info in resolved.structs.items()
        }
        self.members.update(
            (("POU", name), _held_variables(pou))
            for name, pou in resolved.pous.items()
            if pou.kind != "FUNCTION"
        )
        self.held: dict[Holder, Held] = {}
        self.cyclic: list[Holder] = []
        for component in _components(sorted(self.members), self._inner_holders):
            self._size(component)

    def name(self, holder: Holder) -> str:
        kind, name = holder
        return self.resolved.pous[name].name if kind == "POU" else self.resolved.structs[name].name

    def _inner_holders(self, holder: Holder) -> list[Holder]:
        found = {inner for v in self.members[holder] if (inner := self.holder_in(v.type))}
        return sorted(found)

    def holder_in(self, t: Type) -> Holder | None:
        """The structure or block a value of `t` is made of, inside its arrays."""
        while isinstance(t, ArrayType):
            t = t.element
        if isinstance(t, StructType):
            return "STRUCT", key(t.name)
        if isinstance(t, FbType) and key(t.name) in self.resolved.pous:
            return "POU", key(t.name)
        return None

    def _size(self, component: list[Holder]) -> None:
        holder = component[0]
        if len(component) > 1 or holder in self._inner_holders(holder):
            self.cyclic.extend(component)
            self.held.update((h, Held(None, None)) for h in component)
            return
        variables = self.members[holder]
        depths = [self.depth(v.type) for v in variables]
        values = [self.values(v.type) for v in variables]
        known_depths = [d for d in depths if d is not None]
        known_values = [v for v in values if v is not None]
        if len(known_depths) < len(depths) or len(known_values) < len(values):
            self.held[holder] = Held(None, None)
        else:
            self.held[holder] = Held(1 + max(known_depths, default=0), max(1, sum(known_values)))

    def depth(self, t: Type) -> int | None:
        """The levels of arrays, structures and blocks a value of `t` is made of."""
        arrays = 0
        while isinstance(t, ArrayType):
            arrays, t = arrays + 1, t.element
        holder = self.holder_in(t)
        inner = self.held[holder].depth if holder is not None else 0
        return None if inner is None else arrays + inner

    def values(self, t: Type) -> int | None:
        """The values a variable of `t` holds."""
        if isinstance(t, ArrayType):
            element = self.values(t.element)
            return None if element is None else t.size * element
        holder = self.holder_in(t)
        if holder is not None:
            return self.held[holder].values
        if isinstance(t, ElementaryType) and t.category == "string":
            return max(1, -(-t.max_length // STRING_VALUE))
        return 1


def _held_variables(pou: PouSymbols) -> list[Variable]:
    """What an instance of a block or program is made of (a global it names is not its)."""
    return [v for v in pou.variables if v.kind != "VAR_GLOBAL"]


def check_data(resolved: Resolved) -> list[Diagnostic]:
    """Blocks that hold themselves; data nested too deep; arrays and calls too large."""
    sizes = DataSizes(resolved)
    diagnostics = [
        Diagnostic.at(
            resolved.pous[name].pou.pos,
            Code.SELF_CONTAINED,
            f"'{resolved.pous[name].name}' contains an instance of itself",
        )
        for kind, name in sorted(sizes.cyclic)
        if kind == "POU"
    ]
    for holder, variables in sorted(sizes.members.items()):
        for variable in variables:
            diagnostics.extend(_variable_problems(sizes, variable, holder))
    functions = [pou for pou in resolved.sorted_pous() if pou.kind == "FUNCTION"]
    for variable in [*(v for f in functions for v in _held_variables(f)), *resolved.globals]:
        diagnostics.extend(_variable_problems(sizes, variable, None))
    for function in functions:
        diagnostics.extend(_call_problems(sizes, function))
    return diagnostics


def _variable_problems(
    sizes: DataSizes, variable: Variable, holder: Holder | None
) -> Iterator[Diagnostic]:
    """Reported where the nesting first goes beyond the limit: at the variable whose arrays
    do it, or whose holder would (`holder`: the structure or block it belongs to)."""
    depth = sizes.depth(variable.type)
    inside = sizes.holder_in(variable.type)
    inner = sizes.held[inside].depth if inside is not None else 0
    if depth is not None and inner is not None:
        if inner <= MAX_DATA_DEPTH < depth:
            message = f"'{variable.name}' nests data {depth} levels deep; at most {MAX_DATA_DEPTH}"
            yield Diagnostic.at(variable.pos, Code.DATA_DEPTH, message)
        elif holder is not None and depth == MAX_DATA_DEPTH:
            message = (
                f"'{sizes.name(holder)}' nests data {depth + 1} levels deep through "
                f"'{variable.name}'; at most {MAX_DATA_DEPTH}"
            )
            yield Diagnostic.at(variable.pos, Code.DATA_DEPTH, message)
    values = sizes.values(variable.type) if isinstance(variable.type, ArrayType) else None
    if values is not None and values > MAX_ARRAY_VALUES:
        message = f"array '{variable.name}' holds {values:,} values; at most {MAX_ARRAY_VALUES:,}"
        yield Diagnostic.at(variable.pos, Code.ARRAY_SIZE, message)


def _call_problems(sizes: DataSizes, function: PouSymbols) -> Iterator[Diagnostic]:
    values = [sizes.values(v.type) for v in _held_variables(function)]
    total = sum(v for v in values if v is not None)
    if total > MAX_DATA_VALUES:
        message = f"a call of '{function.name}' holds {total:,} values; at most {MAX_DATA_VALUES:,}"
        yield Diagnostic.at(function.pou.pos, Code.DATA_SIZE, message)


def resource_data(resolved: Resolved, user_programs: int) -> list[Diagnostic]:
    """The instances of a resource: every PROGRAM has one, and the globals one copy for the
    resource and one for each user program when there are several (their views)."""
    sizes = DataSizes(resolved)
    counted = [
        (pou, held.values)
        for pou in resolved.sorted_pous()
        if pou.kind == "PROGRAM" and (held := sizes.held[("POU", key(pou.name))]).values is not None
    ]
    global_values = [sizes.values(v.type) for v in resolved.globals]
    copies = 1 + (user_programs if user_programs > 1 else 0)
    globals_total = copies * sum(v for v in global_values if v is not None)
    total = globals_total + sum(values for _, values in counted)
    if total <= MAX_DATA_VALUES:
        return []
    largest = max(counted, key=lambda item: item[1], default=None)
    if largest is not None and largest[1] >= globals_total:
        where, part = largest[0].pou.pos, f"program '{largest[0].name}' {largest[1]:,}"
    else:  # then there are globals
        where, part = resolved.globals[0].pos, f"the globals {globals_total:,}"
    message = f"the resource's data holds {total:,} values ({part}); at most {MAX_DATA_VALUES:,}"
    return [Diagnostic.at(where, Code.DATA_SIZE, message)]


def _components(
    nodes: list[Holder], successors: Callable[[Holder], list[Holder]]
) -> Iterator[list[Holder]]:
    """Tarjan's strongly connected components, without recursion: each one comes after
    every component it reaches."""
    index: dict[Holder, int] = {}
    low: dict[Holder, int] = {}
    stack: list[Holder] = []
    on_stack: set[Holder] = set()
    for root in nodes:
        if root in index:
            continue
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        work = [(root, iter(successors(root)))]
        while work:
            node, children = work[-1]
            for child in children:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(successors(child))))
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            else:
                work.pop()
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[node])
                if low[node] == index[node]:
                    component: list[Holder] = []
                    while not component or component[-1] != node:
                        component.append(stack.pop())
                        on_stack.discard(component[-1])
                    yield component
