"""The Reload screen: online change of the selected resource to a project the PADT knows,
as SILworX's reload or CODESYS's online change. **Preview** compiles the project twice and
asks the resource for its plan against the live state: every variable's fate, the
programs' changes, the two configuration CRCs. Each risk of the plan is ticked on its own;
the rename map carries values across renames; **Reload** asks once more, naming the
resource and both CRCs, and is sent with the CRC the preview was made against, so that a
resource that changed meanwhile refuses it.

Compiling and transferring take a second or more: they run on a thread of their own,
never on viser's callback thread; the refresher shows their progress and outcome."""

from __future__ import annotations

import html
import re
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import viser
from viser._gui_handles import GuiProgressBarHandle

from backend.engineering.compile_gate import compile_checked
from backend.engineering.project import ProjectError
from backend.engineering.reload import (
    Reloaded,
    ReloadOptions,
    counted,
    preview_reload,
    reload_checked,
    rename_map,
)
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from frontend import screen_registry
from frontend.confirm import attempt, confirm
from frontend.permissions import Allowed
from frontend.screen_registry import Now, Screen
from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal

FATES = ("kept", "converted", "initialised", "new", "deleted")
# the table's filter; "changed" is every fate but kept
SHOW = ("all", "changed", *FATES)
# the order of the table: what is lost or restarts first, what simply stays last
_FATE_ORDER = {"deleted": 0, "initialised": 1, "converted": 2, "new": 3, "kept": 4}
_FATE_COLORS = {
    "kept": "#2b8a3e",
    "converted": "#1971c2",
    "initialised": "#e67700",
    "new": "#7048e8",
    "deleted": "#c92a2a",
}
NO_PROJECT = "(no project)"
_NAME = r"[A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)*"
_RENAME_LINE = re.compile(rf"\s*({_NAME})\s*->\s*({_NAME})\s*")
_DIAGNOSTIC = re.compile(
    r"(?P<where>.+?:\d+:\d+): (?P<severity>\w+): (?P<message>.*) \[(?P<code>\w+)\]"
)
RENAME_SETTLE_S = 0.8  # the rename map is previewed again once the user stops typing
_CELL = "padding:2px 8px;border-bottom:1px solid #e9ecef"
_MUTED = "color:#868e96"
_BOX = "margin:6px 0;padding:4px 8px;border-radius:4px;border:1px solid "  # + its colour


@dataclass(frozen=True)
class Risk:
    """Something the plan would lose or risk, which the user ticks before a reload."""

    label: str  # of its checkbox
    title: str
    detail: str


@dataclass(frozen=True)
class Preview:
    resource: str
    project: str
    renames: dict[str, str]  # NEW -> OLD, as the runtime's rename map has it
    plan: p.ReloadPlanInfo
    risks: tuple[Risk, ...]


@dataclass
class Outcome:
    """What the last reload came to: done, or why not."""

    resource: str
    done: Reloaded | None = None
    refused: str = ""  # "code: message"


@dataclass
class Work:
    """What this screen's thread is doing, if anything; written by that thread, read by the
    refresher (under `lock`)."""

    lock: threading.Lock = field(default_factory=threading.Lock)
    busy: str = ""  # "Preview" / "Reload" while running
    stage: str = ""
    started: float = 0.0
    preview: Preview | None = None
    loaded: bool = False  # the preview's configuration was reloaded: preview again first
    attempted: tuple[str, str, dict[str, str]] | None = None  # resource, project, renames
    preview_error: str = ""  # HTML
    outcome: Outcome | None = None
    version: int = 0


@dataclass(frozen=True)
class ReloadHooks:
    """What the screen needs of its browser session."""

    client: viser.ClientHandle  # for the confirmation and the notifications
    projects: Mapping[str, Path]
    backup_dir: Path
    user: str
    selected: Callable[[], str | None]
    client_of: Callable[[str], ResourceClient]


@dataclass
class Budget:
    """A higher watchdog and target cycle for the switch-over cycle only (empty: as
    configured), as SILworX offers when a reload does not fit the cycle."""

    watchdog: viser.GuiTextHandle
    target_cycle: viser.GuiTextHandle
    note: viser.GuiHtmlHandle


