"""The element tree of a PLCopen TC6 XML file (versions 1.0 to 2.01) into the model.

Types and initial values become ST text here, FBD and LD bodies `GraphicBody`s
(`graphic.py`). A POU in IL, or with a drawing that cannot be read, becomes a `NotImported`
entry (the importer lists them all); a file that breaks the schema where the import relies
on it fails with the place of the problem.
"""

from __future__ import annotations

import re

from backend.compiler.graphics.model import GraphicBody
from backend.engineering.plcopen.graphic import DrawingProblem, graphic_body
from backend.engineering.plcopen.issues import ImportCode, ImportFailed, Where
from backend.engineering.plcopen.model import (
    Accessor,
    Action,
    Configuration,
    DataType,
    Dropped,
    Instance,
    Interface,
    Method,
    NotImported,
    PlcProject,
    Pou,
    Property,
    Resource,
    Task,
    Variable,
    VarSection,
)
from backend.engineering.plcopen.sfc import SfcProblem, sfc_text
from backend.engineering.plcopen.xml_tree import Element, st_source
from runtime.contract.values import parse_time_literal

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
ADDRESS = re.compile(r"%[IQM][XBWDL]?([0-9]+(\.[0-9]+)*|\*)\Z", re.IGNORECASE)
IEC_TIME = re.compile(r"(T|TIME|LT|LTIME)#[0-9a-zA-Z_.]+\Z", re.IGNORECASE)
XSD_TIME = re.compile(r"(\d+):(\d+):(\d+(?:\.\d+)?)\Z")  # TC6 1.0: xsd:time intervals
POU_KINDS = {"program": "PROGRAM", "functionBlock": "FUNCTION_BLOCK", "function": "FUNCTION"}
SECTIONS = {
    "inputVars": "VAR_INPUT",
    "outputVars": "VAR_OUTPUT",
    "inOutVars": "VAR_IN_OUT",
    "localVars": "VAR",
    "tempVars": "VAR_TEMP",
    "externalVars": "VAR_EXTERNAL",
    "globalVars": "VAR_GLOBAL",
}
QUALIFIERS = (
    ("constant", "CONSTANT"),
    ("retain", "RETAIN"),
    ("nonretain", "NON_RETAIN"),
    ("persistent", "PERSISTENT"),
)
# the elementary types of TC6 (elements named as the IEC type) and the generic ones
ELEMENTARY = frozenset((
    "BOOL", "BYTE", "WORD", "DWORD", "LWORD", "SINT", "INT", "DINT", "LINT", "USINT", "UINT",
    "UDINT", "ULINT", "REAL", "LREAL", "TIME", "DATE", "DT", "TOD", "LTIME", "LDATE", "LDT",
    "LTOD", "CHAR", "WCHAR", "ANY", "ANY_DERIVED", "ANY_ELEMENTARY", "ANY_MAGNITUDE",
    "ANY_NUM", "ANY_REAL", "ANY_INT", "ANY_BIT", "ANY_STRING", "ANY_DATE",
))  # fmt: skip
GRAPHICAL = ("FBD", "LD")
CONFIGURATION_PARTS = {"accessVars": "VAR_ACCESS", "configVars": "VAR_CONFIG"}
NOT_TYPES = ("documentation", "addData")
# CODESYS's access modifiers (attributes of <AccessModifiers>): ST keyword by attribute
ACCESS = {a.lower(): a for a in ("PUBLIC", "PRIVATE", "PROTECTED", "INTERNAL")}
MODIFIERS = {m.lower(): m for m in ("ABSTRACT", "FINAL")}


def fail(element: Element, message: str, code: ImportCode = ImportCode.STRUCTURE) -> ImportFailed:
    return ImportFailed(element.where, code, message)


def name_of(element: Element, attribute: str = "name") -> str:
    """An attribute that must be an IEC identifier: it names files and ST declarations."""
    value = element.attrs.get(attribute)
    if value is None:
        raise fail(element, f"<{element.tag}> without its {attribute} attribute")
    if not IDENTIFIER.match(value):
        raise fail(
            element, f"<{element.tag}> {attribute} {value!r} is no IEC identifier", ImportCode.NAME
        )
    return value


def required(element: Element, tag: str) -> Element:
    found = element.child(tag)
    if found is None:
        raise fail(element, f"<{element.tag}> without <{tag}>")
    return found


def flag(element: Element, attribute: str) -> bool:
    return element.attrs.get(attribute, "false").strip().lower() in ("true", "1")


