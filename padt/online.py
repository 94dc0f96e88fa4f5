"""`padt load`, `start`, `stop`, `status` and `reload`: the commands that act on a running
resource over Zenoh. docs/cli.md documents their output and exit codes.

Exit codes: 0 done, 1 refused (by the resource, the compile-twice gate, or a missing
confirmation) or the resource did not answer, 2 bad options or an unreadable project.
"""

from __future__ import annotations

import argparse
import getpass
import json
import os
import shlex
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from backend.engineering.backup import BackupError
from backend.engineering.loading import (
    CheckedCompile,
    CompileFailed,
    LoadRefused,
    backup_of,
    checked_reply,
    compile_checked,
    counted,
    download,
    needs_confirmation,
    preview_reload,
)
from backend.engineering.loading import reload as reload_resource
from backend.engineering.project import ProjectError
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from runtime.contract.keyspace import valid_resource_name


class _Failed(Exception):
    """Ends a command with a message on stderr and an exit code."""

    def __init__(self, message: str, code: int = 1) -> None:
        super().__init__(message)
        self.code = code


def parse_rename(text: str) -> tuple[str, str]:
    """`OLD=NEW` as the user writes it -> (NEW, OLD) as the runtime's rename map has it."""
    old, sep, new = text.partition("=")
    old, new = old.strip(), new.strip()
    if not sep or not old or not new or "=" in new:
        raise argparse.ArgumentTypeError(f"'{text}' is not OLD=NEW")
    return new, old


def _renames(pairs: list[tuple[str, str]]) -> dict[str, str]:
    renames: dict[str, str] = {}
    for new, old in pairs:
        if new.upper() in (known.upper() for known in renames):
            raise _Failed(f"--rename gives {new} twice", 2)
        renames[new] = old
    return renames


@contextmanager
def _client(args: argparse.Namespace) -> Iterator[ResourceClient]:
    from runtime.contract.session import open_client
    from runtime.contract.session_options import RouterUnreachable

    try:
        session = open_client(args.zenoh, args.zenoh_config)
    except RouterUnreachable as exc:
        raise _Failed(str(exc)) from None
    try:
        client = ResourceClient(session, args.resource)
        if args.user is not None:
            _log_in(client, args.user)
        yield client
    except ResourceUnreachable as exc:
        raise _Failed(
            f"{exc}: is `padt runtime --resource {args.resource}` running and connected to "
            f"{args.zenoh}?"
        ) from None
    finally:
        session.close()


def _log_in(client: ResourceClient, user: str) -> None:
    """Log in as `user`: the password from PADT_PASSWORD, else asked for (never an
    option, so that it stays out of shell histories and process lists)."""
    password = os.environ.get("PADT_PASSWORD")
    if password is None:
        password = getpass.getpass(f"password of {user}: ")
    reply = client.login(user, password)
    if not reply.get("ok"):
        error = reply.get("error", {})
        raise _Failed(f"login refused ({error.get('code')}): {error.get('message')}")


def _run(name: str, args: argparse.Namespace, body: Callable[[], int]) -> int:
    """Run a command body; refusals and failures become one line on stderr."""
    if not valid_resource_name(args.resource):
        print(f"padt {name}: invalid resource name '{args.resource}'", file=sys.stderr)
        return 2
    try:
        return body()
    except CompileFailed as exc:
        for diagnostic in exc.diagnostics:
            print(diagnostic, file=sys.stderr)
        print(f"padt {name}: {exc}", file=sys.stderr)
        return 1
    except LoadRefused as exc:
        print(f"padt {name}: {exc}", file=sys.stderr)
        return 1
    except ProjectError as exc:
        print(f"padt {name}: {exc}", file=sys.stderr)
        return 2
    except _Failed as exc:
        print(f"padt {name}: {exc}", file=sys.stderr)
        return exc.code


def _compile(paths: list[Path]) -> CheckedCompile:
    checked = compile_checked(paths)
    for diagnostic in checked.diagnostics:  # warnings: errors never get this far
        print(diagnostic, file=sys.stderr)
    print(f"check-twice: OK, configuration CRC {checked.artifact.crc}")
    return checked


def _backup(
    args: argparse.Namespace, checked: CheckedCompile, action: str, command: list[str]
) -> None:
    line = shlex.join([*command, "--backup-dir", str(args.backup_dir)])
    try:
        path = backup_of(checked, args.backup_dir, args.resource, action, line)
    except BackupError as exc:
        # the resource has the configuration already; only the record of it is missing
        raise _Failed(f"{action} done, but no backup: {exc}") from None
    print(f"backup: {path}")


def _common(args: argparse.Namespace) -> list[str]:
    return ["--resource", args.resource, "--zenoh", args.zenoh]


# ---- padt load


def load(args: argparse.Namespace) -> int:
    def body() -> int:
        checked = _compile(args.paths)
        with _client(args) as client:
            reply = download(client, checked.artifact)
        status = reply["status"]
        print(f"load: configuration CRC {status['crc']} in resource {args.resource}")
        print(f"resource {args.resource}: {status['state']}")
        command = ["padt", "load", *map(str, args.paths), *_common(args)]
        _backup(args, checked, "load", command)
        return 0

    return _run("load", args, body)


# ---- padt start / stop / status


def _command(args: argparse.Namespace, cmd: str, **arguments: Any) -> dict[str, Any]:
    with _client(args) as client:
        return checked_reply(client.command(cmd, **arguments))


def _program_state(status: dict[str, Any], program: str) -> str:
    for entry in status.get("programs", []):
        if str(entry.get("name", "")).upper() == program.upper():
            return str(entry.get("state"))
    return "?"


