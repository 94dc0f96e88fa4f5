"""The values of a configuration in its memory image (docs/native-code.md, "Who reaches a
value, and how"): `ImageMemory`, the `Memory` of the C tier, which reads and writes the
image's bytes at the offsets of the layouts (runtime/contract/layout.py) with `struct`,
in C, without a Python object per instance. Values are the contract's representations, as
`ObjectMemory` gives them (bool, int, float, str, lists for arrays), and the context's
trees are the ones `context_snapshot.snapshot` makes of the objects, so a context saved
on either side warm-starts the other.

A block's in-out of an array or a structure is where a call bound it (layout.py's
`Bound`): a path through one is found at each read and write, as the objects' path goes
through the caller's very variable; the context holds the values it refers to, as the
objects' snapshot does, and a restore puts them into the in-out's own storage (a restored
block holds a variable of its own until its next call, as on objects).

A resource's values go into an image once its C is in place (runtime/image_switch.py).
"""

from __future__ import annotations

import math
import operator
import struct
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any

from runtime.code.instances import BoundVariable
from runtime.context_snapshot import (
    CLASS,
    FIELDS,
    IEEE,
    ContextMismatch,
    Deferred,
    Records,
    nonfinite_node,
    nonfinite_value,
)
from runtime.contract.layout import (
    NULLABLE_TIME,
    Bound,
    Chars,
    Elements,
    ImageLayout,
    Layouts,
    Nested,
    Scalar,
    Shape,
    size_and_align,
)
from runtime.memory import ValueTrees

_NO_TIME = -(1 << 63)  # a runtime class's time that is None (layout.NULLABLE_TIME)
_LENGTH = struct.Struct("<H")
_BOUND = struct.Struct("<I")  # where an in-out is bound (layout.Bound)


@dataclass(frozen=True)
class _Place:
    """Where a variable's bytes are in the image, and their shape; `through_in_out`: found
    through an in-out, so only until a call binds it elsewhere."""

    offset: int
    shape: Shape
    through_in_out: bool = False