def single_child(element: Element) -> Element:
    """The one element inside a wrapper like <type>, <baseType>, <initialValue>."""
    inner = [c for c in element.children if c.tag not in NOT_TYPES]
    if len(inner) != 1:
        raise fail(element, f"<{element.tag}> must hold exactly one element, not {len(inner)}")
    return inner[0]


# ---- types and values -------------------------------------------------------------------


# ST declares an enum, a structure or a subrange without a name only in some places: a
# variable or a data type takes any; a structure member a subrange; the element type of an
# array, the target of a pointer and the base type of an enum or a subrange none
ANONYMOUS = {"enum", "struct", "subrangeSigned", "subrangeUnsigned"}
TAKES = {"declaration": ANONYMOUS, "member": {"subrangeSigned", "subrangeUnsigned"}, "named": set()}


def type_text(wrapper: Element, place: str = "declaration") -> str:
    """The ST of the type inside <type>, <baseType> or <returnType>, at `place` (a key of
    TAKES)."""
    element = single_child(wrapper)
    tag = element.tag
    if tag in ANONYMOUS and tag not in TAKES[place]:
        raise fail(
            element,
            f"an <{tag}> without a name inside <{wrapper.tag}> has no ST form: declare it as a "
            "data type and use its name",
        )
    if tag in ("string", "wstring"):
        length = element.attrs.get("length", "").strip()
        if length and not length.isdigit():
            raise fail(element, f"string length {length!r} is no whole number")
        base = "STRING" if tag == "string" else "WSTRING"
        return f"{base}[{length}]" if length else base
    if tag == "derived":
        return name_of(element)
    if tag == "array":
        ranges = []
        for dimension in element.all("dimension"):
            lower, upper = dimension.attrs.get("lower"), dimension.attrs.get("upper")
            if lower is None or upper is None:
                raise fail(dimension, "<dimension> needs lower and upper")
            ranges.append(f"{_bound(dimension, lower)}..{_bound(dimension, upper)}")
        if not ranges:
            raise fail(element, "<array> without a <dimension>")
        element_type = type_text(required(element, "baseType"), "named")
        return f"ARRAY [{', '.join(ranges)}] OF {element_type}"
    if tag in ("subrangeSigned", "subrangeUnsigned"):
        bounds = required(element, "range")
        lower, upper = bounds.attrs.get("lower"), bounds.attrs.get("upper")
        if lower is None or upper is None:
            raise fail(bounds, "<range> needs lower and upper")
        base = type_text(required(element, "baseType"), "named")
        return f"{base} ({_bound(bounds, lower)}..{_bound(bounds, upper)})"
    if tag == "enum":
        values = []
        for entry in required(element, "values").all("value"):
            name = name_of(entry)
            number = entry.attrs.get("value")
            values.append(f"{name} := {_bound(entry, number)}" if number else name)
        if not values:
            raise fail(element, "<enum> without a <value>")
        declared = element.child("baseType")
        prefix = f"{type_text(declared, 'named')} " if declared is not None else ""
        return f"{prefix}({', '.join(values)})"
    if tag == "struct":
        members = "".join(f"    {v.declaration()};\n" for v in variables(element, "member"))
        if not members:
            raise fail(element, "<struct> without a member")
        return f"STRUCT\n{members}END_STRUCT"
    if tag == "pointer":
        return f"REF_TO {type_text(required(element, 'baseType'), 'named')}"
    if tag in ELEMENTARY:
        return tag
    raise fail(element, f"<{tag}> is no type padt knows")


def _bound(element: Element, text: str) -> str:
    """An array bound, subrange bound or enum value: an integer (or a constant's name)."""
    text = text.strip()
    if not re.fullmatch(r"[+-]?[0-9_]+|[+-]?[A-Za-z_][A-Za-z0-9_]*(#[0-9A-Za-z_]+)?", text):
        raise fail(element, f"{text!r} is no integer or constant name")
    return text


def value_text(wrapper: Element) -> str:
    """The ST initializer of <initialValue> (or of a <value> inside an array or struct)."""
    element = single_child(wrapper)
    if element.tag == "simpleValue":
        simple = element.attrs.get("value")
        if simple is None:
            raise fail(element, "<simpleValue> without its value")
        if "\n" in simple or "\r" in simple:  # a declaration ends at its line in the ST file
            raise fail(element, "a value that spans lines")
        return simple.strip()
    if element.tag == "arrayValue":
        items = []
        for value in element.all("value"):
            text = value_text(value)
            repeat = value.attrs.get("repetitionValue", "").strip()
            if repeat and not repeat.isdigit():
                raise fail(value, f"repetitionValue {repeat!r} is no whole number")
            items.append(f"{repeat}({text})" if repeat and repeat != "1" else text)
        return f"[{', '.join(items)}]"
    if element.tag == "structValue":
        members = [
            f"{name_of(value, 'member')} := {value_text(value)}" for value in element.all("value")
        ]
        if not members:
            raise fail(element, "<structValue> without a member")
        return f"({', '.join(members)})"
    raise fail(element, f"<{element.tag}> is no initial value")


