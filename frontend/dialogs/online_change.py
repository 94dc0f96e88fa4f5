"""The Online change dialog (spec section 9, SILworX's reload, CODESYS's online change): the
project compiled twice, the resource's plan against its live state and what the PADT adds
to it (`backend/engineering/online_change.py`): the source diff since the running
configuration, every value's fate, the online parameter values the reload resets (each
may be kept), and why a change cannot be made online. Each risk is ticked on its own;
**Online change** sends the configuration shown with the CRC the plan was made against,
so that a resource that changed meanwhile refuses it; the outcome shows in the dialog.

The browser decides nothing here: the risks, the resets, the reasons and the rename
syntax are the services'; this module only draws them and reads the user's ticks."""

from __future__ import annotations

import html
from collections.abc import Mapping
from pathlib import Path

import viser

from backend.engineering.compile_gate import compile_checked
from backend.engineering.online_change import (
    FileDiff,
    OnlineChanged,
    OnlineChangePreview,
    ParameterReset,
    online_change,
    parameter_words,
    preview_online_change,
)
from backend.engineering.reload import ReloadOptions, counted
from frontend.dialogs.deployment import (
    GREEN,
    KNOWN_FAILURES,
    MUTED,
    RED,
    WIDE_MODAL,
    Deployment,
    failure_html,
    failure_of,
    in_background,
    note_html,
)
from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal

FATES = ("kept", "converted", "initialised", "new", "deleted")
# what is lost or restarts first, what comes from a renamed variable next, kept last
_FATE_ORDER = {"lost": 0, "initialised": 1, "renamed": 2, "converted": 3, "new": 4, "kept": 5}
FATE_COLORS = {
    "kept": GREEN,
    "converted": "#1971c2",
    "renamed": "#0c8599",
    "initialised": "#e67700",
    "new": "#7048e8",
    "deleted": RED,
    "lost": RED,
}
_CELL = "padding:2px 8px;border-bottom:1px solid #e9ecef"
KEEP, ACCEPT = "Keep", "Accept"  # the checkboxes' labels, short: the words are above them
# each of the diff and the table at most a fifth of the window: the confirmation stays near
_SCROLL = "max-height:22vh;overflow:auto;border:1px solid #e9ecef;margin:2px 0 8px 0"
_HEADING = "margin:10px 0 2px 0;font-weight:600"