class ImageMemory:
    """The values in one memory image: the globals (`_G`), each user program's instance
    and, where programs have them, their own copies of the globals (`<program>._G`)."""

    def __init__(
        self,
        image: bytearray,
        layouts: Layouts,
        placement: ImageLayout,
        class_names: Mapping[str, str],
        programs: list[str],
    ) -> None:
        """`class_names`: the name each layout's class has in Python (an SFC step's
        structure is the runtime's `_SfcStep`), which the context's trees name;
        `programs`: the user programs' names."""
        self._image = image
        self._layouts = layouts
        self._placement = placement
        self._names = class_names
        self._programs = programs
        self._at = {p.name: p for p in placement.placements}
        self._copies = [self._at[f"{name}._G"] for name in programs if f"{name}._G" in self._at]

    # -- reading and writing variables
    def reader(self, bounds: list[BoundVariable]) -> Callable[[], list[Any]]:
        """The elementary values in one `struct` call over the image (in offset order,
        put back in the bounds' order by one `itemgetter`); texts and arrays after it."""
        if not bounds:  # (an `itemgetter` of one index gives no tuple)
            return list
        places = [self._place(bound) for bound in bounds]
        fixed = [isinstance(p.shape, Scalar) and not p.through_in_out for p in places]
        scalars = sorted(
            {p.offset: p.shape for p, f in zip(places, fixed, strict=True) if f}.items()
        )
        packed = self._packing(scalars)
        order = {offset: n for n, (offset, _) in enumerate(scalars)}
        others = [
            (n, p)
            for n, p in enumerate(places)
            if not isinstance(p.shape, Scalar) and not p.through_in_out
        ]
        moving = [
            (n, b) for n, (b, p) in enumerate(zip(bounds, places, strict=True)) if p.through_in_out
        ]
        # where each variable's value is in the row (a text's or an array's: a stand-in)
        pick = [order[p.offset] if f else 0 for p, f in zip(places, fixed, strict=True)]
        gather = operator.itemgetter(*pick, 0)  # a tuple, however many variables
        image, value = self._image, self._value

        def read() -> list[Any]:
            row = packed.unpack_from(image, 0) if scalars else (None,)
            got = list(gather(row))
            got.pop()
            for n, place in others:
                got[n] = value(place.offset, place.shape)
            for n, bound in moving:
                got[n] = self.read(bound)
            return got

        return read

    def read(self, bound: BoundVariable) -> Any:
        place = self._place(bound)
        return self._value(place.offset, place.shape)

    def writer(self, bound: BoundVariable) -> Callable[[Any], None]:
        roots = self._roots(bound)
        places = [self._place(bound, root) for root in roots]

        def write(value: Any) -> None:
            for root, place in zip(roots, places, strict=True):
                if place.through_in_out:  # where its in-out is bound now
                    place = self._place(bound, root)
                self._put(self._image, place.offset, place.shape, value)

        return write

    def store(self, bound: BoundVariable, value: Any) -> None:
        """A global goes into the globals and into every program's own copy of them."""
        self.writer(bound)(value)

    def _roots(self, bound: BoundVariable) -> list[str]:
        if bound.program is not None:
            return [bound.program.name]
        return ["_G", *(copy.name for copy in self._copies)]

    def _place(self, bound: BoundVariable, root: str | None = None) -> _Place:
        if root is None:
            root = bound.program.name if bound.program is not None else "_G"
        placed = self._at[root]
        offset = placed.offset
        shape: Shape = Nested(placed.cls)
        through = False
        for step in bound.path.attrs:
            if isinstance(shape, Bound):
                offset, shape, through = self._target(offset, shape), shape.target, True
            if isinstance(step, int):
                if not isinstance(shape, Elements) or not 0 <= step < shape.count:
                    raise KeyError(f"{bound.path.path}: no element {step}")
                offset += step * size_and_align(shape.element, self._layouts.__getitem__)[0]
                shape = shape.element
            else:
                if not isinstance(shape, Nested):
                    raise KeyError(f"{bound.path.path}: no member {step}")
                member = self._layouts[shape.cls].member(step)
                offset, shape = offset + member.offset, member.shape
        if isinstance(shape, Bound):
            offset, shape, through = self._target(offset, shape), shape.target, True
        return _Place(offset, shape, through)

    def _target(self, offset: int, bound: Bound, image: bytearray | None = None) -> int:
        """Where the in-out at `offset` is bound, checked to lie in the image."""
        image = self._image if image is None else image
        target = _BOUND.unpack_from(image, offset)[0]
        size, _ = size_and_align(bound.target, self._layouts.__getitem__)
        if target == 0 or target + size > len(image):
            raise KeyError("an in-out bound to no variable of the image")
        return int(target)

    def _value(self, offset: int, shape: Shape, image: bytearray | None = None) -> Any:
        image = self._image if image is None else image
        match shape:
            case Scalar(code=code):
                value = struct.unpack_from(f"<{_code(code)}", image, offset)[0]
                return None if code == NULLABLE_TIME and value == _NO_TIME else value
            case Chars(length=length, wide=wide):
                count = min(_LENGTH.unpack_from(image, offset)[0], length)
                unit = 2 if wide else 1
                raw = bytes(image[offset + 2 : offset + 2 + unit * count])
                return raw.decode("utf-16-le" if wide else "latin-1")
            case Elements(element=element, count=count):
                stride = size_and_align(element, self._layouts.__getitem__)[0]
                if isinstance(element, Scalar) and element.code != NULLABLE_TIME:
                    return list(struct.unpack_from(f"<{count}{_code(element.code)}", image, offset))
                return [self._value(offset + n * stride, element, image) for n in range(count)]
            case Bound(target=target):
                return self._value(self._target(offset, shape, image), target, image)
        raise TypeError(f"no value of a {type(shape).__name__}")

    def _put(self, image: bytearray, offset: int, shape: Shape, value: Any) -> None:
        """`value` (of the contract's representation) into the bytes at `offset`."""
        match shape:
            case Scalar(code=code):
                if code == NULLABLE_TIME and value is None:
                    value = _NO_TIME
                struct.pack_into(f"<{_code(code)}", image, offset, value)
                return
            case Chars(length=length, wide=wide):
                if not isinstance(value, str) or len(value) > length:
                    raise ValueError(f"{value!r} is no text of at most {length} characters")
                data = value.encode("utf-16-le" if wide else "latin-1")
                if wide and len(data) != 2 * len(value):
                    raise ValueError(f"{value!r} has a character beyond two bytes")
                image[offset + 2 : offset + 2 + len(data)] = data
                _LENGTH.pack_into(image, offset, len(value))
                return
            case Elements(element=element, count=count):
                if not isinstance(value, list) or len(value) != count:
                    raise ValueError(f"an array of {count} elements cannot take {value!r}")
                stride = size_and_align(element, self._layouts.__getitem__)[0]
                for n, item in enumerate(value):
                    self._put(image, offset + n * stride, element, item)
                return
            case Bound(target=target):
                self._put(image, self._target(offset, shape, image), target, value)
                return
        raise TypeError(f"no value into a {type(shape).__name__}")

    # -- the context
    def take(self, *, deferred: bool = False) -> ValueTrees:
        """Every value as `context_snapshot.snapshot` takes it of the objects. With
        `deferred`, a copy of the image's bytes (what the cycle thread spends: 0.6 MB for
        100,000 variables), each tree `Deferred` until the context is encoded."""
        if deferred:
            source = ImageMemory(
                bytearray(self._image), self._layouts, self._placement, self._names, []
            )
            return ValueTrees(
                Deferred(partial(source._root, "_G", True)) if "_G" in self._at else None,
                {name: Deferred(partial(source._root, name, True)) for name in self._programs},
            )
        return ValueTrees(
            self._root("_G") if "_G" in self._at else None,
            {name: self._root(name) for name in self._programs},
        )

    def _root(self, name: str, rows: bool = False) -> Any:
        """The tree of the globals (`_G`) or of a program's instance."""
        place = self._at[name]
        return self._tree(place.offset, Nested(place.cls), rows)

    def _packing(self, scalars: Sequence[tuple[int, Shape]], size: int = 0) -> struct.Struct:
        """The `struct` of elementary values at offsets (ascending), the bytes between them
        skipped, `size` bytes in all at least."""
        codes, end = ["<"], 0
        for offset, shape in scalars:
            assert isinstance(shape, Scalar)
            codes.append(f"{offset - end}x" if offset > end else "")
            codes.append(_code(shape.code))
            end = offset + size_and_align(shape, self._layouts.__getitem__)[0]
        codes.append(f"{size - end}x" if size > end else "")
        return struct.Struct("".join(codes))

    def _records(self, offset: int, element: Nested, count: int) -> Records | None:
        """An array of structures whose members are all elementary, in one `struct` pass
        over its bytes; None for any other."""
        members = sorted(self._layouts[element.cls].members, key=lambda m: m.offset)
        if not all(isinstance(m.shape, Scalar) and m.shape.code != NULLABLE_TIME for m in members):
            return None
        stride = size_and_align(element, self._layouts.__getitem__)[0]
        row = self._packing([(m.offset, m.shape) for m in members], stride)
        data = self._image[offset : offset + count * stride]
        name = self._names.get(element.cls, element.cls)
        return Records(name, tuple(m.name for m in members), list(row.iter_unpack(data)))

    def _tree(self, offset: int, shape: Shape, rows: bool = False) -> Any:
        """The tree of the value at `offset`; with `rows`, an array of structures of
        elementary values as `Records` (what `capture` takes), which the encoder expands."""
        if rows and isinstance(shape, Elements) and isinstance(shape.element, Nested):
            records = self._records(offset, shape.element, shape.count)
            if records is not None:
                return records
        match shape:
            case Nested(cls=cls):
                layout = self._layouts[cls]
                fields = {
                    m.name: self._tree(offset + m.offset, m.shape, rows)
                    for m in sorted(layout.members, key=lambda m: m.name)
                }
                return {CLASS: self._names.get(cls, cls), FIELDS: fields}
            case Elements(element=element, count=count) if not isinstance(element, Scalar):
                stride = size_and_align(element, self._layouts.__getitem__)[0]
                return [self._tree(offset + n * stride, element, rows) for n in range(count)]
            case Bound(target=target):  # the values of the variable it refers to
                return self._tree(self._target(offset, shape), target, rows)
        value = self._value(offset, shape)
        if isinstance(value, list):
            return [_node(item) for item in value]
        return _node(value)

    def restore(self, trees: ValueTrees) -> None:
        """Into a copy of the image first: a tree that does not fit (ContextMismatch)
        leaves the image as it was."""
        scratch = bytearray(self._image)
        if trees.globals is not None and "_G" in self._at:
            self._restore_node(
                scratch, self._at["_G"].offset, Nested(self._at["_G"].cls), trees.globals
            )
        for name, tree in trees.programs.items():
            if name not in self._programs:
                raise ContextMismatch(f"no program {name}")
            place = self._at[name]
            self._restore_node(scratch, place.offset, Nested(place.cls), tree)
        if "_G" in self._at:  # the programs' copies of the globals see them too
            start, size = self._at["_G"].offset, self._layouts[self._at["_G"].cls].size
            for copy in self._copies:
                scratch[copy.offset : copy.offset + size] = scratch[start : start + size]
        self._image[:] = scratch

    def _restore_node(self, image: bytearray, offset: int, shape: Shape, node: Any) -> None:
        if type(node) is Records:
            node = node.nodes()
        match shape:
            case Nested(cls=cls):
                layout = self._layouts[cls]
                name = self._names.get(cls, cls)
                if (
                    type(node) is not dict
                    or node.get(CLASS) != name
                    or type(node.get(FIELDS)) is not dict
                ):
                    raise ContextMismatch(f"expected an instance of {name}")
                fields = node[FIELDS]
                if fields.keys() != {m.name for m in layout.members}:
                    raise ContextMismatch(f"{name} fields differ")
                for member in layout.members:
                    try:
                        self._restore_node(
                            image, offset + member.offset, member.shape, fields[member.name]
                        )
                    except ContextMismatch as exc:
                        exc.path.insert(0, member.name)
                        raise
                return
            case Elements(element=element, count=count):
                if type(node) is not list or len(node) != count:
                    raise ContextMismatch(f"expected an array of {count}")
                stride = size_and_align(element, self._layouts.__getitem__)[0]
                for n, item in enumerate(node):
                    try:
                        self._restore_node(image, offset + n * stride, element, item)
                    except ContextMismatch as exc:
                        exc.path.insert(0, n)
                        raise
                return
            case Bound(target=target):  # into its own storage, where it is bound until a call
                own = offset + shape.own(self._layouts.__getitem__)
                self._restore_node(image, own, target, node)
                _BOUND.pack_into(image, offset, own)
                return
        value = _value_of(node, shape)
        try:
            self._put(image, offset, shape, value)
        except (struct.error, ValueError) as exc:  # out of the range, a text too long
            raise ContextMismatch(f"{value!r} does not fit: {exc}") from None


def _code(code: str) -> str:
    """The `struct` character of a layout's scalar code."""
    return "q" if code == NULLABLE_TIME else code


def _node(value: Any) -> Any:
    """A value as the context's tree holds it: a NaN or an infinity by its bits."""
    if type(value) is float and not math.isfinite(value):
        return nonfinite_node(value)
    return value


def _value_of(node: Any, shape: Shape) -> Any:
    """The value a tree's node stands for, of the kind the variable holds."""
    if type(node) is dict and node.keys() == {IEEE}:
        return nonfinite_value(node[IEEE])
    if isinstance(shape, Scalar):
        if shape.code == "?":
            if type(node) is not bool:
                raise ContextMismatch(f"expected TRUE or FALSE, found {node!r}")
            return node
        if shape.code in ("f", "d"):
            if type(node) not in (int, float):
                raise ContextMismatch(f"expected a number, found {node!r}")
            return float(node)
        if type(node) is not int and not (shape.code == NULLABLE_TIME and node is None):
            raise ContextMismatch(f"expected a whole number, found {node!r}")
    return node
