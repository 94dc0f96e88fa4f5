"""The element tree of a PLCopen TC6 XML file (versions 1.0 to 2.01) into the model.

Types and initial values become ST text here. A POU in a graphical language or IL becomes
a `NotImported` entry (the importer lists them all); a file that breaks the schema where
the import relies on it fails with the place of the problem.
"""

from __future__ import annotations

import re

from backend.compiler.parse import parse_time_literal
from backend.engineering.plcopen.issues import ImportCode, ImportFailed
from backend.engineering.plcopen.model import (
    Action,
    Configuration,
    DataType,
    Dropped,
    Instance,
    NotImported,
    PlcProject,
    Pou,
    Resource,
    Task,
    Variable,
    VarSection,
)
from backend.engineering.plcopen.sfc import SfcProblem, sfc_text
from backend.engineering.plcopen.xml_tree import Element, st_source

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
GRAPHICAL = ("FBD", "LD", "IL")
CONFIGURATION_PARTS = {"accessVars": "VAR_ACCESS", "configVars": "VAR_CONFIG"}
NOT_TYPES = ("documentation", "addData")
# CODESYS keeps these in the <addData> of a POU, its interface or a data type, under
# `<data name="http://www.3s-software.com/plcopenxml/method">` and the like: a part of the
# name -> what padt does not read there
CODESYS_PARTS = (
    ("method", "methods"),
    ("property", "properties"),
    ("inheritance", "EXTENDS"),
    ("implement", "IMPLEMENTS"),
)


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
    """The POU cannot be imported: `reason` says why (a language, or a sentence)."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


def st_text(body: Element) -> str:
    """The ST of a body, an action or a transition."""
    language = [c for c in body.children if c.tag not in NOT_TYPES]
    if len(language) != 1:
        raise _Refused(f"a <{body.tag}> at line {body.where.line} with {len(language)} languages")
    element = language[0]
    if element.tag in GRAPHICAL:
        raise _Refused(element.tag)
    if element.tag != "ST":
        raise _Refused(f"a body in <{element.tag}>")
    return st_source(element)


def pou(element: Element) -> Pou | NotImported:
    name = name_of(element)
    kind = POU_KINDS.get(element.attrs.get("pouType", ""))
    if kind is None:
        raise fail(element, f"POU {name}: pouType {element.attrs.get('pouType')!r} is unknown")
    sections: list[VarSection] = []
    return_type = ""
    interface = element.child("interface")
    try:
        for part in interface.children if interface is not None else []:
            if part.tag == "returnType":
                return_type = type_text(part)
            elif part.tag in SECTIONS:
                sections.append(var_section(part, SECTIONS[part.tag]))
            elif part.tag not in NOT_TYPES:
                raise _Refused(f"<{part.tag}> in its interface")
        actions = _actions(element)
        transitions = _transitions(element)
        bodies = element.all("body")
        if len(bodies) > 1:
            raise fail(bodies[1], f"POU {name} has more than one <body>")
        body = _body(bodies[0], actions, transitions) if bodies else ("", ())
    except _Refused as refused:
        return NotImported(name, refused.reason, element.where)
    text, inline_actions = body
    return Pou(
        name, kind, return_type, tuple(sections), text, (*actions, *inline_actions),
        _comment(element), element.where,
    )  # fmt: skip


def _actions(element: Element) -> tuple[Action, ...]:
    holder = element.child("actions")
    if holder is None:
        return ()
    found = []
    for action in holder.all("action"):
        name = name_of(action)
        try:
            found.append(Action(name, st_text(required(action, "body"))))
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
) -> tuple[str, tuple[Action, ...]]:
    language = [c for c in body.children if c.tag not in NOT_TYPES]
    if len(language) == 1 and language[0].tag == "SFC":
        try:
            chart = sfc_text(language[0], transitions, {a.name.upper() for a in actions})
        except SfcProblem as problem:
            raise _Refused(f"SFC: {problem}") from None
        return chart.text, tuple(Action(name, text) for name, text in chart.inline_actions)
    return st_text(body), ()


# ---- data types, configurations ---------------------------------------------------------


def codesys_parts(element: Element) -> list[Dropped]:
    """What CODESYS adds to a POU or data type in <addData> that changes its meaning
    (methods, properties, inheritance): named, since the import does not read it."""
    found = []
    interface = element.child("interface")
    holders = [
        element.child("addData"),
        interface.child("addData") if interface is not None else None,
    ]
    for data in (d for h in holders if h is not None for d in h.all("data")):
        kind = data.attrs.get("name", "").rstrip("/").rpartition("/")[2].lower()
        what = next((what for part, what in CODESYS_PARTS if part in kind), None)
        if what is not None:
            names = [c.attrs.get("name", "") for c in data.children]
            listed = ", ".join(n for n in names if IDENTIFIER.match(n))
            found.append(Dropped(name_of(element), f"{what} {listed}".strip(), data.where))
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
            project.dropped += codesys_parts(element)
        else:
            project.not_imported.append(read)
    extra = root.child("addData")
    for data in extra.all("data") if extra is not None else []:
        project.globals += [var_section(g, "VAR_GLOBAL") for g in data.all("globalVars")]
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
