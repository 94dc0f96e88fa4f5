"""`padt load` and `padt reload`: a configuration into a running resource, after the
compile-twice gate, with a backup of what was loaded (docs/cli.md)."""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from backend.engineering.compile_gate import CheckedCompile, compile_checked
from backend.engineering.download import Kept, download_checked
from backend.engineering.reload import (
    ReloadOptions,
    counted,
    needs_confirmation,
    preview_reload,
    reload_checked,
    rename_map,
)
from padt.online import Failed, resource_client, run, table
from runtime.contract.protocol import ReloadPlanInfo
from runtime.contract.refusal import Refusal


def parse_rename(text: str) -> tuple[str, str]:
    """`OLD=NEW` as the user writes it -> (NEW, OLD) as the runtime's rename map has it."""
    old, sep, new = text.partition("=")
    old, new = old.strip(), new.strip()
    if not sep or not old or not new or "=" in new:
        raise argparse.ArgumentTypeError(f"'{text}' is not OLD=NEW")
    return new, old


def _compile(paths: list[Path]) -> CheckedCompile:
    checked = compile_checked(paths)
    for diagnostic in checked.diagnostics:  # warnings: errors never get this far
        print(diagnostic, file=sys.stderr)
    print(f"check-twice: OK, configuration CRC {checked.artifact.crc}")
    return checked


def _command_line(args: argparse.Namespace, verb: str, *extra: str) -> str:
    """How it was loaded, for the backup's manifest."""
    words = ["padt", verb, *map(str, args.paths), "--resource", args.resource]
    words += ["--zenoh", args.zenoh, *extra, "--backup-dir", str(args.backup_dir)]
    return shlex.join(words)


def _report_backup(kept: Kept, action: str) -> None:
    if kept.path is None:
        # the resource has the configuration already; only the record of it is missing
        raise Failed(f"{action} done, but no backup: {kept.error}")
    print(f"backup: {kept.path}")


def load(args: argparse.Namespace) -> int:
    def body() -> int:
        checked = _compile(args.paths)
        with resource_client(args) as client:
            done = download_checked(client, checked, args.backup_dir, _command_line(args, "load"))
        print(f"load: configuration CRC {done.status.crc} in resource {args.resource}")
        print(f"resource {args.resource}: {done.status.state}")
        _report_backup(done.backup, "load")
        return 0

    return run("load", args, body)


def plan_lines(plan: ReloadPlanInfo) -> list[str]:
    """The reload preview: every value that is not simply kept, the hazards, the summary.
    Kept values are only counted: they are most of a plan, and nothing happens to them."""
    lines = [f"reload preview: configuration CRC {plan.old_crc} -> {plan.new_crc}"]
    for what, names in (
        ("added", plan.programs.added),
        ("removed", plan.programs.removed),
        ("changed", plan.programs.changed),
    ):
        if names:
            lines.append(f"programs {what}: {', '.join(names)}")
    rows = [
        [
            change.path,
            change.action,
            f"{change.old_type or '-'} -> {change.new_type or '-'}",
            change.reason or "",
        ]
        for change in plan.changes
        if change.action != "kept"
    ]
    if rows:
        lines += table(["path", "action", "type", "reason"], rows)
    for hazard in plan.hazards:
        lines.append(f"WARNING {hazard.kind}: {hazard.message}")
    lines.append(
        "summary: "
        + ", ".join(
            f"{plan.summary.get(action, 0)} {action}"
            for action in ("kept", "converted", "initialised", "new", "deleted")
        )
    )
    lines.append(f"estimated switch-over: {plan.estimate_us:.0f} us")
    if plan.refusals:
        lines.append("reload not possible: needs STOP and download: " + "; ".join(plan.refusals))
    return lines


def reload(args: argparse.Namespace) -> int:
    def body() -> int:
        try:
            renames = rename_map(args.rename)
        except Refusal as refused:
            raise Failed(f"--rename: {refused.message}", 2) from None
        checked = _compile(args.paths)
        with resource_client(args) as client:
            plan = preview_reload(client, checked.artifact, renames)
            print("\n".join(plan_lines(plan)))
            if args.preview:
                return 0
            if plan.refusals:
                raise Refusal(
                    "needs_download", "needs STOP and download: " + "; ".join(plan.refusals)
                )
            if not args.yes:
                # an online change of a running controller is never implicit
                risks = "".join(f"{risk}, " for risk in needs_confirmation(plan))
                raise Failed(f"{risks}nothing changed; confirm with --yes")
            extra = [word for new, old in args.rename for word in ("--rename", f"{old}={new}")]
            for flag, value in (
                ("--watchdog-ms", args.watchdog_ms),
                ("--target-cycle-ms", args.target_cycle_ms),
            ):
                if value is not None:
                    extra += [flag, str(value)]
            options = ReloadOptions(renames, plan.old_crc, args.watchdog_ms, args.target_cycle_ms)
            how = _command_line(args, "reload", *extra, "--yes")
            done = reload_checked(client, checked, options, args.backup_dir, how)
        outcome = done.reply.reload
        print(
            f"reload done: configuration CRC {outcome.old_crc} -> {outcome.new_crc}, "
            f"pause {outcome.pause_us:.0f} us, {counted(outcome.carried, 'value')} carried over"
        )
        print(f"resource {args.resource}: {done.reply.status.state}")
        _report_backup(done.backup, "reload")
        return 0

    return run("reload", args, body)
