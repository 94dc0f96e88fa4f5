"""A PLCopen XML file read into a small element tree that knows where each element is.

The file is hostile input. It is parsed with the standard library's expat, which expands
no external entity by itself; on top of that any DOCTYPE is refused before expat reads a
declaration in it, so no entity can be declared at all (no "billion laughs", no quadratic
blow-up, no file or URL pulled in). PLCopen files never carry a DOCTYPE. The size of the
file and the depth of its elements are limited.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from xml.parsers import expat

from backend.compiler.limits import MiB
from backend.engineering.plcopen.issues import ImportCode, ImportFailed, Where

MAX_XML_BYTES = 32 * MiB
MAX_DEPTH = 200  # PLCopen nests a dozen levels; this keeps the tree walks' recursion safe


@dataclass
class Element:
    tag: str  # the local name, without its namespace
    attrs: dict[str, str]
    where: Where
    namespace: str = ""
    children: list[Element] = field(default_factory=list)
    # the children and the character data between them, in document order
    order: list[Element | str] = field(default_factory=list)

    def child(self, tag: str) -> Element | None:
        return next((c for c in self.children if c.tag == tag), None)

    def all(self, tag: str) -> list[Element]:
        return [c for c in self.children if c.tag == tag]

    def text(self) -> str:
        """All character data inside, children's included, in document order."""
        parts: list[str] = []
        stack: list[Element | str] = [self]
        while stack:
            item = stack.pop()
            if isinstance(item, str):
                parts.append(item)
                continue
            stack.extend(reversed(item.order))
        return "".join(parts)


class _Refused(Exception):
    pass


def parse_xml(data: bytes) -> Element:
    """The root element; ImportFailed with the place of the first problem."""
    if len(data) > MAX_XML_BYTES:
        raise ImportFailed(
            Where(1, 1), ImportCode.TOO_LARGE, f"larger than {MAX_XML_BYTES // MiB} MiB"
        )
    parser = expat.ParserCreate(namespace_separator=" ")
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    stack: list[Element] = []
    roots: list[Element] = []
    refusal: list[tuple[Where, str]] = []

    def here() -> Where:
        return Where(parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)

    def refuse(what: str) -> None:
        refusal.append((here(), what))
        raise _Refused

    def start(name: str, attrs: dict[str, str]) -> None:
        if len(stack) >= MAX_DEPTH:
            refusal.append((here(), f"elements nested deeper than {MAX_DEPTH}"))
            raise _Refused
        namespace, _, local = name.rpartition(" ")
        names = {k.rpartition(" ")[2]: v for k, v in attrs.items()}
        element = Element(local, names, here(), namespace)
        if stack:
            stack[-1].children.append(element)
            stack[-1].order.append(element)
        else:
            roots.append(element)
        stack.append(element)

    def end(name: str) -> None:
        stack.pop()

    def characters(text: str) -> None:
        if stack:
            stack[-1].order.append(text)

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = characters
    parser.StartDoctypeDeclHandler = lambda *_: refuse("a DOCTYPE (PLCopen files have none)")
    parser.EntityDeclHandler = lambda *_: refuse("an entity declaration")
    parser.ExternalEntityRefHandler = lambda *_: refuse("an external entity")  # type: ignore[assignment]
    try:
        parser.Parse(data, True)
    except _Refused:
        where, what = refusal[0]
        code = ImportCode.UNSAFE if "nested" not in what else ImportCode.STRUCTURE
        raise ImportFailed(where, code, f"refused: {what}") from None
    except LookupError as exc:  # the XML declaration names an encoding Python lacks
        raise ImportFailed(
            Where(parser.CurrentLineNumber, parser.CurrentColumnNumber + 1),
            ImportCode.MALFORMED,
            f"not readable XML: {exc}",
        ) from None
    except expat.ExpatError as exc:
        message = expat.errors.messages.get(exc.code, str(exc)) if exc.code else str(exc)
        raise ImportFailed(
            Where(exc.lineno, exc.offset + 1),
            ImportCode.MALFORMED,
            f"not well-formed XML: {message}",
        ) from None
    return roots[0]


def st_source(st: Element) -> str:
    """The ST inside an <ST> element: directly (TC6 1.0) or in an <xhtml:p> (2.01); its
    lines as they are, the blank ones around them dropped."""
    text = "".join(child.text() for child in st.children) if st.children else st.text()
    lines = text.split("\n")
    while lines and not lines[0].strip():
        lines.pop(0)
    while lines and not lines[-1].strip():
        lines.pop()
    return "\n".join(line.rstrip() for line in lines)