def initial_text(wrapper: Element, type_st: str) -> str:
    """An initial value for a variable or type of `type_st`. A plain value of a STRING is
    written unquoted by some tools (matiec's tests: `str test name`); it is quoted here, as
    Beremiz does when it generates ST."""
    text = value_text(wrapper)
    wide = type_st.upper().startswith("WSTRING")
    if not (wide or type_st.upper().startswith("STRING")) or text[:1] in ("'", '"'):
        return text
    if single_child(wrapper).tag != "simpleValue":
        return text
    quote = '"' if wide else "'"
    return quote + text.replace("$", "$$").replace(quote, "$" + quote) + quote


def _comment(element: Element) -> str:
    documentation = element.child("documentation")
    if documentation is None:
        return ""
    return documentation.text().strip()


def variables(section: Element, place: str = "declaration") -> tuple[Variable, ...]:
    found = []
    for variable in section.all("variable"):
        address = variable.attrs.get("address", "").strip()
        if address and not ADDRESS.match(address):
            raise fail(variable, f"address {address!r} is no direct address (%IX0.0, %QW3, ...)")
        initial = variable.child("initialValue")
        type_st = type_text(required(variable, "type"), place)
        found.append(
            Variable(
                name=name_of(variable),
                type=type_st,
                address=address,
                initial=initial_text(initial, type_st) if initial is not None else "",
                comment=_comment(variable),
            )
        )
    return tuple(found)


def var_section(element: Element, kind: str) -> VarSection:
    qualifiers = tuple(st for attribute, st in QUALIFIERS if flag(element, attribute))
    return VarSection(kind, qualifiers, variables(element))


# ---- POUs -------------------------------------------------------------------------------


class _Refused(Exception):
    """The POU cannot be imported: `reason` says why (a language, or a sentence); `where`,
    the place of a fault in a drawing."""

    def __init__(self, reason: str, where: Where | None = None) -> None:
        super().__init__(reason)
        self.reason = reason
        self.where = where


def _language(body: Element) -> Element:
    language = [c for c in body.children if c.tag not in NOT_TYPES]
    if len(language) != 1:
        raise _Refused(f"a <{body.tag}> at line {body.where.line} with {len(language)} languages")
    return language[0]


def st_text(body: Element) -> str:
    """The ST of a body, an action or a transition (the bodies that must be ST)."""
    element = _language(body)
    if (
        element.tag in GRAPHICAL
    ):  # the grammar takes a drawing as the body of a POU or an action only
        raise _Refused(f"{element.tag}, which padt takes as the body of a POU or an action only")
    if element.tag == "IL":  # the importer says why
        raise _Refused(element.tag)
    if element.tag != "ST":
        raise _Refused(f"a body in <{element.tag}>")
    return st_source(element)


def drawn_or_st(body: Element) -> tuple[str, GraphicBody | None]:
    """The ST of a POU's body, or its drawing in FBD or LD."""
    element = _language(body)
    if element.tag not in GRAPHICAL:
        return st_text(body), None
    try:
        return "", graphic_body(element)
    except DrawingProblem as problem:
        raise _Refused(f"{element.tag}: {problem.message}", problem.where) from None


def _declarations(interface: Element | None) -> tuple[str, tuple[VarSection, ...]]:
    """The result type and the variable sections of an <interface> (of a POU, a method or
    an accessor)."""
    sections: list[VarSection] = []
    return_type = ""
    for part in interface.children if interface is not None else []:
        if part.tag == "returnType":
            return_type = type_text(part)
        elif part.tag in SECTIONS:
            sections.append(var_section(part, SECTIONS[part.tag]))
        elif part.tag not in NOT_TYPES:
            raise _Refused(f"<{part.tag}> in its interface")
    return return_type, tuple(sections)


