"""Views of a configuration's memory image (docs/native-code.md, "Python code uses views"):
a class per generated class whose instances read and write the image's bytes, so that
Python code (a body left to Python, the debugger, a service not on the accessor) works on
the image as it works on slot objects.

`padt_memory.c` is compiled once per machine into the native cache, like a unit, and
loaded once per process. A view class is a subclass of its `View` with a `Field`
descriptor per member of the class's layout and the functions of the generated class (its
body, methods, actions), so `view.__call__()` runs the generated Python on the image. Its
`__slots__` names the members, as a slot object's class does, for whoever lists them
(the context snapshot). A block's in-out of an array, a structure or a block no block
extends reads as a view of the variable it is bound to. References, interfaces, in-outs
of blocks another block extends and of open arrays have no view yet: `ViewsRefused` says
which member.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

from runtime.code.native.build import Toolchain, runtime_module
from runtime.contract.layout import (
    Bound,
    Chars,
    Elements,
    Layout,
    Layouts,
    Nested,
    Scalar,
    Shape,
    size_and_align,
)

SOURCE = Path(__file__).with_name("padt_memory.c")
# what a class may have besides its slots: the generated code's functions, `KIND__`
_NOT_COPIED = frozenset({"__slots__", "__init__", "__dict__", "__weakref__", "__doc__"})


class ViewsRefused(ValueError):
    """A class that has no view yet; the message names the member."""


def memory_module(cache: Path, toolchain: Toolchain) -> ModuleType:
    """padt_memory, built into `cache` unless it is there, loaded once per process."""
    return runtime_module("padt_memory", SOURCE, cache, toolchain)


def view_classes(
    memory: ModuleType, layouts: Layouts, classes: Mapping[str, type]
) -> dict[str, type]:
    """A view class per layout, with the functions of the class of the same name in
    `classes` (the generated classes, and the runtime's classes an image holds)."""
    made: dict[str, type] = {}
    for name in sorted(layouts):
        _make(memory, layouts, classes, name, made)
    return made


def _make(
    memory: ModuleType,
    layouts: Layouts,
    classes: Mapping[str, type],
    name: str,
    made: dict[str, type],
) -> type:
    done = made.get(name)
    if done is not None:
        return done
    layout = layouts[name]
    for member in layout.members:  # the classes it holds first: their fields need them
        held = _held(member.shape)
        if held is not None:
            _make(memory, layouts, classes, held, made)
    space: dict[str, Any] = {
        key: value
        for key, value in vars(classes[name]).items()
        if key not in _NOT_COPIED and not _is_member_descriptor(value)
    }
    space.update(_fields(memory, layouts, layout, made))
    space["__slots__"] = ()
    space["__size__"] = layout.size
    view = type(classes[name].__name__, (memory.View,), space)
    # set after the class is made: as a class body's `__slots__` it would make slots
    view.__slots__ = tuple(m.name for m in layout.members)  # type: ignore[attr-defined]
    made[name] = view
    return view


def _is_member_descriptor(value: object) -> bool:
    return type(value).__name__ == "member_descriptor"


def _held(shape: Shape) -> str | None:
    match shape:
        case Nested(cls=cls):
            return cls
        case Elements(element=element) | Bound(target=element):
            return _held(element)
    return None


def _fields(
    memory: ModuleType, layouts: Layouts, layout: Layout, made: dict[str, type]
) -> dict[str, Any]:
    fields = {}
    for member in layout.members:
        try:
            fields[member.name] = _field(memory, layouts, member.shape, member.offset, made)
        except ViewsRefused as refused:
            raise ViewsRefused(f"{layout.name}.{member.name}: {refused}") from None
    return fields


def _field(
    memory: ModuleType, layouts: Layouts, shape: Shape, offset: int, made: dict[str, type]
) -> Any:
    size, _ = size_and_align(shape, layouts.__getitem__)
    match shape:
        case Scalar(code=code):
            return memory.Field(code, offset, size)
        case Chars(length=length, wide=wide):
            return memory.Field("w" if wide else "s", offset, size, length)
        case Nested(cls=cls):
            return memory.Field("n", offset, size, view_type=made[cls])
        case Elements(element=element, count=count):
            stride, _ = size_and_align(element, layouts.__getitem__)
            inner = _field(memory, layouts, element, 0, made)
            return memory.Field("a", offset, size, element=inner, count=count, stride=stride)
        case Bound(target=target):
            inner = _field(memory, layouts, target, 0, made)
            own = shape.own(layouts.__getitem__)
            return memory.Field("r", offset, size, element=inner, own=own)
    raise ViewsRefused(f"no view of {type(shape).__name__} yet")


def is_array(value: object) -> bool:
    """A list, or an array of an image (padt_memory's Elements): a sequence, no text."""
    return hasattr(value, "__len__") and not isinstance(value, str)


def is_instance(value: object) -> bool:
    """A slot object or a view: its class names its members."""
    return hasattr(type(value), "__slots__") and not isinstance(value, str)
