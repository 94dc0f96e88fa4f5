"""Which objects of the running configuration a reload's new configuration takes over
as they are (adopts) instead of copying their values into fresh ones.

An object (a program instance, the globals, an FB or struct instance, an array of them)
is adopted when copying it would give exactly what the plan says anyway: every variable
below it is kept (same relative path, same type, no rename inside, none new or deleted)
and every generated object below it has a class of the same name whose slots are laid out
exactly as before, so the object can be switched to the new class (its code may have
changed) by assigning `__class__`. Only the topmost such objects are adopted; the rest
of the values are copied. The decisions are made while preparing (off the cycle thread);
the switch-over then grafts the adopted objects into the new configuration (writing only
into the new one) and, past the point of no return, switches their classes.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from runtime.code_image import Accessor, CodeImage, slot_names
from runtime.instances import Instances
from runtime.reload_plan import KEPT, ReloadPlan
from runtime.user_program import UserProgram

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
    values: int  # declared variables below it


@dataclass
class Adoption:
    grafts: list[Graft] = field(default_factory=list)
    paths: set[str] = field(default_factory=set)  # upper-case new paths carried by grafts
    replaced: set[int] = field(default_factory=set)  # ids of new objects grafts replace
    classes: dict[type, type] = field(default_factory=dict)  # old class -> new class
    children: dict[type, tuple[str, ...]] = field(default_factory=dict)  # of old classes
    objects: int = 0  # generated objects whose class the switch-over changes
    # the old objects adopted, and every object above them: one old object goes to one
    # place (a rename map may name a source twice; the second one is copied)
    taken: set[Node] = field(default_factory=set)
    under: set[Node] = field(default_factory=set)


def _taken(node: Node, adoption: Adoption) -> bool:
    owner, attrs = node
    above = any((owner, attrs[:depth]) in adoption.taken for depth in range(len(attrs) + 1))
    return above or node in adoption.under


def compatible_classes(old: CodeImage, new: CodeImage) -> dict[type, type]:
    """Old generated class -> new class of the same name, where an object of the old one
    can become one of the new one (the same slots in the same order)."""
    renewed = new.classes()
    compatible = {}
    for name, kind in old.classes().items():
        other = renewed.get(name)
        if other is None:
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


def plan_adoption(old: Instances, new: Instances, plan: ReloadPlan) -> Adoption:
    """The objects to adopt (see the module's docstring)."""
    classes = compatible_classes(old.image, new.image)
    adoption = Adoption(classes=classes, children=old.image.object_attrs())
    new_children = new.image.object_attrs()
    changes = {change.path.upper(): change for change in plan.changes}
    old_members = Counter(_prefixes(old.bound))
    members: Counter[Node] = Counter()
    # what each node of the new tree would be adopted from; None where nothing can be
    proposals: dict[Node, tuple[UserProgram | None, tuple[Accessor, ...]] | None] = {}
    for bound in new.bound:
        change = changes.get(bound.path.path.upper())
        source = None
        if change is not None and change.action == KEPT and change.source is not None:
            source = old.by_name.get(change.source.upper())
        attrs = bound.path.attrs
        for depth in range(len(attrs)):
            node = (bound.program, attrs[:depth])
            members[node] += 1
            suffix = attrs[depth:]
            origin = source.path.attrs if source is not None else ()
            if source is None or origin[len(origin) - len(suffix) :] != suffix:
                proposals[node] = None
                continue
            proposal = (source.program, origin[: len(origin) - len(suffix)])
            if proposals.setdefault(node, proposal) != proposal:
                proposals[node] = None
    decided: dict[Node, bool] = {}
    for bound in new.bound:
        attrs = bound.path.attrs
        for depth in range(len(attrs)):
            node = (bound.program, attrs[:depth])
            if node not in decided:
                decided[node] = _adopt(
                    node,
                    proposals.get(node),
                    members[node],
                    old_members,
                    old,
                    new,
                    new_children,
                    adoption,
                )
            if decided[node]:
                adoption.paths.add(bound.path.path.upper())
                break
    return adoption


def _adopt(
    node: Node,
    proposal: tuple[UserProgram | None, tuple[Accessor, ...]] | None,
    count: int,
    old_members: Counter[Node],
    old: Instances,
    new: Instances,
    new_children: dict[type, tuple[str, ...]],
    adoption: Adoption,
) -> bool:
    """Adopt the object at `node` if it can be; records the graft."""
    if proposal is None or old_members[proposal] != count or _taken(proposal, adoption):
        return False
    owner, attrs = node
    old_owner, old_attrs = proposal
    old_root = old_owner.instance if old_owner is not None else old.globals
    new_root = owner.instance if owner is not None else new.globals
    fresh = resolve(new_root, attrs)
    objects = _same_layout(resolve(old_root, old_attrs), fresh, adoption.classes, new_children)
    if objects is None:
        return False
    adoption.objects += len(objects)
    adoption.replaced.update(objects)
    parent = resolve(new_root, attrs[:-1]) if attrs else None
    last = attrs[-1] if attrs else None
    adoption.taken.add(proposal)
    adoption.under.update((old_owner, old_attrs[:depth]) for depth in range(len(old_attrs)))
    adoption.grafts.append(Graft(old_root, old_attrs, owner, parent, last, fresh, count))
    return True


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
        if kind not in children or classes.get(type(before)) is not kind:
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
