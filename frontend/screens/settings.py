"""The Settings screen: padt.toml of the project chosen in the navigation as forms (the
resource and its parameters, the program instances, the Modbus server and devices), over
`backend/engineering/project_settings.py`. What is typed goes into a draft at once; the
service checks the draft field by field and then by a compile, on a thread of the screen's
own (the newest draft only), and each problem is shown beside its field and in the list
above. **Save** writes padt.toml (Read+Write level), comments and untouched values kept,
refused when padt.toml changed on disk since it was read. A Read-only user sees the forms
greyed out."""

from __future__ import annotations

import copy
import html
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import viser

from backend.engineering.project_access import Editor
from backend.engineering.project_settings import (
    ModbusDevice,
    Problem,
    ProgramSettings,
    Settings,
    read_settings,
    settings_problems,
    write_settings,
)
from frontend.editor.latest_work import LatestWork
from frontend.gui_value import set_value
from frontend.permissions import PADT_ACTORS
from frontend.screen_registry import Now, Screen, Work
from frontend.screens.parameters import LABELS, parse_value, value_range
from runtime.contract.parameters import (
    PROGRAM_PARAMETERS,
    RESOURCE_PARAMETERS,
    ParameterError,
    ParameterSpec,
)
from runtime.contract.refusal import Refusal

DEFAULT = "(default)"
NONE = "(none)"
DEVICE_FIELDS = (
    ("unit_id", "Unit id"),
    ("period_ms", "Poll period ms"),
    ("timeout_ms", "Timeout ms"),
)
_RED = "color:#c92a2a;font-size:0.85em"
_GREY = "color:#868e96;font-size:0.85em"


@dataclass
class Field:
    """One input of the forms and the note beside it; `key` is the field as the service
    names it in a problem (`resource.watchdog_ms`, `resource.program.0.priority`)."""

    handle: Any  # a viser text input or dropdown
    note: viser.GuiHtmlHandle
    key: Callable[[], str]


@dataclass
class Loaded:
    project: str
    draft: Settings
    base_hash: str