def ask_online_change(
    deployment: Deployment,
    project: str,
    renames: Mapping[str, str] | None = None,
    budget: tuple[int | None, int | None] = (None, None),
) -> None:
    """Open the Online change dialog for `project` and the resource selected in the
    workspace; `renames` NEW -> OLD (from `parse_renames`), `budget` the watchdog and
    target cycle for the switch-over cycle only (None: as configured)."""
    client, resource = deployment.client, deployment.selected()
    folder = deployment.projects.get(project)
    verdict = deployment.allowed(p.ReloadPreview)
    if resource is None or folder is None or not verdict.ok:
        why = (
            "select a resource online first"
            if resource is None
            else f"no project {project}"
            if folder is None
            else verdict.reason
        )
        client.add_notification("Online change", why, color="red", auto_close_seconds=6)
        return
    renames = dict(renames or {})
    gui = client.gui
    with gui.add_modal(f"Online change: {project} into {resource}") as modal:
        body = gui.add_html(
            WIDE_MODAL
            + note_html("online-change-progress", f"Compiling {project} twice, then the plan ...")
        )
        progress = gui.add_progress_bar(100, animated=True)
        choices = gui.add_folder("Confirm", visible=False)
        change = gui.add_button("Online change", color="red", visible=False, disabled=True)
        reason = gui.add_html("")
        outcome = gui.add_html("")
        close = gui.add_button("Cancel", color="gray")
    close.on_click(lambda _: modal.close())
    keeps: dict[str, viser.GuiCheckboxHandle] = {}
    risk_checks: list[viser.GuiCheckboxHandle] = []
    shown: dict[str, object] = {}

    def verdict_now() -> None:
        open_risks = sum(not check.value for check in risk_checks)
        change.disabled = open_risks > 0
        reason.content = (
            note_html(
                "online-change-disabled",
                f"Tick each risk above ({open_risks} of {len(risk_checks)} not ticked).",
            )
            if open_risks
            else ""
        )

    def prepare() -> None:
        try:
            checked = compile_checked([folder])
            preview = preview_online_change(
                deployment.client_of(resource),
                checked,
                project,
                renames,
                deployment.backup_dir,
                deployment.projects,
            )
        except KNOWN_FAILURES as error:
            body.content = WIDE_MODAL + failure_html(failure_of(error), "Online change")
            progress.visible = False
            close.label = "Close"
            return
        shown["preview"], shown["checked"] = preview, checked
        body.content = WIDE_MODAL + preview_html(preview)
        progress.visible = False
        if not preview.possible:
            close.label = "Close"
            return
        with choices:
            # the words in a row of their own: a checkbox's label column is narrow
            for reset in preview.resets:
                gui.add_html(keep_html(reset))
                box = gui.add_checkbox(KEEP, False, disabled=bool(reset.keepable))
                keeps[reset.name] = box
            for risk in preview.risks:
                gui.add_html(
                    f'<div data-testid="risk" style="margin:4px 0 0 0"><b style="color:{RED}">'
                    f'{html.escape(risk.title)}</b><br><span style="font-size:0.9em">'
                    f"{html.escape(risk.detail)}</span></div>"
                )
                check = gui.add_checkbox(ACCEPT, False, hint=risk.label)
                check.on_update(lambda _: verdict_now())
                risk_checks.append(check)
            if not preview.risks:
                gui.add_html(
                    note_html("risks", "Nothing to accept: every value is kept, converted or new.")
                )
        choices.visible = True
        change.visible = True
        verdict_now()

    def send() -> None:
        preview = shown.get("preview")
        if not isinstance(preview, OnlineChangePreview) or change.disabled:
            return
        change.disabled = True
        progress.visible = True
        outcome.content = note_html(
            "online-change-under-way", f"Compiling {project} again, then switching over ..."
        )
        keep = [reset for reset in preview.resets if keeps[reset.name].value]

        def act() -> None:
            try:
                done = _change(deployment, folder, project, preview, keep, budget)
            except KNOWN_FAILURES as error:
                outcome.content = failure_html(failure_of(error), "Online change")
            else:
                outcome.content = outcome_html(resource, done)
            progress.visible, change.visible = False, False
            choices.visible = False
            close.label = "Close"

        in_background("padt-online-change", act)

    change.on_click(lambda _: send())
    in_background("padt-online-change-plan", prepare)


def _change(
    deployment: Deployment,
    folder: Path,
    project: str,
    preview: OnlineChangePreview,
    keep: list[ParameterReset],
    budget: tuple[int | None, int | None],
) -> OnlineChanged:
    """The online change of what the user saw: the project compiled again must give the
    previewed CRC, and the resource must still run the one the plan was made against."""
    checked = compile_checked([folder])
    if checked.artifact.crc != preview.plan.new_crc:
        raise Refusal(
            "project_changed",
            f"project {project} compiles to {checked.artifact.crc} now, the plan showed "
            f"{preview.plan.new_crc}: open Online change again",
        )
    options = ReloadOptions(dict(preview.renames), preview.plan.old_crc, *budget)
    how = f"browser UI: online change of project {project} by {deployment.user}"
    client = deployment.client_of(preview.resource)
    return online_change(client, checked, options, keep, deployment.backup_dir, how)


# ---- what the user reads (pure: previews and outcomes to HTML)


def fate(change: p.VariableChange) -> str:
    """A value's fate as the engineer asks it: kept, converted, renamed (its value comes
    from another name), initialised, new, or lost."""
    if change.action == "deleted":
        return "lost"
    renamed = change.source is not None and change.source.upper() != change.path.upper()
    return "renamed" if renamed and change.action in ("kept", "converted") else change.action


def value_after(change: p.VariableChange) -> str:
    """Where the variable's value comes from after the online change, in words."""
    renamed = change.source is not None and change.source.upper() != change.path.upper()
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


def preview_html(preview: OnlineChangePreview) -> str:
    return (
        summary_html(preview)
        + why_not_html(preview)
        + resets_html(preview.resets)
        + diff_html(preview)
        + values_html(preview.plan)
    )


