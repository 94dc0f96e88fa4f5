"""The Online change screen: a project the PADT knows into the selected resource. Compile
(twice, with CRCs), Download (a resource in STOP) and Online change (a running one) open
the dialogs of `frontend/dialogs/`, the same the editor's toolbar opens; here the user
also writes the rename map (one `OLD=NEW` a line, as `padt reload --rename`) and may
raise the budget of the switch-over cycle. The screen decides nothing itself: the rename
syntax is the service's, the controls are enabled as the resource would allow."""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import viser

from backend.engineering.reload import parse_renames
from frontend import screen_registry
from frontend.dialogs.deployment import MUTED, RED, Deployment, deployment_of, start_compile
from frontend.dialogs.download import ask_download
from frontend.dialogs.online_change import ask_online_change
from frontend.permissions import Allowed
from frontend.screen_registry import Now, Screen
from runtime.contract import protocol as p

NO_PROJECT = "(no project)"


@dataclass
class Budget:
    """A higher watchdog and target cycle for the switch-over cycle only (empty: as
    configured), as SILworX offers when a reload does not fit the cycle."""

    watchdog: viser.GuiTextHandle
    target_cycle: viser.GuiTextHandle
    note: viser.GuiHtmlHandle


@dataclass
class OnlineChangeScreen:
    deployment: Deployment
    project: viser.GuiDropdownHandle[str]
    renames: viser.GuiTextHandle
    rename_note: viser.GuiHtmlHandle
    budget: Budget
    compile_button: viser.GuiButtonHandle
    download_button: viser.GuiButtonHandle
    change_button: viser.GuiButtonHandle
    reason: viser.GuiHtmlHandle
    shown: dict[str, str] = field(default_factory=dict)  # handle name -> HTML shown


def build(gui: viser.GuiApi, deployment: Deployment) -> OnlineChangeScreen:
    projects = tuple(sorted(deployment.projects)) or (NO_PROJECT,)
    project = gui.add_dropdown("Project", projects)
    compile_button = gui.add_button("Compile", color="blue", icon=viser.Icon.CHECKS)
    download_button = gui.add_button("Download", color="orange", icon=viser.Icon.DOWNLOAD)
    change_button = gui.add_button("Online change", color="red", icon=viser.Icon.REFRESH)
    reason = gui.add_html("")
    renames = gui.add_text(
        "Renames",
        "",
        multiline=True,
        hint="one OLD=NEW a line, full paths (TankControl.level=TankControl.measured): "
        "NEW keeps the value of OLD",
    )
    rename_note = gui.add_html("")
    with gui.add_folder("Budget of the switch-over", expand_by_default=False):
        hint = "empty: as configured; only higher, for the cycle of the switch-over only"
        budget = Budget(
            gui.add_text("Watchdog for the reload (ms)", "", hint=hint),
            gui.add_text("Target cycle for the reload (ms)", "", hint=hint),
            gui.add_html(""),
        )
    screen = OnlineChangeScreen(
        deployment, project, renames, rename_note, budget, compile_button, download_button,
        change_button, reason,
    )  # fmt: skip
    compile_button.on_click(lambda _: start_compile(deployment, project.value))
    download_button.on_click(lambda _: ask_download(deployment, project.value))
    change_button.on_click(lambda _: _ask_online_change(screen))
    return screen


def _ask_online_change(screen: OnlineChangeScreen) -> None:
    renames, errors = parse_renames(screen.renames.value)
    watchdog_ms, target_cycle_ms, budget_errors = read_budget(screen.budget)
    if errors or budget_errors:
        return  # the button is disabled then; a click raced the refresh
    ask_online_change(
        screen.deployment, screen.project.value, renames, (watchdog_ms, target_cycle_ms)
    )


def parse_milliseconds(text: str) -> tuple[int | None, str]:
    """A budget field: None when empty, or whole milliseconds; what is wrong otherwise."""
    text = text.strip()
    if not text:
        return None, ""
    if not text.isdigit() or not 1 <= int(text) <= p.MAX_MS:
        return None, f"'{text[:20]}' is no number of milliseconds from 1 to {p.MAX_MS}"
    return int(text), ""


def read_budget(budget: Budget) -> tuple[int | None, int | None, list[str]]:
    """The watchdog and target cycle for the reload, and what is wrong with the fields."""
    watchdog, watchdog_error = parse_milliseconds(budget.watchdog.value)
    target, target_error = parse_milliseconds(budget.target_cycle.value)
    named = (("watchdog", watchdog_error), ("target cycle", target_error))
    return watchdog, target, [f"{name}: {error}" for name, error in named if error]


# ---- ten times a second, while in view


def refresh(
    screen: OnlineChangeScreen,
    resource: str | None,
    status: p.Status | None,
    allowed: Callable[[type[p.Command[Any]]], Allowed],
) -> None:
    projects = tuple(sorted(screen.deployment.projects)) or (NO_PROJECT,)
    if tuple(screen.project.options) != projects:  # a project made since, in the tree
        screen.project.options = projects
    rename_errors = parse_renames(screen.renames.value)[1]
    budget_errors = read_budget(screen.budget)[2]
    _show(screen, "rename_note", screen.rename_note, _errors("rename-errors", rename_errors))
    _show(screen, "budget", screen.budget.note, _errors("budget-errors", budget_errors))
    has_project = screen.project.value in screen.deployment.projects
    compiling = Allowed(True) if has_project else Allowed(False, "the PADT knows no project")
    # in RUN too: the dialog says why a download needs STOP, as from the editor
    download = _verdict(has_project, resource, status, allowed(p.Load))
    change = _verdict(has_project, resource, status, allowed(p.Reload))
    if change.ok and (rename_errors or budget_errors):
        change = Allowed(False, "correct the renames or the budget first")
    lines = []
    for button, verdict in (
        (screen.compile_button, compiling),
        (screen.download_button, download),
        (screen.change_button, change),
    ):
        button.disabled = not verdict.ok
        button.hint = verdict.reason or None
        if not verdict.ok:
            lines.append(f"{button.label}: {verdict.reason}")
    text = "".join(f"<div>{html.escape(line)}</div>" for line in lines)
    content = f'<div data-testid="deploy-disabled" style="{MUTED}">{text}</div>' if text else ""
    _show(screen, "reason", screen.reason, content)


def _verdict(
    has_project: bool, resource: str | None, status: p.Status | None, allowed: Allowed
) -> Allowed:
    if not has_project:
        return Allowed(False, "the PADT knows no project")
    if resource is None or status is None:
        return Allowed(False, "select a resource online")
    return allowed


def _errors(testid: str, errors: list[str]) -> str:
    if not errors:
        return ""
    lines = "".join(f"<div>{html.escape(error)}</div>" for error in errors)
    return f'<div data-testid="{testid}" style="color:{RED};font-size:0.9em">{lines}</div>'


def _show(screen: OnlineChangeScreen, name: str, handle: viser.GuiHtmlHandle, content: str) -> None:
    """Send HTML only when it changed: ten refreshes a second must cost the browser nothing."""
    if screen.shown.get(name) != content:
        handle.content = content
        screen.shown[name] = content


class Reload(Screen):
    name = "Online change"
    icon = viser.Icon.REFRESH

    def __init__(self, work: screen_registry.Work) -> None:
        super().__init__(work)
        self.screen = build(work.gui, deployment_of(work))

    def refresh(self, now: Now) -> None:
        refresh(self.screen, now.resource, now.status, self.work.allowed)
