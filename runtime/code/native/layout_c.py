"""The C declarations of layouts (runtime/contract/layout.py): a struct per class,
member by member, and a static assertion of every member's offset and every struct's size
and alignment, so a C compiler that laid a struct out otherwise than the layout says fails
the build instead of reading the wrong bytes.

A class `POU_MAIN` is `struct L_POU_MAIN`; a member `x` is `v_x` (a variable may be named
as a keyword of C: `auto`, `long`, `union`).
"""

from __future__ import annotations

from runtime.contract.layout import (
    Bound,
    Chars,
    Elements,
    Handle,
    Layout,
    Layouts,
    Nested,
    Offset,
    Scalar,
    Shape,
    Slice,
)

C_TYPES = {
    "?": "uint8_t", "b": "int8_t", "B": "uint8_t", "h": "int16_t", "H": "uint16_t",
    "i": "int32_t", "I": "uint32_t", "q": "int64_t", "Q": "uint64_t", "f": "float",
    "d": "double", "o": "int64_t",
}  # fmt: skip

PRELUDE = """\
#include <stddef.h>
#include <stdint.h>
typedef struct { uint32_t at; uint32_t cls; } padt_handle;
"""


def struct_name(cls: str) -> str:
    return f"L_{cls}"


def member_name(name: str) -> str:
    return f"v_{name}"


def declarations(layouts: Layouts) -> str:
    """The structs of `layouts` (every class a struct holds among them), each after the
    ones it holds, with their assertions (after PRELUDE)."""
    lines: list[str] = []
    done: set[str] = set()
    for name in sorted(layouts):
        _declare(layouts, name, done, lines)
    return "\n".join(lines) + "\n"


def _declare(layouts: Layouts, name: str, done: set[str], lines: list[str]) -> None:
    if name in done:
        return
    done.add(name)
    layout = layouts[name]
    for member in layout.members:
        held = _held_class(member.shape)
        if held is not None:
            _declare(layouts, held, done, lines)
    lines.extend(_struct(layout))


def _held_class(shape: Shape) -> str | None:
    match shape:
        case Nested(cls=cls):
            return cls
        case Elements(element=element) | Bound(target=element):
            return _held_class(element)
    return None


def _struct(layout: Layout) -> list[str]:
    struct = f"struct {struct_name(layout.name)}"
    body = [f"    {_declarator(m.shape, member_name(m.name))};" for m in layout.members]
    if not body:  # a class without slots takes a byte (layout.py)
        body = ["    uint8_t padt_empty;"]
    asserts = [
        f"_Static_assert(offsetof({struct}, {member_name(m.name)}) == {m.offset}, "
        f'"{layout.name}.{m.name}");'
        for m in layout.members
    ]
    asserts.append(f'_Static_assert(sizeof({struct}) == {layout.size}, "{layout.name}");')
    asserts.append(f'_Static_assert(_Alignof({struct}) == {layout.align}, "{layout.name}");')
    return [f"{struct} {{", *body, "};", *asserts]


def _declarator(shape: Shape, name: str) -> str:
    """`int16_t v_x[4][2]` and the like: a C declaration of `name` as `shape`."""
    dims = ""
    while isinstance(shape, Elements):
        dims += f"[{shape.count}]"
        shape = shape.element
    return f"{_type(shape)} {name}{dims}"


def _type(shape: Shape) -> str:
    match shape:
        case Scalar(code=code):
            return C_TYPES[code]
        case Chars(length=length, wide=wide):
            unit = "uint16_t" if wide else "uint8_t"
            return f"struct {{ uint16_t len; {unit} c[{length + 1}]; }}"
        case Nested(cls=cls):
            return f"struct {struct_name(cls)}"
        case Offset():
            return "uint32_t"
        case Bound(target=target):
            return f"struct {{ uint32_t at; {_declarator(target, 'own')}; }}"
        case Handle():
            return "padt_handle"
        case Slice(dims=dims):
            return f"struct {{ uint32_t at; int64_t bounds[{dims}][2]; }}"
    raise AssertionError(shape)