def summary_html(preview: OnlineChangePreview) -> str:
    plan = preview.plan
    first, second = preview.check_crcs
    rows = [
        ("Resource", f'<b data-testid="change-resource">{html.escape(preview.resource)}</b>'),
        ("Project", html.escape(preview.project)),
        (
            "Configuration",
            f'running <code data-testid="crc-running">{html.escape(plan.old_crc)}</code> '
            f'&rarr; new <code data-testid="crc-new">{html.escape(plan.new_crc)}</code>',
        ),
        ("Compiled twice", f"{html.escape(first)} and {html.escape(second)}"),
        ("Programs", f'<span data-testid="reload-programs">{_programs(plan.programs)}</span>'),
        ("Switch-over", f"estimated {plan.estimate_us:.0f} &micro;s between two cycles"),
    ]
    if preview.renames:
        pairs = ", ".join(
            f"{html.escape(old)}={html.escape(new)}" for new, old in sorted(preview.renames.items())
        )
        rows.append(("Renames", pairs))
    cells = "".join(
        f'<tr><td style="{MUTED};padding:1px 12px 1px 0;vertical-align:top">{name}</td>'
        f"<td>{value}</td></tr>"
        for name, value in rows
    )
    counts = " ".join(
        f'<span data-count="{name}" style="display:inline-block;margin:2px 4px 2px 0;'
        f"padding:1px 8px;border-radius:10px;border:1px solid {FATE_COLORS[name]};"
        f'color:{FATE_COLORS[name]}"><b>{plan.summary.get(name, 0)}</b> {name}</span>'
        for name in FATES
    )
    return f'<table style="font-size:0.9em">{cells}</table><div style="margin:4px 0">{counts}</div>'


def why_not_html(preview: OnlineChangePreview) -> str:
    if preview.possible:
        return ""
    reasons = "".join(f"<li>{html.escape(why)}</li>" for why in preview.why_not)
    return (
        f'<div data-testid="why-not-online" style="color:{RED};margin:6px 0">'
        "<b>Not possible online: this change needs STOP and a download.</b>"
        f'<ul style="margin:2px 0">{reasons}</ul></div>'
    )


def resets_html(resets: tuple[ParameterReset, ...]) -> str:
    if not resets:
        return ""
    rows = "".join(
        f'<li data-testid="parameter-reset">{html.escape(parameter_words(reset))}'
        f"{_why_not_kept(reset)}</li>"
        for reset in resets
    )
    return (
        f'<div style="{_HEADING};color:#e67700">Online parameter values the change resets</div>'
        f'<ul style="margin:2px 0;font-size:0.9em">{rows}</ul>'
        f'<div style="{MUTED};font-size:0.85em">Tick "Keep" below to set the online value '
        "again right after the switch-over.</div>"
    )


def keep_html(reset: ParameterReset) -> str:
    """The line above a reset's "Keep" checkbox: what ticking it keeps, or why it cannot."""
    words = (
        f"Keep {html.escape(reset.name)} at its online value "
        f"<b>{html.escape(_value(reset.online))}</b> after the switch-over"
    )
    return f'<div data-testid="keep" style="margin:4px 0 0 0">{words}{_why_not_kept(reset)}</div>'


def _why_not_kept(reset: ParameterReset) -> str:
    if not reset.keepable:
        return ""
    return f' <span style="{MUTED}">({html.escape(reset.keepable)})</span>'


def diff_html(preview: OnlineChangePreview) -> str:
    heading = f'<div style="{_HEADING}">Source changes since the running configuration</div>'
    if not preview.running_from:
        return heading + note_html(
            "source-diff-unknown",
            "The running configuration's sources are not known here (no backup of "
            f"{preview.plan.old_crc} and no project that compiles to it).",
        )
    origin = note_html("source-origin", f"against {preview.running_from}")
    if not preview.diff:
        return heading + origin + note_html("source-diff-none", "No file differs.")
    files = "".join(_file_diff(diff) for diff in preview.diff)
    return f'{heading}{origin}<div data-testid="source-diff" style="{_SCROLL}">{files}</div>'