@dataclass
class Checked:
    """The service's answer for one draft, written by the checking thread."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    version: int = 0  # of the draft it checked
    problems: list[Problem] = field(default_factory=list)


class SettingsScreen(Screen):
    name = "Settings"
    icon = viser.Icon.SETTINGS

    def __init__(self, work: Work) -> None:
        super().__init__(work)
        gui = work.gui
        self.editor = Editor(work.user, work.level)
        self.writes = work.level in PADT_ACTORS
        self.typing: dict[str, str] = {}  # label -> why what is typed is not of its type
        self.loaded: Loaded | None = None
        self.fields: list[Field] = []
        self.version = 0  # of the draft, one more at each change
        self.checked = Checked()
        self.shown_version = -1
        self.checker = LatestWork("settings-check")
        self.header = gui.add_html("")
        self.problems = gui.add_html("")
        # on top, where the problems are listed: the forms below are long
        self.save = gui.add_button("Save padt.toml", color="blue", disabled=True)
        self.save.on_click(lambda _: self._save())
        self.saved = gui.add_html("")
        reread = gui.add_button("Read padt.toml again")
        reread.on_click(lambda _: self._load(self.loaded.project if self.loaded else None))
        with gui.add_folder("Resource"):
            self.resource_name = self._text("Resource name", _fixed("resource.name"))
            self.resource_note = gui.add_html("")
            self.resource_fields = {
                spec.name: self._parameter(spec, LABELS[spec.name], "resource")
                for spec in RESOURCE_PARAMETERS
            }
        with gui.add_folder("Program instances"):
            self.instance = gui.add_dropdown("Program instance", (NONE,), disabled=not self.writes)
            self.instance.on_update(lambda _: self._show_instance())
            self.instance_name = self._text("Instance name", self._instance_key("name"))
            self.instance_pou = self._text("Runs PROGRAM", self._instance_key("pou"))
            self.instance_id = self._text("Program ID", self._instance_key("id"))
            self.program_fields = {
                spec.name: self._parameter(spec, f"Instance: {LABELS[spec.name]}", "program")
                for spec in PROGRAM_PARAMETERS
                if spec.name != "program_id"
            }
            add = gui.add_button("Add instance", disabled=not self.writes)
            remove = gui.add_button("Remove instance", disabled=not self.writes)
            add.on_click(lambda _: self._add_instance())
            remove.on_click(lambda _: self._remove_instance())
        with gui.add_folder("Modbus"):
            self.server_host = self._text("Served on host", _fixed("modbus.host"))
            self.server_port = self._text("Served on port", _fixed("modbus.port"))
            self.device = gui.add_dropdown("Modbus device", (NONE,), disabled=not self.writes)
            self.device.on_update(lambda _: self._show_device())
            self.device_name = self._text("Device name", self._device_key("name"))
            self.device_host = self._text("Device host", self._device_key("host"))
            self.device_port = self._text("Device port", self._device_key("port"))
            self.device_fields = {
                key: self._text(label, self._device_key(key)) for key, label in DEVICE_FIELDS
            }
            self.points = gui.add_html("")
        self._filling = False  # while the forms are filled from the draft: no edit

    # ---- building
    def _text(self, label: str, key: Callable[[], str]) -> Field:
        handle = self.work.gui.add_text(label, "", disabled=not self.writes)
        made = Field(handle, self.work.gui.add_html(""), key)
        handle.on_update(lambda _: self._typed())
        self.fields.append(made)
        return made

    def _parameter(self, spec: ParameterSpec, label: str, owner: str) -> Field:
        gui = self.work.gui
        hint = value_range(spec)
        if spec.kind is bool or spec.choices:
            options = (DEFAULT, "ON", "OFF") if spec.kind is bool else (DEFAULT, *spec.choices)
            handle: Any = gui.add_dropdown(label, options, disabled=not self.writes, hint=hint)
        else:
            handle = gui.add_text(label, "", disabled=not self.writes, hint=hint)
        key = (
            self._instance_key(spec.name) if owner == "program" else _fixed(f"resource.{spec.name}")
        )
        made = Field(handle, gui.add_html(""), key)
        handle.on_update(lambda _: self._typed())
        self.fields.append(made)
        return made

    def _instance_key(self, key: str) -> Callable[[], str]:
        """A field of the instance shown, as the service names it in a problem."""
        return lambda: f"resource.program.{self._index()}.{key}"

    def _device_key(self, key: str) -> Callable[[], str]:
        return lambda: f"modbus.device.{self._device_index()}.{key}"

    # ---- the draft from the forms, the forms from the draft
    def _index(self) -> int:
        return _position(self.instance.value)

    def _device_index(self) -> int:
        return _position(self.device.value)

    def _load(self, project: str | None) -> None:
        self.loaded = None
        self.saved.content = ""
        if project is None:
            self.header.content = _note("settings-header", "Choose a project in the navigation.")
            return
        try:
            read = read_settings(self.work.context.shelf, project, self.editor)
        except Refusal as refused:
            self.header.content = _note("settings-header", refused.message, red=True)
            return
        self.loaded = Loaded(project, read.settings, read.hash)
        level = (
            "" if self.writes else f" Your PADT account is {self.work.level}: you may look only."
        )
        self.header.content = _note("settings-header", f"padt.toml of project {project}.{level}")
        self._fill()
        self._changed()

    def _fill(self) -> None:
        assert self.loaded is not None
        draft = self.loaded.draft
        self._filling = True
        try:
            set_value(self.resource_name.handle, draft.resource)
            for name, made in self.resource_fields.items():
                _show_value(made, draft.parameters.get(name))
            names = tuple(f"{i + 1}: {p.name}" for i, p in enumerate(draft.programs)) or (NONE,)
            self.instance.options = names
            set_value(self.instance, names[0])
            server = draft.modbus or {}
            set_value(self.server_host.handle, str(server.get("host", "")))
            set_value(self.server_port.handle, str(server.get("port", "")))
            devices = tuple(f"{i + 1}: {d.name}" for i, d in enumerate(draft.devices)) or (NONE,)
            self.device.options = devices
            set_value(self.device, devices[0])
        finally:
            self._filling = False
        self._show_instance()
        self._show_device()

    def _show_instance(self) -> None:
        program = self._program()
        self._filling = True
        try:
            set_value(self.instance_name.handle, program.name if program else "")
            set_value(self.instance_pou.handle, program.pou if program else "")
            set_value(self.instance_id.handle, str(program.id) if program else "")
            for name, made in self.program_fields.items():
                _show_value(made, program.parameters.get(name) if program else None)
        finally:
            self._filling = False
        self.shown_version = -1  # the notes of this instance

    def _show_device(self) -> None:
        device = self._device()
        self._filling = True
        try:
            set_value(self.device_name.handle, device.name if device else "")
            set_value(self.device_host.handle, device.host if device else "")
            set_value(self.device_port.handle, str(device.port) if device else "")
            for key, made in self.device_fields.items():
                value = device.settings.get(key) if device else None
                set_value(made.handle, "" if value is None else str(value))
        finally:
            self._filling = False
        self.points.content = _render_points(device)
        self.shown_version = -1

    def _program(self) -> ProgramSettings | None:
        if self.loaded is None:
            return None
        programs = self.loaded.draft.programs
        index = self._index()
        return programs[index] if 0 <= index < len(programs) else None

    def _device(self) -> ModbusDevice | None:
        if self.loaded is None:
            return None
        devices = self.loaded.draft.devices
        index = self._device_index()
        return devices[index] if 0 <= index < len(devices) else None

    def _typed(self) -> None:
        """A field changed: into the draft (what does not read as its type is said beside
        the field at once), then the draft checked."""
        if self._filling or self.loaded is None or not self.writes:
            return
        draft = self.loaded.draft
        draft.resource = self.resource_name.handle.value.strip()
        typing: dict[str, str] = {}
        for name, made in self.resource_fields.items():
            _into(draft.parameters, name, made, typing)
        program = self._program()
        if program is not None:
            program.name = self.instance_name.handle.value.strip()
            program.pou = self.instance_pou.handle.value.strip()
            program.id = _number(self.instance_id.handle.value, "Program ID", typing, program.id)
            for name, made in self.program_fields.items():
                _into(program.parameters, name, made, typing)
        host, port = self.server_host.handle.value.strip(), self.server_port.handle.value
        if host or port.strip() or draft.modbus is not None:
            server = dict(draft.modbus or {})
            server["host"] = host
            server["port"] = _number(port, "Served on port", typing, server.get("port", 0))
            draft.modbus = server
        device = self._device()
        if device is not None:
            device.name = self.device_name.handle.value.strip()
            device.host = self.device_host.handle.value.strip()
            device.port = _number(self.device_port.handle.value, "Device port", typing, device.port)
            for key, made in self.device_fields.items():
                text = made.handle.value.strip()
                if text:
                    device.settings[key] = _number(text, made.handle.label, typing, 0)
                else:
                    device.settings.pop(key, None)
        self.typing = typing
        names = tuple(f"{i + 1}: {p.name}" for i, p in enumerate(draft.programs)) or (NONE,)
        if tuple(self.instance.options) != names:
            self._filling = True
            self.instance.options = names
            set_value(self.instance, names[max(0, min(self._index(), len(names) - 1))])
            self._filling = False
        self._changed()

    def _changed(self) -> None:
        assert self.loaded is not None
        self.version += 1
        version, loaded = self.version, self.loaded
        draft = copy.deepcopy(loaded.draft)
        shelf, editor, checked = self.work.context.shelf, self.editor, self.checked

        def check() -> None:
            try:
                found = settings_problems(shelf, loaded.project, draft, editor)
            except Refusal as refused:
                found = [Problem("", refused.message)]
            with checked.lock:
                if version > checked.version:
                    checked.version, checked.problems = version, found

        self.checker.submit("check", check)

    # ---- the instances
    def _add_instance(self) -> None:
        if self.loaded is None:
            return
        programs = self.loaded.draft.programs
        taken = {p.id for p in programs}
        free = next((i for i in range(1, 33) if i not in taken), 0)
        programs.append(ProgramSettings(f"Program{len(programs) + 1}", "", free))
        self._fill_instances(len(programs) - 1)

    def _remove_instance(self) -> None:
        if self.loaded is None or self._program() is None:
            return
        del self.loaded.draft.programs[self._index()]
        self._fill_instances(0)

    def _fill_instances(self, chosen: int) -> None:
        assert self.loaded is not None
        programs = self.loaded.draft.programs
        names = tuple(f"{i + 1}: {p.name}" for i, p in enumerate(programs)) or (NONE,)
        self._filling = True
        self.instance.options = names
        set_value(self.instance, names[min(chosen, len(names) - 1)])
        self._filling = False
        self._show_instance()
        self._changed()

    # ---- saving
    def _save(self) -> None:
        loaded = self.loaded
        if loaded is None or not self.writes:
            return
        try:
            saved = write_settings(
                self.work.context.shelf, loaded.project, loaded.draft, loaded.base_hash, self.editor
            )
        except Refusal as refused:
            self.saved.content = _note("settings-saved", f"Not saved: {refused.message}", red=True)
            return
        loaded.base_hash = saved.hash
        self.saved.content = _note("settings-saved", f"Saved padt.toml ({saved.hash[:12]}).")

    # ---- drawing
    def refresh(self, now: Now) -> None:
        project = self.work.project()
        if (self.loaded.project if self.loaded else None) != project:
            self._load(project)
        with self.checked.lock:
            version, problems = self.checked.version, list(self.checked.problems)
        if version == self.shown_version:
            return
        self.shown_version = version
        typing = self.typing
        by_field: dict[str, list[str]] = {}
        for problem in problems:
            by_field.setdefault(problem.field, []).append(_worded(problem))
        for made in self.fields:
            said = by_field.get(made.key(), [])
            mistyped = typing.get(made.handle.label)
            content = _notes([mistyped, *said] if mistyped else said)
            if made.note.content != content:
                made.note.content = content
        self.resource_note.content = _notes(by_field.get("resource", []))
        errors = [p for p in problems if p.severity == "error"]
        listed = "".join(
            f'<div style="{_RED if p.severity == "error" else _GREY}">'
            f"{html.escape(p.field or 'padt.toml')}: {html.escape(_worded(p))}</div>"
            for p in problems
        )
        self.problems.content = (
            f'<div data-testid="settings-problems">{listed}</div>' if problems else ""
        )
        current = version == self.version
        self.save.disabled = not (self.writes and current and not errors and not typing)


def _fixed(key: str) -> Callable[[], str]:
    return lambda: key


def _position(option: str) -> int:
    number, _, _ = option.partition(":")
    return int(number) - 1 if number.isdigit() else -1


def _show_value(made: Field, value: Any) -> None:
    if isinstance(made.handle, viser.GuiDropdownHandle):
        text = (
            DEFAULT
            if value is None
            else ("ON" if value else "OFF")
            if isinstance(value, bool)
            else str(value)
        )
        options = tuple(made.handle.options)
        set_value(made.handle, text if text in options else DEFAULT)
    else:
        set_value(made.handle, "" if value is None else str(value))


def _into(values: dict[str, Any], name: str, made: Field, typing: dict[str, str]) -> None:
    """A parameter's field into the draft: empty or (default) is not set (the resource's
    default); what does not read as the parameter's type is said beside the field."""
    text = str(made.handle.value).strip()
    if not text or text == DEFAULT:
        values.pop(name, None)
        return
    spec = next(s for s in (*RESOURCE_PARAMETERS, *PROGRAM_PARAMETERS) if s.name == name)
    try:
        values[name] = parse_value(spec, text)
    except ParameterError as exc:
        typing[made.handle.label] = str(exc)


def _number(text: str, label: str, typing: dict[str, str], before: int) -> int:
    word = text.strip()
    try:
        return int(word, 10)
    except ValueError:
        typing[label] = f"{label} is a whole number, not {word!r}"
        return before


def _worded(problem: Problem) -> str:
    return f"{problem.message} [{problem.code}]" if problem.code else problem.message


def _notes(lines: list[str]) -> str:
    return "".join(f'<div style="{_RED}">{html.escape(line)}</div>' for line in lines)


def _note(testid: str, text: str, red: bool = False) -> str:
    return f'<div data-testid="{testid}" style="{_RED if red else _GREY}">{html.escape(text)}</div>'


def _render_points(device: ModbusDevice | None) -> str:
    if device is None or not device.points:
        return f'<div style="{_GREY}">No points.</div>'
    rows = "".join(
        f"<tr><td>{html.escape(p.variable)}</td><td>{html.escape(p.area)}</td>"
        f"<td>{p.address}</td></tr>"
        for p in device.points
    )
    return (
        f'<table data-testid="modbus-points" style="font-size:0.85em">'
        f"<tr><th>Variable</th><th>Area</th><th>Address</th></tr>{rows}</table>"
    )