@dataclass
class ReloadScreen:
    hooks: ReloadHooks
    project: viser.GuiDropdownHandle[str]
    renames: viser.GuiTextHandle
    rename_note: viser.GuiHtmlHandle
    preview_button: viser.GuiButtonHandle
    preview_progress: GuiProgressBarHandle
    preview_info: viser.GuiHtmlHandle
    summary: viser.GuiHtmlHandle
    show: viser.GuiDropdownHandle[str]
    table: viser.GuiHtmlHandle
    risk_folder: viser.GuiFolderHandle
    budget: Budget
    reload_button: viser.GuiButtonHandle
    reason: viser.GuiHtmlHandle
    reload_progress: GuiProgressBarHandle
    result: viser.GuiHtmlHandle
    work: Work = field(default_factory=Work)
    checks: list[viser.GuiCheckboxHandle] = field(default_factory=list)
    risk_handles: list[Any] = field(default_factory=list)
    checks_for: Preview | str | None = "none built yet"  # a str: nothing shown yet
    shown: dict[str, str] = field(default_factory=dict)  # handle name -> HTML shown
    rename_text: str = ""
    rename_changed: float = 0.0
    choice: tuple[str | None, str] = (None, "")  # resource and project the screen shows


def build(gui: viser.GuiApi, hooks: ReloadHooks) -> ReloadScreen:
    projects = tuple(sorted(hooks.projects)) or (NO_PROJECT,)
    project = gui.add_dropdown("Project", projects)
    renames = gui.add_text("Renames", "", multiline=True)
    rename_note = gui.add_html("")
    preview_button = gui.add_button("Preview", color="blue", disabled=True)
    preview_progress = gui.add_progress_bar(100, animated=True, visible=False)
    preview_info = gui.add_html("")
    # the reload's progress and result at the top, where the eye is after the dialog
    reload_progress = gui.add_progress_bar(100, animated=True, visible=False)
    result = gui.add_html("")
    summary = gui.add_html("")
    show = gui.add_dropdown("Show", SHOW, initial_value="all")
    table = gui.add_html("")
    risk_folder = gui.add_folder("Confirm each risk")
    with gui.add_folder("Budget of the switch-over", expand_by_default=False):
        hint = "empty: as configured; only higher, for the cycle of the switch-over only"
        budget = Budget(
            gui.add_text("Watchdog for the reload (ms)", "", hint=hint),
            gui.add_text("Target cycle for the reload (ms)", "", hint=hint),
            gui.add_html(""),
        )
    reload_button = gui.add_button("Reload", color="red", disabled=True)
    reason = gui.add_html("")
    screen = ReloadScreen(
        hooks, project, renames, rename_note, preview_button, preview_progress, preview_info,
        summary, show, table, risk_folder, budget, reload_button, reason, reload_progress,
        result,
    )  # fmt: skip
    preview_button.on_click(lambda _: _start_preview(screen))
    reload_button.on_click(lambda _: _ask_reload(screen))
    return screen


# ---- the rename map


def parse_renames(text: str) -> tuple[dict[str, str], list[str]]:
    """`old -> new` lines (blank lines and `#` comments skipped) -> the rename map NEW ->
    OLD, and what is wrong with the lines that are not such a pair."""
    pairs: list[tuple[str, str]] = []
    errors: list[str] = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.strip().startswith("#"):
            continue
        match = _RENAME_LINE.fullmatch(line)
        if match is None:
            errors.append(f"line {number}: '{line.strip()}' is not old -> new")
        elif match.group(1).upper() == match.group(2).upper():
            errors.append(f"line {number}: {match.group(1)} is renamed to itself")
        else:
            pairs.append((match.group(2), match.group(1)))
    try:
        renames = rename_map(pairs)
    except Refusal as refused:
        errors.append(refused.message)
        renames = {}
    return renames, errors


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


