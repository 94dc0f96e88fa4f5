"""`padt load` and `padt reload`: a configuration into a running resource, after the
compile-twice gate, with a backup of what was loaded (docs/cli.md)."""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from backend.engineering.compile_gate import CheckedCompile, compile_checked
from backend.engineering.download import Kept, download_checked
from backend.engineering.online_change import (
    OnlineChangePreview,
    chosen_resets,
    online_change,
    parameter_words,
    preview_online_change,
)
from backend.engineering.reload import (
    ReloadOptions,
    counted,
    needs_confirmation,
    rename_map,
    rename_pair,
)
from padt.online import Failed, resource_client, run, table
from runtime.contract.refusal import Refusal


def parse_rename(text: str) -> tuple[str, str]:
    """`OLD=NEW` as the user writes it -> (NEW, OLD) as the runtime's rename map has it."""
    try:
        return rename_pair(text)
    except Refusal as refused:
        raise argparse.ArgumentTypeError(refused.message) from None


def _compile(paths: list[Path], resource: str | None = None) -> CheckedCompile:
    """`resource`: compiled for that resource in place of the project's own (a resource
    a fleet load loaded with a project named for another)."""
    checked = compile_checked(paths, resource)
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


def plan_lines(preview: OnlineChangePreview, with_diff: bool = True) -> list[str]:
    """The reload preview: every value that is not simply kept, the hazards, the summary,
    the online parameter settings it resets, why it cannot be made online, and the source
    diff since the running configuration (`with_diff` False: only the files that differ,
    counted). Kept values are only counted: they are most of a plan, and nothing happens
    to them."""
    plan = preview.plan
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
    for reset in preview.resets:
        keep = f" (--keep-online {reset.name} keeps it)" if not reset.keepable else ""
        lines.append(f"parameter reset: {parameter_words(reset)}{keep}")
    if plan.refusals:
        lines.append("reload not possible: needs STOP and download: " + "; ".join(plan.refusals))
        lines += [f"  {why}" for why in preview.why_not]
    if not preview.running_from:
        lines.append("source diff: the running configuration's sources are not known here")
    elif not with_diff:
        differ = "differs" if len(preview.diff) == 1 else "differ"
        lines.append(
            f"source diff against {preview.running_from}: "
            f"{counted(len(preview.diff), 'file')} {differ}"
        )
    else:
        lines.append(f"source diff against {preview.running_from}:")
        for diff in preview.diff:
            lines.append(f"--- {diff.name} ({diff.change})")
            lines += diff.lines
            if diff.cut:
                lines.append(f"... {diff.cut} more lines")
        if not preview.diff:
            lines.append("  no file differs")
    return lines


def reload(args: argparse.Namespace) -> int:
    def body() -> int:
        try:
            renames = rename_map(args.rename)
        except Refusal as refused:
            raise Failed(f"--rename: {refused.message}", 2) from None
        checked = _compile(args.paths, args.resource if args.compile_for_resource else None)
        with resource_client(args) as client:
            project = checked.project.name
            preview = preview_online_change(client, checked, project, renames, args.backup_dir, {})
            plan = preview.plan
            print("\n".join(plan_lines(preview)))
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
            extra += [word for name in args.keep_online for word in ("--keep-online", name)]
            if args.compile_for_resource:
                extra.append("--compile-for-resource")
            options = ReloadOptions(renames, plan.old_crc, args.watchdog_ms, args.target_cycle_ms)
            how = _command_line(args, "reload", *extra, "--yes")
            keep = chosen_resets(client, checked, args.keep_online)
            changed = online_change(client, checked, options, keep, args.backup_dir, how)
        done = changed.reloaded
        outcome = done.reply.reload
        print(
            f"reload done: configuration CRC {outcome.old_crc} -> {outcome.new_crc}, "
            f"pause {outcome.pause_us:.0f} us, {counted(outcome.carried, 'value')} carried over"
        )
        for kept in changed.kept:
            print(f"kept online: {kept}")
        print(f"resource {args.resource}: {done.reply.status.state}")
        _report_backup(done.backup, "reload")
        if changed.not_kept:
            raise Failed("reload done, online values not set again: " + "; ".join(changed.not_kept))
        return 0

    return run("reload", args, body)
