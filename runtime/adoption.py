"""Which objects of the running configuration a reload's new configuration takes over
as they are (adopts) instead of copying their values into fresh ones.

An object (a program instance, the globals, an FB or struct instance, an array of them)
is adopted when copying it would give exactly what the plan says anyway: every variable
below it is kept (same relative path, same type, no rename inside, none new or deleted)
and every generated object below it has a class of the same name whose slots are laid out
exactly as before, so the object can be switched to the new class (its code may have
changed) by assigning `__class__`. An object whose own variables are all kept and whose
class is compatible is adopted on its own even when some children are new (their layout
changed): those are filled by copying and set into it at the end. Only the topmost such
objects are adopted; the rest of the values are copied. The decisions are made while
preparing (off the cycle thread); the switch-over then grafts the adopted objects into the
new configuration (writing only into the new one) and, past the point of no return, sets
the new children into them and switches their classes.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from runtime.code.code_image import Accessor, CodeImage, slot_names
from runtime.code.instances import Instances
from runtime.code.user_program import UserProgram
from runtime.reload_plan import KEPT, ReloadPlan

_VALUES = (bool, int, float, str, type(None))

# an object in an instance tree: its owner (a user program; None for the globals) and the
# accessors from the owner's root object down to it
Node = tuple[UserProgram | None, tuple[Accessor, ...]]


@dataclass(frozen=True)
class Graft:
    """One adopted object: where it is in the running configuration (looked up at switch
    time: an assignment may have replaced a struct since) and where it goes in the new one."""

    old_root: Any
    old_attrs: tuple[Accessor, ...]
    new_owner: UserProgram | None  # whose root it is, when it replaces a root object
    new_parent: Any  # None: it replaces the root object of `new_owner` (or the globals)
    last: Accessor | None
    fresh: Any  # the new object it replaces
    # (slot, new object): children that are new, set into the adopted object at the end
    patches: tuple[tuple[str, Any], ...] = ()


@dataclass
class Adoption:
    """What the switch-over does with the adopted objects."""

    grafts: list[Graft] = field(default_factory=list)
    classes: dict[type, type] = field(default_factory=dict)  # old class -> new class
    children: dict[type, tuple[str, ...]] = field(default_factory=dict)  # of old classes
    objects: int = 0  # generated objects whose class the switch-over changes


@dataclass
class Adopted:
    """What comes along with the adopted objects, for working out the rest (only while
    preparing: the cycle thread need not free it)."""

    paths: set[str] = field(default_factory=set)  # upper-case new paths
    replaced: set[int] = field(default_factory=set)  # ids of the new objects replaced
    # ids of new objects replaced by an adopted one that takes some new children over
    shallow: set[int] = field(default_factory=set)


def compatible_classes(old: CodeImage, new: CodeImage) -> dict[type, type]:
    """Old generated class -> new class of the same name, where an object of the old one
    can become one of the new one (the same slots in the same order)."""
    renewed = new.classes()
    compatible = {}
    for name, kind in old.classes().items():
        other = renewed.get(name)
        if other is None or other is kind:  # a class of the runtime's own (a step)
            continue
        probe: Any = object.__new__(kind)
        if tuple(slot_names(probe)) != tuple(slot_names(object.__new__(other))):
            continue
        try:
            probe.__class__ = other  # what the switch-over will do; proven here
        except TypeError:
            continue
        compatible[kind] = other
    return compatible


def plan_adoption(old: Instances, new: Instances, plan: ReloadPlan) -> tuple[Adoption, Adopted]:
    """The objects to adopt (see the module's docstring)."""
    planner = _Planner(old, new, plan)
    return planner.adoption, planner.adopted


Origin = tuple[UserProgram | None, tuple[Accessor, ...]]  # a node of the old tree


class _Planner:
    """Works out the adoption: for every node of the new tree (walked from the roots down,
    leaf by leaf) whether it is adopted with everything below it (`deep`), adopted itself
    with some of its children new (`shallow`), adopted with its shallow parent (`inplace`),
    new below a shallow parent and all copied (`blocked`), or not adopted (`no`)."""

    def __init__(self, old: Instances, new: Instances, plan: ReloadPlan) -> None:
        self.old, self.new = old, new
        self.adoption = Adoption(
            classes=compatible_classes(old.image, new.image), children=old.image.object_attrs()
        )
        self.adopted = Adopted()
        # the old objects adopted, and every object above them: one old object goes to one
        # place (a rename map may name a source twice; the second one is copied)
        self.taken: set[Node] = set()
        self.under: set[Node] = set()
        self.new_children = new.image.object_attrs()
        self.old_members = Counter(_prefixes(old.bound))
        self.old_direct = Counter((b.program, b.path.attrs[:-1]) for b in old.bound)
        self.members: Counter[Node] = Counter()
        self.direct: Counter[Node] = Counter()
        # what each node would be adopted from, by all leaves below it and by its own
        # leaves; None where the leaves disagree or one of them is not simply kept
        self.proposals: dict[Node, Origin | None] = {}
        self.direct_proposals: dict[Node, Origin | None] = {}
        changes = {change.path.upper(): change for change in plan.changes}
        for bound in new.bound:
            change = changes.get(bound.path.path.upper())
            source = None
            if change is not None and change.action == KEPT and change.source is not None:
                source = old.by_name.get(change.source.upper())
            attrs = bound.path.attrs
            for depth in range(len(attrs)):
                node = (bound.program, attrs[:depth])
                self.members[node] += 1
                self._propose(self.proposals, node, source, attrs[depth:])
            self.direct[(bound.program, attrs[:-1])] += 1
            self._propose(self.direct_proposals, (bound.program, attrs[:-1]), source, attrs[-1:])
        self.state: dict[Node, str] = {}
        for bound in new.bound:
            if self._adopted(bound.program, bound.path.attrs):
                self.adopted.paths.add(bound.path.path.upper())

    @staticmethod
    def _propose(
        proposals: dict[Node, Origin | None], node: Node, source: Any, suffix: tuple[Accessor, ...]
    ) -> None:
        origin = source.path.attrs if source is not None else ()
        if source is None or origin[len(origin) - len(suffix) :] != suffix:
            proposals[node] = None
            return
        proposal = (source.program, origin[: len(origin) - len(suffix)])
        if proposals.setdefault(node, proposal) != proposal:
            proposals[node] = None

    def _adopted(self, owner: UserProgram | None, attrs: tuple[Accessor, ...]) -> bool:
        """Whether the leaf at `attrs` comes along with an adopted object."""
        for depth in range(len(attrs)):
            node = (owner, attrs[:depth])
            if node not in self.state:
                self.state[node] = self._decide(node)
            state = self.state[node]
            if state in ("deep", "inplace"):
                return True
            if state == "blocked":
                return False
            if state == "shallow" and depth == len(attrs) - 1:
                return True  # one of the shallow object's own variables
        return False

    def _taken(self, origin: Origin) -> bool:
        owner, attrs = origin
        above = any((owner, attrs[:depth]) in self.taken for depth in range(len(attrs) + 1))
        return above or origin in self.under

    def _roots(self, node: Node, origin: Origin) -> tuple[Any, Any]:
        old_root = origin[0].instance if origin[0] is not None else self.old.globals
        new_root = node[0].instance if node[0] is not None else self.new.globals
        return old_root, new_root

    def _deep(self, node: Node, origin: Origin | None) -> set[int] | None:
        """The new objects below `node` when it can be adopted from `origin` whole."""
        if origin is None or self.old_members[origin] != self.members[node]:
            return None
        if self._taken(origin):
            return None
        old_root, new_root = self._roots(node, origin)
        before, after = resolve(old_root, origin[1]), resolve(new_root, node[1])
        return _same_layout(before, after, self.adoption.classes, self.new_children)

    def _decide(self, node: Node) -> str:
        origin = self.proposals.get(node)
        objects = self._deep(node, origin)
        if objects is not None:
            assert origin is not None
            self._graft(node, origin, objects, ())
            return "deep"
        return "shallow" if self._shallow(node) else "no"

    def _shallow(self, node: Node) -> bool:
        """Adopt the object at `node` itself when its own variables are all kept and its
        class is compatible; each child comes along or is new (set into it at the end)."""
        origin = self.direct_proposals.get(node)
        if origin is None or self.old_direct[origin] != self.direct[node]:
            return False
        if self._taken(origin):
            return False
        old_root, new_root = self._roots(node, origin)
        before, after = resolve(old_root, origin[1]), resolve(new_root, node[1])
        kind = type(after)
        if kind not in self.new_children or isinstance(after, list):
            return False
        if self.adoption.classes.get(type(before), type(before)) is not kind:
            return False
        objects, patches = {id(after)}, []
        for attr in self.new_children[kind]:
            child = (node[0], (*node[1], attr))
            inner = (origin[0], (*origin[1], attr))
            found = self._deep(child, inner) if self.proposals.get(child) == inner else None
            if found is None:
                self.state[child] = "blocked"
                patches.append((attr, getattr(after, attr)))
            else:
                self.state[child] = "inplace"
                objects |= found
        self.adopted.shallow.add(id(after))
        self._graft(node, origin, objects - {id(after)}, tuple(patches))
        self.adoption.objects += 1
        return True

    def _graft(
        self,
        node: Node,
        origin: Origin,
        objects: set[int],
        patches: tuple[tuple[str, Any], ...],
    ) -> None:
        owner, attrs = node
        old_root, new_root = self._roots(node, origin)
        adoption = self.adoption
        adoption.objects += len(objects)
        self.adopted.replaced.update(objects)
        self.taken.add(origin)
        self.under.update((origin[0], origin[1][:depth]) for depth in range(len(origin[1])))
        parent = resolve(new_root, attrs[:-1]) if attrs else None
        last = attrs[-1] if attrs else None
        fresh = resolve(new_root, attrs)
        graft = Graft(old_root, origin[1], owner, parent, last, fresh, patches)
        adoption.grafts.append(graft)


def _same_layout(
    old: Any, new: Any, classes: dict[type, type], children: dict[type, tuple[str, ...]]
) -> set[int] | None:
    """The ids of the generated objects below `new` (itself included) when the objects
    below `old` correspond to them one for one with compatible classes; else None."""
    found: set[int] = set()
    stack = [(old, new)]
    while stack:
        before, after = stack.pop()
        if isinstance(after, list):
            if not isinstance(before, list) or len(before) != len(after):
                return None
            pairs = zip(before, after, strict=True)
            stack.extend(pair for pair in pairs if not isinstance(pair[1], _VALUES))
            continue
        if isinstance(after, _VALUES):  # an unbound VAR_IN_OUT; it is bound at each call
            continue
        kind = type(after)
        if kind not in children or classes.get(type(before), type(before)) is not kind:
            return None
        found.add(id(after))
        stack.extend((getattr(before, attr), getattr(after, attr)) for attr in children[kind])
    return found


def _prefixes(bound: Iterable[Any]) -> Iterable[Node]:
    for variable in bound:
        attrs = variable.path.attrs
        for depth in range(len(attrs)):
            yield variable.program, attrs[:depth]


def resolve(root: Any, attrs: tuple[Accessor, ...]) -> Any:
    target = root
    for accessor in attrs:
        target = target[accessor] if isinstance(accessor, int) else getattr(target, accessor)
    return target


def rebind(
    objects: list[Any], classes: dict[type, type], children: dict[type, tuple[str, ...]]
) -> None:
    """Switch every generated object below `objects` to its new class (the point of no
    return: the old configuration cannot run any more). Cannot fail: every class pair was
    proven compatible; an object already switched is not walked again."""
    stack = list(objects)
    while stack:
        target = stack.pop()
        if isinstance(target, list):
            kind = type(target[0]) if target else type(None)
            renewed = classes.get(kind)
            if renewed is not None and not children[kind]:
                for item in target:  # an array of structs without objects inside: fast
                    if type(item) is kind:
                        item.__class__ = renewed
            else:
                stack.extend(item for item in target if type(item) in classes)
            continue
        kind = type(target)
        renewed = classes.get(kind)
        if renewed is None:
            continue
        for attr in children[kind]:
            value = getattr(target, attr)
            if isinstance(value, list) or type(value) in classes:
                stack.append(value)
        target.__class__ = renewed