def budget_text(watchdog_ms: int | None, target_cycle_ms: int | None) -> str:
    """The raised budget in words for the confirmation ("" when none is raised)."""
    named = (("watchdog", watchdog_ms), ("target cycle", target_cycle_ms))
    raised = [f"{name} {ms} ms" for name, ms in named if ms is not None]
    return f"For the cycle of the switch-over: {' and '.join(raised)}. " if raised else ""


# ---- the work, on a thread of its own


def _start_preview(screen: ReloadScreen, renames: dict[str, str] | None = None) -> None:
    hooks, work = screen.hooks, screen.work
    resource, project = hooks.selected(), screen.project.value
    if resource is None or project not in hooks.projects:
        return
    if renames is None:
        renames, errors = parse_renames(screen.renames.value)
        if errors:
            return
    folder = hooks.projects[project]
    with work.lock:
        if work.busy:
            return
        work.busy, work.stage, work.started = (
            "Preview",
            f"compiling {project} twice",
            time.monotonic(),
        )
        work.attempted = attempt_key = (resource, project, dict(renames))
        work.version += 1

    def run() -> None:
        preview, error = None, ""
        try:
            checked = compile_checked([folder])
            _stage(work, f"asking {resource} for the plan")
            plan = preview_reload(hooks.client_of(resource), checked.artifact, renames)
            preview = Preview(resource, project, dict(renames), plan, tuple(risks(plan)))
        except ProjectError as exc:
            error = _failure("project", str(exc), [])
        except Refusal as refused:
            error = _failure(refused.code, refused.message, refused.details.get("diagnostics", []))
        except ResourceUnreachable as exc:
            error = _failure("unreachable", str(exc), [])
        finally:
            with work.lock:
                work.busy = ""
                # unless the user chose another resource or project meanwhile
                if work.attempted == attempt_key:
                    work.preview, work.loaded, work.preview_error = preview, False, error
                work.version += 1

    threading.Thread(target=run, name="reload-preview", daemon=True).start()


def _stage(work: Work, stage: str) -> None:
    with work.lock:
        work.stage = stage
        work.version += 1


def _ask_reload(screen: ReloadScreen) -> None:
    with screen.work.lock:
        preview = screen.work.preview
    if preview is None:
        return
    plan = preview.plan
    ticked = "; ".join(risk.title for risk in preview.risks)
    watchdog_ms, target_cycle_ms, errors = read_budget(screen.budget)
    if errors:
        return
    confirm(
        screen.hooks.client,
        f"Reload: {preview.resource}",
        f"Reload project {preview.project} into resource {preview.resource} while it runs: "
        f"configuration {plan.old_crc} is replaced by {plan.new_crc}, "
        f"{_counts_text(plan)}. "
        + (f"You confirmed: {ticked}. " if ticked else "")
        + budget_text(watchdog_ms, target_cycle_ms)
        + f"The resource refuses the reload if it no longer runs {plan.old_crc}.",
        lambda: _start_reload(screen, preview, watchdog_ms, target_cycle_ms),
    )


def _start_reload(
    screen: ReloadScreen, preview: Preview, watchdog_ms: int | None, target_cycle_ms: int | None
) -> None:
    hooks, work = screen.hooks, screen.work
    folder = hooks.projects[preview.project]
    resource, plan = preview.resource, preview.plan
    with work.lock:
        if work.busy:
            return
        work.busy, work.stage, work.started = (
            "Reload",
            f"compiling {preview.project} twice",
            time.monotonic(),
        )
        work.outcome = None
        work.version += 1

    def act() -> None:
        outcome = Outcome(resource)
        try:
            checked = compile_checked([folder])
            if checked.artifact.crc != plan.new_crc:
                # what would be loaded is not what the user saw the plan of
                raise Refusal(
                    "project_changed",
                    f"project {preview.project} compiles to {checked.artifact.crc} now, the "
                    f"preview showed {plan.new_crc}: preview again",
                )
            _stage(work, f"transferring to {resource} and switching over")
            options = ReloadOptions(
                dict(preview.renames), plan.old_crc, watchdog_ms, target_cycle_ms
            )
            how = f"browser UI: reload of project {preview.project} by {hooks.user}"
            outcome.done = reload_checked(
                hooks.client_of(resource), checked, options, hooks.backup_dir, how
            )
        except ProjectError as exc:
            outcome.refused = f"project: {exc}"
            raise Refusal("project", str(exc)) from None
        except Refusal as refused:
            # a project that no longer compiles: where, in the compiler's words
            where = "; ".join(refused.details.get("diagnostics", []))
            outcome.refused = f"{refused.code}: {refused.message}" + (
                f" ({where})" if where else ""
            )
            raise
        except ResourceUnreachable as exc:
            outcome.refused = f"no answer: {exc}"
            raise
        finally:
            with work.lock:
                work.busy = ""
                work.outcome = outcome
                work.loaded = work.loaded or outcome.done is not None
                work.version += 1

    # a refusal or no answer is also a notification, like every other command's
    threading.Thread(
        target=lambda: attempt(hooks.client, f"Reload {resource}", act),
        name="reload",
        daemon=True,
    ).start()