def _start_stop(args: argparse.Namespace, name: str) -> int:
    def body() -> int:
        if args.program is None:
            status = _command(args, name)["status"]
            print(f"resource {args.resource}: {status['state']}")
        else:
            status = _command(args, f"{name}_program", program=args.program)["status"]
            print(f"program {args.program}: {_program_state(status, args.program)}")
        return 0

    return _run(name, args, body)


def start(args: argparse.Namespace) -> int:
    return _start_stop(args, "start")


def stop(args: argparse.Namespace) -> int:
    return _start_stop(args, "stop")


def _ms(value: Any) -> str:
    return f"{float(value):.3f} ms"


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    widths = [max(len(row[i]) for row in [header, *rows]) for i in range(len(header))]
    return [
        "  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True)).rstrip()
        for row in [header, *rows]
    ]


def status_lines(status: dict[str, Any]) -> list[str]:
    """A resource status for people: state, configuration, cycle statistics, programs."""
    lines = [f"resource {status.get('resource')}: {status.get('state')}"]
    if status.get("error"):
        lines.append(f"error: {status['error']}")
    if status.get("crc") is None:
        lines.append("configuration: none loaded")
    else:
        lines.append(f"configuration CRC {status['crc']}, project {status.get('project')}")
    stats = status.get("stats") or {}
    lines.append(
        f"cycle {status.get('cycle')}: last {_ms(stats.get('last_ms', 0))}, "
        f"min {_ms(stats.get('min_ms', 0))}, max {_ms(stats.get('max_ms', 0))}, "
        f"mean {_ms(stats.get('mean_ms', 0))}"
    )
    lines.append(
        f"period {_ms(stats.get('period_ms', 0))}, largest jitter "
        f"{_ms(stats.get('jitter_max_ms', 0))}, {stats.get('overruns', 0)} overruns"
    )
    lines.append(
        f"start: {status.get('start') or '-'}, forcing: {'on' if status.get('forcing') else 'off'}"
    )
    programs = status.get("programs") or []
    if programs:
        rows = [
            [
                str(p.get("name")),
                str(p.get("id")),
                str(p.get("priority")),
                str(p.get("state")),
                str(p.get("cycles")),
                str(p.get("crc")),
                str(p.get("error") or ""),
            ]
            for p in programs
        ]
        lines += _table(["program", "id", "priority", "state", "cycles", "crc", "error"], rows)
    return lines


def status(args: argparse.Namespace) -> int:
    def body() -> int:
        current = _command(args, "status")["status"]
        if args.json:
            print(json.dumps(current, indent=2, sort_keys=True))
        else:
            print("\n".join(status_lines(current)))
        return 0

    return _run("status", args, body)


# ---- padt reload


def plan_lines(plan: dict[str, Any]) -> list[str]:
    """The reload preview: every value that is not simply kept, the hazards, the summary.
    Kept values are only counted: they are most of a plan, and nothing happens to them."""
    lines = [f"reload preview: configuration CRC {plan['old_crc']} -> {plan['new_crc']}"]
    programs = plan.get("programs", {})
    for what in ("added", "removed", "changed"):
        if programs.get(what):
            lines.append(f"programs {what}: {', '.join(programs[what])}")
    rows = [
        [
            str(change["path"]),
            str(change["action"]),
            f"{change['old_type'] or '-'} -> {change['new_type'] or '-'}",
            str(change.get("reason") or ""),
        ]
        for change in plan.get("changes", [])
        if change["action"] != "kept"
    ]
    if rows:
        lines += _table(["path", "action", "type", "reason"], rows)
    for hazard in plan.get("hazards", []):
        lines.append(f"WARNING {hazard['kind']}: {hazard['message']}")
    summary = plan.get("summary", {})
    lines.append(
        "summary: "
        + ", ".join(
            f"{summary.get(action, 0)} {action}"
            for action in ("kept", "converted", "initialised", "new", "deleted")
        )
    )
    lines.append(f"estimated switch-over: {float(plan.get('estimate_us', 0)):.0f} us")
    if plan.get("refusals"):
        lines.append("reload not possible: needs STOP and download: " + "; ".join(plan["refusals"]))
    return lines


def reload(args: argparse.Namespace) -> int:
    def body() -> int:
        renames = _renames(args.rename)
        checked = _compile(args.paths)
        with _client(args) as client:
            plan = preview_reload(client, checked.artifact, renames)
            print("\n".join(plan_lines(plan)))
            if args.preview:
                return 0
            if plan.get("refusals"):
                raise LoadRefused(
                    "needs_download", "needs STOP and download: " + "; ".join(plan["refusals"])
                )
            if not args.yes:
                # an online change of a running controller is never implicit
                risks = "".join(f"{risk}, " for risk in needs_confirmation(plan))
                raise _Failed(f"{risks}nothing changed; confirm with --yes")
            reply = reload_resource(
                client,
                checked.artifact,
                renames,
                watchdog_ms=args.watchdog_ms,
                target_cycle_ms=args.target_cycle_ms,
                expected_crc=plan["old_crc"],
            )
        outcome = reply["reload"]
        print(
            f"reload done: configuration CRC {outcome['old_crc']} -> {outcome['new_crc']}, "
            f"pause {float(outcome['pause_us']):.0f} us, "
            f"{counted(outcome['carried'], 'value')} carried over"
        )
        print(f"resource {args.resource}: {reply['status']['state']}")
        command = ["padt", "reload", *map(str, args.paths), *_common(args)]
        for new, old in renames.items():
            command += ["--rename", f"{old}={new}"]
        for flag, value in (
            ("--watchdog-ms", args.watchdog_ms),
            ("--target-cycle-ms", args.target_cycle_ms),
        ):
            if value is not None:
                command += [flag, str(value)]
        command.append("--yes")
        _backup(args, checked, "reload", command)
        return 0

    return _run("reload", args, body)