def pou(element: Element) -> Pou | NotImported:
    name = name_of(element)
    kind = POU_KINDS.get(element.attrs.get("pouType", ""))
    if kind is None:
        raise fail(element, f"POU {name}: pouType {element.attrs.get('pouType')!r} is unknown")
    interface = element.child("interface")
    try:
        return_type, sections = _declarations(interface)
        actions = _actions(element)
        transitions = _transitions(element)
        bodies = element.all("body")
        if len(bodies) > 1:
            raise fail(bodies[1], f"POU {name} has more than one <body>")
        body = _body(bodies[0], actions, transitions) if bodies else ("", None, ())
        holders = _holders(element)
        methods = tuple(_method(m) for d in _data(holders, "method") for m in d.all("Method"))
        properties = tuple(
            _property(p) for d in _data(holders, "property") for p in d.all("Property")
        )
    except _Refused as refused:
        return NotImported(name, refused.reason, element.where, refused.where)
    extends, implements = _inheritance(holders)
    if len(extends) > 1:
        raise fail(element, f"POU {name} extends {', '.join(extends)}: a block extends one")
    text, drawn, inline_actions = body
    return Pou(
        name, kind, return_type, sections, text, (*actions, *inline_actions),
        _comment(element), element.where, "".join(extends), implements, methods, properties,
        drawn,
    )  # fmt: skip


# ---- CODESYS's object orientation (in <addData>, outside the TC6 schema) ------------------
#
# CODESYS writes a POU's methods and properties into its <addData> (`<data name="http://
# www.3s-software.com/plcopenxml/method"><Method name=...>`, `.../property`), its EXTENDS
# and IMPLEMENTS into its interface's (`.../pouinheritance`: <Inheritance> with <Extends>
# and <Implements>), the access of a method or property into the <addData> of the
# method's interface (`.../accessmodifiers`: `<AccessModifiers Private="true"/>`, empty for
# none), and each INTERFACE into the project's <addData> (`.../interface`: <Interface> with
# <Methods> and <Properties>).


def _holders(element: Element) -> list[Element]:
    """The <addData> of an element and of its <interface>, where CODESYS writes."""
    interface = element.child("interface")
    found = [element.child("addData")]
    if interface is not None:
        found.append(interface.child("addData"))
    return [h for h in found if h is not None]


def _data(holders: list[Element], kind: str) -> list[Element]:
    """The <data> of the holders that CODESYS names `.../plcopenxml/<kind>`."""
    return [
        data
        for holder in holders
        for data in holder.all("data")
        if data.attrs.get("name", "").rstrip("/").rpartition("/")[2].lower() == kind
    ]


def _names(element: Element) -> tuple[str, ...]:
    """The names in an <Extends> or <Implements> (one, or several with commas)."""
    found = []
    for text in element.text().split(","):
        if not IDENTIFIER.match(text.strip()):
            raise fail(
                element, f"<{element.tag}> {text.strip()!r} is no IEC identifier", ImportCode.NAME
            )
        found.append(text.strip())
    return tuple(found)