# ---- ten times a second


def refresh(
    screen: ReloadScreen,
    resource: str | None,
    status: p.Status | None,
    allowed: Callable[[type[p.Command[Any]]], Allowed],
) -> None:
    work = screen.work
    project = screen.project.value
    if resource is not None and screen.choice != (resource, project):
        # a plan is for one resource and one project: another choice needs its own (a
        # resource gone for a moment changes nothing: its plan is still the plan)
        screen.choice = (resource, project)
        with work.lock:
            work.preview, work.attempted, work.preview_error, work.outcome = None, None, "", None
            work.version += 1
    renames, rename_errors = parse_renames(screen.renames.value)
    _show(screen, "rename_note", screen.rename_note, _rename_note(rename_errors))
    with work.lock:
        busy, stage, started = work.busy, work.stage, work.started
        preview, loaded, attempted = work.preview, work.loaded, work.attempted
        preview_error, outcome = work.preview_error, work.outcome
    _rerun_after_renames(screen, renames, rename_errors, busy, attempted)

    preview_verdict = _preview_verdict(screen, resource, status, allowed, busy, rename_errors)
    screen.preview_button.disabled = not preview_verdict.ok
    screen.preview_button.hint = preview_verdict.reason or None
    what = f"{busy} of {resource}" if busy == "Reload" else f"{busy} of {project}"
    running = f"{what}: {stage} ... {time.monotonic() - started:.1f} s" if busy else ""
    screen.preview_progress.visible = busy == "Preview"
    screen.reload_progress.visible = busy == "Reload"
    info = _note("preview-progress", running) if busy == "Preview" else preview_error
    if not info and not preview_verdict.ok and preview is None:
        info = _note("preview-disabled", f"Preview disabled: {preview_verdict.reason}")
    _show(screen, "preview_info", screen.preview_info, info)

    plan = preview.plan if preview is not None else None
    running_crc = status.crc if status is not None else None
    # after a failed preview its refusal says enough, and whoever may not preview is told
    # why above: no invitation to preview then
    quiet = preview is None and (preview_error or not preview_verdict.ok)
    summary = "" if quiet else render_summary(preview, running_crc, loaded)
    _show(screen, "summary", screen.summary, summary)
    _show(screen, "table", screen.table, render_table(plan, screen.show.value))
    if preview is not screen.checks_for:
        _rebuild_risks(screen, preview)
    budget_errors = read_budget(screen.budget)[2]
    _show(screen, "budget", screen.budget.note, _budget_note(budget_errors))
    verdict = _reload_verdict(screen, preview, loaded, renames, rename_errors, busy, allowed)
    if verdict.ok and budget_errors:
        verdict = Allowed(False, "the budget of the switch-over: " + "; ".join(budget_errors))
    screen.reload_button.disabled = not verdict.ok
    screen.reload_button.hint = verdict.reason or None
    # under the button too, in one line: the panel is scrolled down to it by then
    below = _note("reload-under-way", running) if busy == "Reload" else outcome_line(outcome)
    _show(
        screen,
        "reason",
        screen.reason,
        below + _note("reload-disabled", _disabled(verdict)),
    )
    result = _note("reload-progress", running) if busy == "Reload" else render_outcome(outcome)
    _show(screen, "result", screen.result, result)