def _file_diff(diff: FileDiff) -> str:
    lines = "".join(_diff_line(line) for line in diff.lines)
    if diff.cut:
        lines += f'<div style="{MUTED}">... {diff.cut} more lines</div>'
    return (
        f'<div data-file="{html.escape(diff.name)}" style="font-weight:600;padding:2px 6px;'
        f'background:#f1f3f5">{html.escape(diff.name)} ({diff.change})</div>'
        f'<pre style="margin:0;padding:2px 6px;font-size:0.8em;line-height:1.35">{lines}</pre>'
    )


def _diff_line(line: str) -> str:
    color = {"+": "background:#ebfbee", "-": "background:#fff5f5", "@": "color:#1971c2"}.get(
        line[:1], ""
    )
    kind = {"+": "added", "-": "removed"}.get(line[:1], "context")
    return f'<div data-diff="{kind}" style="{color}">{html.escape(line) or " "}</div>'


def values_html(plan: p.ReloadPlanInfo) -> str:
    changes = sorted(
        plan.changes, key=lambda change: (_FATE_ORDER.get(fate(change), 9), change.path)
    )
    head = "".join(
        f'<th style="{_CELL};text-align:left;position:sticky;top:0;background:#fff">{name}</th>'
        for name in ("Variable", "Fate", "Type", "Value after the change")
    )
    rows = "".join(_change_row(change) for change in changes) or (
        f'<tr><td style="{_CELL};{MUTED}" colspan="4">No variable.</td></tr>'
    )
    return (
        f'<div style="{_HEADING}">Every value</div><div style="{_SCROLL}">'
        '<table data-testid="reload-plan" style="font-size:0.85em;border-collapse:collapse;'
        f'width:100%"><tr>{head}</tr>{rows}</table></div>'
    )


def _change_row(change: p.VariableChange) -> str:
    if change.action in ("converted", "initialised"):
        type_text = f"{change.old_type} → {change.new_type}"
    else:
        type_text = change.new_type or change.old_type or ""
    path, shown = html.escape(change.path), fate(change)
    return (
        f'<tr><td style="{_CELL};font-family:monospace">{path}</td>'
        f'<td style="{_CELL};color:{FATE_COLORS.get(shown, "inherit")};font-weight:600" '
        f'data-fate="{path}">{shown}</td>'
        f'<td style="{_CELL};{MUTED}">{html.escape(type_text)}</td>'
        f'<td style="{_CELL}">{html.escape(value_after(change))}</td></tr>'
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


def outcome_html(resource: str, changed: OnlineChanged) -> str:
    done = changed.reloaded.reply.reload
    backup = changed.reloaded.backup
    kept = (
        f'<code data-testid="reload-backup">{html.escape(str(backup.path))}</code>'
        if backup.path is not None
        else f'<span style="color:{RED}">none: {html.escape(backup.error or "")}</span>'
    )
    rows = [
        (
            "Resource",
            f"{html.escape(resource)}: {html.escape(changed.reloaded.reply.status.state)}",
        ),
        (
            "Configuration",
            f"{html.escape(done.old_crc)} &rarr; "
            f'<code data-testid="reload-new-crc">{html.escape(done.new_crc)}</code>',
        ),
        (
            "Pause",
            f'<span data-testid="reload-pause">{done.pause_us / 1000:.3f} ms</span> '
            f'<span style="{MUTED}">(the cycles stood still for the switch-over)</span>',
        ),
        ("Carried over", counted(done.carried, "value")),
        ("Backup", kept),
    ]
    if changed.kept:
        rows.append(("Kept online", html.escape(", ".join(changed.kept))))
    if changed.not_kept:
        refused = html.escape("; ".join(changed.not_kept))
        rows.append(("Not kept", f'<span style="color:{RED}">{refused}</span>'))
    cells = "".join(
        f'<tr><td style="{MUTED};padding:1px 12px 1px 0;vertical-align:top">{name}</td>'
        f'<td style="word-break:break-all">{value}</td></tr>'
        for name, value in rows
    )
    return (
        f'<div data-testid="reload-result" style="margin:6px 0;padding:4px 8px;'
        f'border-radius:4px;border:1px solid {GREEN}"><b style="color:{GREEN}">'
        f'Online change done</b><table style="font-size:0.9em">{cells}</table></div>'
    )


def _value(value: bool | int | str) -> str:
    return ("ON" if value else "OFF") if isinstance(value, bool) else str(value)
