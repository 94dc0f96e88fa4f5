"""The Download dialog: a whole configuration into a resource in STOP (spec section 8).
It compiles the project twice, asks the resource for its state and parameters, and says
what the download would do, naming the resource and the CRC it runs and the new one,
or why it cannot be done now; Download sends exactly the configuration shown, then the
outcome and the resource's next step (Start) are offered in the same dialog."""

from __future__ import annotations

import html

import viser

from backend.engineering.compile_gate import CheckedCompile, compile_checked
from backend.engineering.download import DownloadPlan, download_checked, plan_download
from frontend.confirm import attempt
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


def ask_download(deployment: Deployment, project: str) -> None:
    """Open the Download dialog for `project` and the resource selected in the workspace."""
    client, resource = deployment.client, deployment.selected()
    folder = deployment.projects.get(project)
    if resource is None or folder is None:
        why = "select a resource online first" if resource is None else f"no project {project}"
        client.add_notification("Download", why, color="red", auto_close_seconds=6)
        return
    gui = client.gui
    with gui.add_modal(f"Download: {project} into {resource}") as modal:
        body = gui.add_html(
            WIDE_MODAL + note_html("download-progress", f"Compiling {project} twice ...")
        )
        progress = gui.add_progress_bar(100, animated=True)
        download = gui.add_button("Download", color="red", visible=False)
        start = gui.add_button(f"Start {resource}", color="green", visible=False)
        close = gui.add_button("Cancel", color="gray")
    close.on_click(lambda _: modal.close())
    found: dict[str, CheckedCompile] = {}

    def prepare() -> None:
        try:
            checked = compile_checked([folder])
            resource_client = deployment.client_of(resource)
            status = resource_client.ask(p.GetStatus()).status
            configured = status.crc is not None
            parameters = resource_client.ask(p.GetParameters()).resource if configured else None
        except KNOWN_FAILURES as error:
            body.content = WIDE_MODAL + failure_html(failure_of(error), "Download")
            progress.visible = False
            close.label = "Close"
            return
        verdict = deployment.allowed(p.Load)
        plan = plan_download(checked, status, parameters, None if verdict.ok else verdict.reason)
        found["checked"] = checked
        body.content = WIDE_MODAL + plan_html(plan, project)
        progress.visible = False
        download.visible = plan.possible
        if not plan.possible:
            close.label = "Close"

    def send() -> None:
        checked = found.get("checked")
        if checked is None:
            return
        download.disabled = True
        progress.visible = True

        def act() -> None:
            how = f"browser UI: download of project {project} by {deployment.user}"
            try:
                done = download_checked(
                    deployment.client_of(resource), checked, deployment.backup_dir, how
                )
            except KNOWN_FAILURES as error:
                body.content += failure_html(failure_of(error), "Download")
                progress.visible, download.visible = False, False
                close.label = "Close"
                return
            backup = done.backup
            kept = (
                f'<code data-testid="download-backup">{html.escape(str(backup.path))}</code>'
                if backup.path is not None
                else f'<span style="color:{RED}">none: {html.escape(backup.error or "")}</span>'
            )
            body.content += (
                f'<div data-testid="download-done" style="margin:8px 0;padding:4px 8px;'
                f'border:1px solid {GREEN};border-radius:4px"><b style="color:{GREEN}">'
                f"Downloaded</b>: {html.escape(resource)} is "
                f'<span data-testid="download-state">{html.escape(done.status.state)}</span> '
                f'with configuration <code data-testid="download-crc">'
                f"{html.escape(done.status.crc or '')}</code>. Backup: {kept}</div>"
            )
            progress.visible, download.visible = False, False
            start.visible = deployment.allowed(p.Start).ok
            close.label = "Close"

        in_background("padt-download", act)

    def start_now(_: viser.GuiEvent[viser.GuiButtonHandle]) -> None:
        start.disabled = True
        started = attempt(
            client, f"Start {resource}", lambda: deployment.client_of(resource).ask(p.Start())
        )
        if started:
            modal.close()
        else:
            start.disabled = False

    download.on_click(lambda _: send())
    start.on_click(start_now)
    in_background("padt-download-plan", prepare)


def plan_html(plan: DownloadPlan, project: str) -> str:
    """What the download would do, in words, or why it cannot be done now. The project is
    named as the tree and the Online change dialog name it (its name on the shelf), not
    by the name in its padt.toml."""
    first, second = plan.check_crcs
    rows = [
        ("Resource", f'<b data-testid="download-resource">{html.escape(plan.resource)}</b>'),
        ("Project", f'<span data-testid="download-project">{html.escape(project)}</span>'),
        (
            "Configuration",
            f'running <code data-testid="download-running-crc">'
            f"{html.escape(plan.running_crc or '(none)')}</code> &rarr; new "
            f'<code data-testid="download-new-crc">{html.escape(plan.new_crc)}</code>',
        ),
        (
            "Compiled twice",
            f"{html.escape(first)} and {html.escape(second)}, in two processes",
        ),
    ]
    cells = "".join(
        f'<tr><td style="{MUTED};padding:1px 12px 1px 0;vertical-align:top">{name}</td>'
        f"<td>{value}</td></tr>"
        for name, value in rows
    )
    if plan.possible:
        what = "".join(f"<li>{html.escape(effect)}</li>" for effect in plan.effects)
        said = f'<div data-testid="download-effects">The download:<ul>{what}</ul></div>'
    else:
        why = "".join(f"<li>{html.escape(reason)}</li>" for reason in plan.refusals)
        said = (
            f'<div data-testid="download-refused" style="color:{RED}">Not possible now:'
            f"<ul>{why}</ul></div>"
        )
    return f'<table style="font-size:0.95em">{cells}</table>{said}'