def _rerun_after_renames(
    screen: ReloadScreen,
    renames: dict[str, str],
    errors: list[str],
    busy: str,
    attempted: tuple[str, str, dict[str, str]] | None,
) -> None:
    """An edited rename map previews again by itself, once it is valid and the user has
    stopped typing: the plan on screen is always the plan of the map on screen."""
    text = screen.renames.value
    if text != screen.rename_text:
        screen.rename_text, screen.rename_changed = text, time.monotonic()
        return
    settled = time.monotonic() - screen.rename_changed >= RENAME_SETTLE_S
    if attempted is None or busy or errors or not settled or attempted[2] == renames:
        return
    _start_preview(screen, renames)


def _preview_verdict(
    screen: ReloadScreen,
    resource: str | None,
    status: p.Status | None,
    allowed: Callable[[type[p.Command[Any]]], Allowed],
    busy: str,
    rename_errors: list[str],
) -> Allowed:
    if not screen.hooks.projects:
        return Allowed(False, "the PADT knows no project (padt ui --project NAME=DIR)")
    if resource is None or status is None:
        return Allowed(False, "select a resource you are logged in to")
    verdict = allowed(p.ReloadPreview)
    if not verdict.ok:
        return verdict
    if busy:
        return Allowed(False, f"the {busy.lower()} is under way")
    if rename_errors:
        return Allowed(False, "correct the rename map first")
    return Allowed(True)


def _reload_verdict(
    screen: ReloadScreen,
    preview: Preview | None,
    loaded: bool,
    renames: dict[str, str],
    rename_errors: list[str],
    busy: str,
    allowed: Callable[[type[p.Command[Any]]], Allowed],
) -> Allowed:
    verdict = allowed(p.Reload)
    if not verdict.ok:
        return verdict
    if busy:
        return Allowed(False, f"the {busy.lower()} is under way")
    if preview is None:
        return Allowed(False, "preview the reload first")
    if loaded:
        return Allowed(False, "this preview has been reloaded; preview again for another reload")
    if not preview.plan.possible:
        return Allowed(False, "this change needs STOP and a download (see the plan)")
    if rename_errors or renames != preview.renames:
        return Allowed(False, "the rename map changed: its preview comes once the map is valid")
    open_risks = sum(not check.value for check in screen.checks)
    if open_risks:
        return Allowed(
            False, f"tick each risk above ({open_risks} of {len(screen.checks)} not ticked)"
        )
    return Allowed(True)


def _rebuild_risks(screen: ReloadScreen, preview: Preview | None) -> None:
    """A checkbox per risk of a new plan (never ticked beforehand)."""
    for handle in screen.risk_handles:
        handle.remove()
    screen.risk_handles, screen.checks = [], []
    screen.checks_for = preview
    risks_now = preview.risks if preview is not None else ()
    with screen.risk_folder:
        if not risks_now:
            text = "Nothing to confirm: every value is kept, converted or new."
            if preview is None:
                text = "The risks of a plan show here once it is previewed."
            screen.risk_handles.append(screen.hooks.client.gui.add_html(_note("risks", text)))
        for risk in risks_now:
            screen.risk_handles.append(
                screen.hooks.client.gui.add_html(
                    '<div data-testid="risk" style="margin:4px 0 0 0">'
                    f'<b style="color:#c92a2a">{html.escape(risk.title)}</b><br>'
                    f'<span style="font-size:0.9em">{html.escape(risk.detail)}</span></div>'
                )
            )
            check = screen.hooks.client.gui.add_checkbox(risk.label, False)
            screen.checks.append(check)
            screen.risk_handles.append(check)


def _show(screen: ReloadScreen, name: str, handle: viser.GuiHtmlHandle, content: str) -> None:
    """Send HTML only when it changed: ten refreshes a second must cost the browser nothing."""
    if screen.shown.get(name) != content:
        handle.content = content
        screen.shown[name] = content