def _inheritance(holders: list[Element]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """EXTENDS and IMPLEMENTS from CODESYS's <Inheritance> elements."""
    extends: list[str] = []
    implements: list[str] = []
    for data in _data(holders, "pouinheritance") + _data(holders, "interfaceinheritance"):
        for inheritance in data.all("Inheritance"):
            for part in inheritance.children:
                if part.tag == "Extends":
                    extends += _names(part)
                elif part.tag == "Implements":
                    implements += _names(part)
    return tuple(extends), tuple(implements)


def _access(element: Element) -> tuple[str, tuple[str, ...]]:
    """The access specifier and the modifiers of a method or property. CODESYS makes one
    without an access specifier PUBLIC, IEC (and padt) PROTECTED: the import writes the
    access CODESYS means, PUBLIC where the export names none."""
    access = "PUBLIC"
    modifiers: list[str] = []
    for data in _data(_holders(element), "accessmodifiers"):
        for marks in data.all("AccessModifiers"):
            for attribute in sorted(a for a in marks.attrs if flag(marks, a)):
                if attribute.lower() in ACCESS:
                    access = ACCESS[attribute.lower()]
                elif attribute.lower() in MODIFIERS:
                    modifiers.append(MODIFIERS[attribute.lower()])
    return access, tuple(sorted(set(modifiers)))


def _method(element: Element, prototype: bool = False) -> Method:
    """A method of a POU (with its ST body) or, `prototype`, of an interface."""
    name = name_of(element)
    try:
        return_type, sections = _declarations(element.child("interface"))
        access, modifiers = _access(element)
        body = element.child("body")
        if prototype or "ABSTRACT" in modifiers:
            text = None
        else:
            text = st_text(body) if body is not None else ""
    except _Refused as refused:
        raise _Refused(f"method {name} in {refused.reason}") from None
    return Method(name, access, modifiers, return_type, sections, text, _comment(element))


def _property(element: Element, prototype: bool = False) -> Property:
    """A property with its GET and SET (<GetAccessor>, <SetAccessor>, in either order)."""
    name = name_of(element)
    try:
        type_st, sections = _declarations(element.child("interface"))
        access, modifiers = _access(element)
    except _Refused as refused:
        raise _Refused(f"property {name} in {refused.reason}") from None
    if not type_st or sections:
        raise fail(element, f"property {name}: its <interface> holds its type, and only that")
    accessors: dict[str, Accessor | None] = {}
    for tag, word in (("GetAccessor", "GET"), ("SetAccessor", "SET")):
        accessor = element.child(tag)
        if accessor is None:
            accessors[word] = None
            continue
        try:
            _, own = _declarations(accessor.child("interface"))
            body = accessor.child("body")
            text = "" if prototype or body is None else st_text(body)
        except _Refused as refused:
            raise _Refused(f"property {name} {word} in {refused.reason}") from None
        accessors[word] = Accessor(() if prototype else own, text)
    return Property(
        name, access, modifiers, type_st, accessors["GET"], accessors["SET"], _comment(element)
    )


def codesys_interface(element: Element) -> Interface:
    """A CODESYS interface: method and property prototypes, and what it extends."""
    name = name_of(element)
    holders = _holders(element)
    methods = [m for group in element.all("Methods") for m in group.all("Method")]
    methods += [m for d in _data(holders, "method") for m in d.all("Method")]
    properties = [p for group in element.all("Properties") for p in group.all("Property")]
    properties += [p for d in _data(holders, "property") for p in d.all("Property")]
    try:
        found = (
            tuple(_method(m, prototype=True) for m in methods),
            tuple(_property(p, prototype=True) for p in properties),
        )
    except _Refused as refused:  # only an unknown part of a prototype's interface
        raise fail(element, f"interface {name}: {refused.reason}") from None
    extends, _ = _inheritance(holders)
    return Interface(name, extends, *found, _comment(element), element.where)


def _actions(element: Element) -> tuple[Action, ...]:
    holder = element.child("actions")
    if holder is None:
        return ()
    found = []
    for action in holder.all("action"):
        name = name_of(action)
        try:
            found.append(Action(name, *drawn_or_st(required(action, "body"))))
        except _Refused as refused:
            raise _Refused(f"action {name} in {refused.reason}") from None
    return tuple(found)


def _transitions(element: Element) -> dict[str, str]:
    """Named transitions of an SFC (`<condition><reference name=...>`): their conditions."""
    holder = element.child("transitions")
    if holder is None:
        return {}
    found = {}
    for transition in holder.all("transition"):
        name = name_of(transition)
        try:
            text = st_text(required(transition, "body"))
        except _Refused as refused:
            raise _Refused(f"transition {name} in {refused.reason}") from None
        found[name.upper()] = transition_condition(name, text)
    return found


def transition_condition(name: str, text: str) -> str:
    """A named transition's ST body as an expression: `expr`, `:= expr;` or `name := expr;`
    (the textual SFC of padt takes an expression)."""
    text = re.sub(r"^\s*:=", "", text).strip()
    match = re.fullmatch(rf"{re.escape(name)}\s*:=\s*(.*?);?", text, re.IGNORECASE | re.DOTALL)
    condition = match.group(1) if match else text.removesuffix(";")
    if ";" in condition.replace("';'", ""):
        raise _Refused(f"transition {name}: a body of statements (padt takes an expression)")
    return condition.strip()


def _body(
    body: Element, actions: tuple[Action, ...], transitions: dict[str, str]
) -> tuple[str, GraphicBody | None, tuple[Action, ...]]:
    """The ST or SFC text of a POU's body, or its drawing; and the inline actions of SFC."""
    language = [c for c in body.children if c.tag not in NOT_TYPES]
    if len(language) == 1 and language[0].tag == "SFC":
        try:
            chart = sfc_text(language[0], transitions, {a.name.upper() for a in actions})
        except SfcProblem as problem:
            raise _Refused(f"SFC: {problem}") from None
        return chart.text, None, tuple(Action(name, text) for name, text in chart.inline_actions)
    return *drawn_or_st(body), ()


# ---- data types, configurations ---------------------------------------------------------


def codesys_parts(element: Element) -> list[Dropped]:
    """What CODESYS adds to a data type in <addData> that changes its meaning and padt has
    no ST for (a structure's EXTENDS): named, since the import leaves it out."""
    found = []
    for data in _data(_holders(element), "datatypeinheritance"):
        bases = [e.text().strip() for i in data.all("Inheritance") for e in i.all("Extends")]
        listed = ", ".join(n for n in bases if IDENTIFIER.match(n))
        found.append(Dropped(name_of(element), f"EXTENDS {listed}".strip(), data.where))
    return found


def data_type(element: Element) -> DataType:
    name = name_of(element)
    declaration = type_text(required(element, "baseType"))
    initial = element.child("initialValue")
    if initial is not None:
        declaration += f" := {initial_text(initial, declaration)}"
    return DataType(name, declaration, element.where)


def interval_ms(task: Element) -> int | None:
    text = task.attrs.get("interval", "").strip()
    if not text:
        return None
    if IEC_TIME.match(text):
        nanoseconds, _ = parse_time_literal(text)
    elif match := XSD_TIME.match(text):
        hours, minutes, seconds = match.groups()
        nanoseconds = round((int(hours) * 3600 + int(minutes) * 60 + float(seconds)) * 1e9)
    else:
        raise fail(task, f"task interval {text!r} is no time (T#20ms)")
    return nanoseconds // 1_000_000


def _instance(element: Element, task: str) -> Instance:
    pou_name = element.attrs.get("typeName", element.attrs.get("type"))
    if pou_name is None:
        raise fail(element, "<pouInstance> without its typeName")
    if not IDENTIFIER.match(pou_name):
        raise fail(element, f"typeName {pou_name!r} is no IEC identifier", ImportCode.NAME)
    return Instance(name_of(element), pou_name, task, element.where)


def resource(element: Element) -> Resource:
    tasks, instances, globals_ = [], [], []
    for child in element.children:
        if child.tag == "task":
            priority = child.attrs.get("priority", "0").strip()
            if not priority.isdigit():
                raise fail(child, f"task priority {priority!r} is no whole number")
            task = Task(name_of(child), int(priority), interval_ms(child), child.where)
            tasks.append(task)
            instances += [_instance(i, task.name) for i in child.all("pouInstance")]
        elif child.tag == "pouInstance":
            instances.append(_instance(child, ""))
        elif child.tag == "globalVars":
            globals_.append(var_section(child, "VAR_GLOBAL"))
    return Resource(
        name_of(element), tuple(tasks), tuple(instances), tuple(globals_), element.where
    )


def read_project(root: Element) -> PlcProject:
    if root.tag != "project" or not root.namespace.startswith("http://www.plcopen.org/xml/tc6"):
        raise fail(
            root,
            f"the root element is <{root.tag}> of namespace {root.namespace or 'none'!r}, "
            "not a PLCopen TC6 <project>",
            ImportCode.NOT_PLCOPEN,
        )
    header = root.child("contentHeader")
    attrs = header.attrs if header is not None else {}
    project = PlcProject(attrs.get("name", ""), attrs.get("version", ""))
    types = required(root, "types")
    for element in (types.child("dataTypes") or types).all("dataType"):
        project.types.append(data_type(element))
        project.dropped += codesys_parts(element)
    for element in (types.child("pous") or types).all("pou"):
        read = pou(element)
        if isinstance(read, Pou):
            project.pous.append(read)
        else:
            project.not_imported.append(read)
    extra = root.child("addData")
    for data in extra.all("data") if extra is not None else []:
        project.globals += [var_section(g, "VAR_GLOBAL") for g in data.all("globalVars")]
    extras = [extra] if extra is not None else []
    for data in _data(extras, "interface"):
        project.interfaces += [codesys_interface(i) for i in data.all("Interface")]
    instances = root.child("instances")
    holder = instances.child("configurations") if instances is not None else None
    for configuration in holder.all("configuration") if holder is not None else []:
        for part in configuration.children:
            if part.tag in CONFIGURATION_PARTS:
                project.left_out.append(
                    (part.where, f"{CONFIGURATION_PARTS[part.tag]} of configuration left out")
                )
        project.configurations.append(
            Configuration(
                name_of(configuration),
                tuple(resource(r) for r in configuration.all("resource")),
                tuple(var_section(g, "VAR_GLOBAL") for g in configuration.all("globalVars")),
                configuration.where,
            )
        )
    return project