# ---- what the user reads (pure: plans and outcomes to HTML)


def risks(plan: p.ReloadPlanInfo) -> list[Risk]:
    """What `needs_confirmation` counts, one by one: values that start from their initial
    value, values that are lost, and each hazard the plan names."""
    found: list[Risk] = []
    for action, what in (
        ("initialised", "start from their initial value"),
        ("deleted", "are lost"),
    ):
        names = [change.path for change in plan.changes if change.action == action]
        if names:
            title = counted(len(names), "value") + f" {action}"
            found.append(Risk(f"Accept: {title}", title, f"These {what}: {', '.join(names)}"))
    for number, hazard in enumerate(plan.hazards, start=1):
        found.append(
            Risk(
                f"Accept hazard {number}: {hazard.kind}",
                f"Hazard {number}: {hazard.kind} in {hazard.instance}",
                hazard.message,
            )
        )
    return found


def _counts_text(plan: p.ReloadPlanInfo) -> str:
    return ", ".join(f"{plan.summary.get(fate, 0)} {fate}" for fate in FATES)


def render_summary(preview: Preview | None, running_crc: str | None, loaded: bool) -> str:
    if preview is None:
        return (
            f'<p style="{_MUTED}">Pick a project and press Preview: the plan shows what the '
            "reload would do to every value before anything changes.</p>"
        )
    plan = preview.plan
    rows = [
        ("Resource", html.escape(preview.resource)),
        ("Project", html.escape(preview.project)),
        (
            "Configuration",
            f'running <code data-testid="crc-running">{html.escape(plan.old_crc)}</code> '
            f'&rarr; new <code data-testid="crc-new">{html.escape(plan.new_crc)}</code>',
        ),
        ("Programs", f'<span data-testid="reload-programs">{_programs(plan.programs)}</span>'),
        ("Switch-over", f"estimated {plan.estimate_us:.0f} &micro;s between two cycles"),
    ]
    if preview.renames:
        pairs = ", ".join(f"{old} &rarr; {new}" for new, old in sorted(preview.renames.items()))
        rows.append(("Renames", pairs))
    cells = "".join(
        f'<tr><td style="{_MUTED};padding:1px 12px 1px 0;vertical-align:top">{name}</td>'
        f"<td>{value}</td></tr>"
        for name, value in rows
    )
    counts = " ".join(
        f'<span data-count="{fate}" style="display:inline-block;margin:2px 4px 2px 0;'
        f"padding:1px 8px;border-radius:10px;border:1px solid {_FATE_COLORS[fate]};"
        f'color:{_FATE_COLORS[fate]}"><b>{plan.summary.get(fate, 0)}</b> {fate}</span>'
        for fate in FATES
    )
    notes = []
    if not plan.possible:
        reasons = "; ".join(html.escape(x) for x in plan.refusals)
        notes.append(
            f'<div data-testid="reload-impossible" style="color:#c92a2a">Not possible by '
            f"reload, needs STOP and a download: {reasons}</div>"
        )
    if loaded:
        notes.append(
            f'<div style="{_MUTED}">Reloaded. The resource runs {html.escape(plan.new_crc)} '
            "now; preview again for another reload.</div>"
        )
    elif running_crc is not None and running_crc != plan.old_crc:
        notes.append(
            '<div data-testid="crc-moved" style="color:#e67700">The resource runs '
            f"{html.escape(running_crc)} now, not {html.escape(plan.old_crc)} as at the "
            "preview: it will refuse this reload. Preview again.</div>"
        )
    return (
        '<div style="margin:6px 0 2px 0;font-weight:600">Reload plan</div>'
        f'<table style="font-size:0.9em">{cells}</table>'
        f'<div style="margin:4px 0">{counts}</div>{"".join(notes)}'
    )


def _programs(changes: p.ProgramChanges) -> str:
    parts = [
        f"{what} {', '.join(html.escape(name) for name in names)}"
        for what, names in (
            ("added", changes.added),
            ("removed", changes.removed),
            ("changed", changes.changed),
        )
        if names
    ]
    return "; ".join(parts) or "unchanged"


def render_table(plan: p.ReloadPlanInfo | None, show: str) -> str:
    if plan is None:
        return ""
    chosen = [
        change
        for change in plan.changes
        if show == "all" or change.action == show or (show == "changed" and change.action != "kept")
    ]
    # what is lost or restarts first, then what comes from a renamed variable, kept last
    chosen.sort(
        key=lambda change: (_FATE_ORDER.get(change.action, 9), not _renamed(change), change.path)
    )
    head = "".join(
        f'<th style="{_CELL};text-align:left;position:sticky;top:0;background:#fff">{name}</th>'
        for name in ("Variable", "Fate", "Type", "Value after the reload")
    )
    rows = [_change_row(change) for change in chosen]
    if not rows:
        rows = [f'<tr><td style="{_CELL};{_MUTED}" colspan="4">No variable is {show}.</td></tr>']
    return (
        '<div style="max-height:340px;overflow:auto;border:1px solid #e9ecef">'
        '<table data-testid="reload-plan" style="font-size:0.85em;border-collapse:collapse;'
        f'width:100%"><tr>{head}</tr>{"".join(rows)}</table></div>'
    )


def _change_row(change: p.VariableChange) -> str:
    if change.action in ("converted", "initialised"):
        type_text = f"{change.old_type} → {change.new_type}"
    else:
        type_text = change.new_type or change.old_type or ""
    path = html.escape(change.path)
    color = _FATE_COLORS.get(change.action, "inherit")
    return (
        f'<tr><td style="{_CELL};font-family:monospace">{path}</td>'
        f'<td style="{_CELL};color:{color};font-weight:600" data-fate="{path}">'
        f"{html.escape(change.action)}</td>"
        f'<td style="{_CELL};{_MUTED}">{html.escape(type_text)}</td>'
        f'<td style="{_CELL}">{html.escape(value_after(change))}</td></tr>'
    )


def _renamed(change: p.VariableChange) -> bool:
    return change.source is not None and change.source.upper() != change.path.upper()


def value_after(change: p.VariableChange) -> str:
    """Where the variable's value comes from after the reload, in words."""
    renamed = _renamed(change)
    running = f"the value of {change.source}" if renamed else "its running value"
    said = {
        "kept": running,
        "converted": f"{running}, converted",
        "initialised": "its initial value",
        "new": "its initial value",
        "deleted": "none: the value is lost",
    }.get(change.action, "")
    own_words = change.reason and not change.reason.startswith("renamed from")
    return f"{said} ({change.reason})" if own_words else said


def _failure(code: str, message: str, diagnostics: list[str]) -> str:
    """A preview that did not come: the refusal, and each compile diagnostic as
    `file:line:col code message`."""
    rows = []
    for line in diagnostics:
        match = _DIAGNOSTIC.fullmatch(line)
        if match is None:
            cells = f'<td colspan="3" style="{_CELL}">{html.escape(line)}</td>'
        else:
            color = "#c92a2a" if match["severity"] == "error" else "#e67700"
            cells = (
                f'<td style="{_CELL};font-family:monospace">{html.escape(match["where"])}</td>'
                f'<td style="{_CELL};color:{color};font-family:monospace">'
                f"{html.escape(match['code'])}</td>"
                f'<td style="{_CELL}">{html.escape(match["message"])}</td>'
            )
        rows.append(f'<tr data-testid="diagnostic">{cells}</tr>')
    table = f'<table style="font-size:0.85em;border-collapse:collapse">{"".join(rows)}</table>'
    return (
        '<div data-testid="preview-error" style="color:#c92a2a;margin:4px 0">'
        f"No preview ({html.escape(code)}): {html.escape(message)}</div>" + (table if rows else "")
    )


def render_outcome(outcome: Outcome | None) -> str:
    if outcome is None:
        return ""
    if outcome.done is None:
        return (
            f'<div data-testid="reload-refused" style="{_BOX}#c92a2a;color:#c92a2a">Reload of '
            f"{html.escape(outcome.resource)} refused: {html.escape(outcome.refused)}. The "
            "resource runs on with its configuration.</div>"
        )
    done = outcome.done.reply.reload
    backup = outcome.done.backup
    kept = (
        f'<code data-testid="reload-backup">{html.escape(str(backup.path))}</code>'
        if backup.path is not None
        else f'<span style="color:#c92a2a">none: {html.escape(backup.error or "")}</span>'
    )
    rows = [
        (
            "Resource",
            f"{html.escape(outcome.resource)}: {html.escape(outcome.done.reply.status.state)}",
        ),
        (
            "Configuration",
            f"{html.escape(done.old_crc)} &rarr; "
            f'<code data-testid="reload-new-crc">{html.escape(done.new_crc)}</code>',
        ),
        (
            "Pause",
            f'<span data-testid="reload-pause">{done.pause_us / 1000:.3f} ms</span> '
            f'<span style="{_MUTED}">(the cycles stood still for the switch-over)</span>',
        ),
        ("Carried over", counted(done.carried, "value")),
        ("Backup", kept),
    ]
    cells = "".join(
        f'<tr><td style="{_MUTED};padding:1px 12px 1px 0;vertical-align:top">{name}</td>'
        f'<td style="word-break:break-all">{value}</td></tr>'
        for name, value in rows
    )
    return (
        f'<div data-testid="reload-result" style="{_BOX}#2b8a3e"><b style="color:#2b8a3e">'
        f'Reload done</b><table style="font-size:0.9em">{cells}</table></div>'
    )


def outcome_line(outcome: Outcome | None) -> str:
    """The last reload in one line, for under the Reload button (the details are above)."""
    if outcome is None:
        return ""
    if outcome.done is None:
        return (
            '<div data-testid="reload-outcome" style="color:#c92a2a">Reload refused: '
            f"{html.escape(outcome.refused)}</div>"
        )
    done = outcome.done.reply.reload
    return (
        '<div data-testid="reload-outcome" style="color:#2b8a3e">Reload done: '
        f"{html.escape(done.old_crc)} &rarr; {html.escape(done.new_crc)}, pause "
        f"{done.pause_us / 1000:.3f} ms (details at the top)</div>"
    )


def _rename_note(errors: list[str]) -> str:
    if not errors:
        return (
            f'<div style="{_MUTED};font-size:0.85em">One rename a line, full paths, e.g. '
            "<code>TankControl.level -&gt; TankControl.measuredLevel</code>: the new name keeps "
            "the old one's value.</div>"
        )
    lines = "".join(f"<div>{html.escape(error)}</div>" for error in errors)
    return f'<div data-testid="rename-errors" style="color:#c92a2a;font-size:0.9em">{lines}</div>'


def _budget_note(errors: list[str]) -> str:
    if not errors:
        return (
            f'<div style="{_MUTED};font-size:0.85em">When the plan\'s switch-over does not fit '
            "what the cycle leaves, the resource refuses the reload (budget): raise the watchdog "
            "and, with a fixed or dynamic target cycle, the target cycle for that one cycle.</div>"
        )
    lines = "".join(f"<div>{html.escape(error)}</div>" for error in errors)
    return f'<div data-testid="budget-errors" style="color:#c92a2a;font-size:0.9em">{lines}</div>'


def _disabled(verdict: Allowed) -> str:
    return f"Disabled: {verdict.reason}" if not verdict.ok else ""


def _note(testid: str, text: str) -> str:
    if not text:
        return ""
    return f'<div data-testid="{testid}" style="{_MUTED}">{html.escape(text)}</div>'


class Reload(Screen):
    name = "Reload"
    icon = viser.Icon.REFRESH

    def __init__(self, work: screen_registry.Work) -> None:
        super().__init__(work)
        context = work.context
        hooks = ReloadHooks(
            work.client,
            context.projects,
            context.backup_dir,
            work.user,
            work.selected,
            work.client_of,
        )
        self.screen = build(work.gui, hooks)

    def refresh(self, now: Now) -> None:
        refresh(self.screen, now.resource, now.status, self.work.allowed)
