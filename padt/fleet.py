"""`padt fleet status`, `padt fleet load` and `padt fleet reload`: the resources on a router
mesh as one table, and one project loaded into several of them in turn, or changed online
in several of them in turn (docs/cli.md)."""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from contextlib import closing

from backend.engineering.fleet import (
    FleetEntry,
    FleetLoad,
    FleetReload,
    download_fleet,
    fleet_confirmation,
    fleet_done,
    fleet_refusal,
    keep_online_refusal,
    reload_fleet,
    reload_fleet_done,
    survey,
)
from backend.engineering.project import load_project
from backend.engineering.reload import counted, rename_map
from backend.engineering.resource_client import ResourceClient
from padt.configuration import plan_lines
from padt.online import Failed, password_of, run, sign_in, table
from runtime.contract.refusal import Refusal
from runtime.contract.session import open_client

# `padt fleet status` exit codes
ALL_RUN, NOT_ALL_RUN = 0, 1


def _cells(entry: FleetEntry) -> list[str]:
    status = entry.status
    if status is None:
        return [entry.resource, "-", entry.note, "-", "-", "-", "-"]
    return [
        entry.resource,
        status.host or "-",
        str(status.state),
        status.crc or "-",
        status.project or "-",
        f"{status.cycle_ms:g} ms",
        f"{status.stats.mean_ms:.3f} ms",
    ]


def fleet_lines(entries: list[FleetEntry]) -> list[str]:
    header = ["resource", "host", "state", "crc", "project", "target", "mean"]
    return table(header, [_cells(entry) for entry in entries])


def status(args: argparse.Namespace) -> int:
    def body() -> int:
        password = password_of(args.user) if args.user is not None else None

        def login(client: ResourceClient) -> None:
            client.login(args.user, password or "")

        # no router: main() says so in one line, exit code 1
        with closing(open_client(args.zenoh, args.zenoh_config)) as session:
            entries = survey(session, login=login if args.user else None, wait_s=args.wait)
        if args.json:
            print(json.dumps([e.as_json() for e in entries], indent=2, sort_keys=True))
        elif entries:
            print("\n".join(fleet_lines(entries)))
        if not entries:
            print(f"padt fleet status: no resource is online on {args.zenoh}", file=sys.stderr)
            return NOT_ALL_RUN
        return ALL_RUN if all(entry.running for entry in entries) else NOT_ALL_RUN

    return run("fleet status", args, body)


def _told(result: FleetLoad) -> None:
    for line in result.diagnostics:
        print(line, file=sys.stderr)
    for warning in result.warnings:
        print(f"{result.resource}: {warning}", file=sys.stderr)
    if result.outcome == "done":
        backup = f"backup {result.backup}" if result.backup else f"no backup: {result.backup_error}"
        print(f"{result.resource}: done, configuration CRC {result.crc}, {result.state}, {backup}")
    elif result.outcome == "refused":
        crc = f" (configuration CRC {result.crc})" if result.crc else ""
        print(f"{result.resource}: refused ({result.code}){crc}: {result.message}")
    else:
        print(f"{result.resource}: not tried")


def _command_words(command: str, args: argparse.Namespace) -> list[str]:
    """The start of the command line that repeats a fleet command (kept with its backups)."""
    words = ["padt", "fleet", command, *map(str, args.paths)]
    for name in args.resource:
        words += ["--resource", name]
    return [*words, "--zenoh", args.zenoh]


def _logged_in(
    client: ResourceClient, args: argparse.Namespace, password: str | None
) -> ResourceClient:
    """`client`, logged in as `--user`; a refused login is a Refusal (`login`), which ends
    the fleet command at that resource."""
    try:
        sign_in(client, args, password)
    except Failed as exc:
        raise Refusal("login", str(exc)) from None
    return client


def load(args: argparse.Namespace) -> int:
    wrong = fleet_refusal(args.resource)
    if wrong is not None:
        print(f"padt fleet load: {wrong.message}", file=sys.stderr)
        return 2

    def body() -> int:
        load_project(list(args.paths))  # an unreadable project before any router is asked
        password = password_of(args.user) if args.user is not None else None
        how = shlex.join([*_command_words("load", args), "--backup-dir", str(args.backup_dir)])
        # no router: main() says so in one line, exit code 1
        with closing(open_client(args.zenoh, args.zenoh_config)) as session:

            def client_of(name: str) -> ResourceClient:
                return _logged_in(ResourceClient(session, name), args, password)

            results = download_fleet(
                args.paths,
                args.resource,
                client_of,
                args.backup_dir,
                how,
                told=None if args.json else _told,
            )
        if args.json:
            shown = {
                "done": fleet_done(results),
                "resources": [
                    {**r.as_json(), "backup": str(r.backup) if r.backup else None} for r in results
                ],
            }
            print(json.dumps(shown, indent=2, sort_keys=True))
        return 0 if fleet_done(results) else 1

    return run("fleet load", args, body)


def _reload_told(result: FleetReload) -> None:
    name = result.resource
    for line in result.diagnostics:
        print(line, file=sys.stderr)
    if result.preview is not None:
        first, *rest = plan_lines(result.preview, with_diff=False)
        print(f"{name}: {first}")
        for line in rest:
            print(f"  {line}")
    if result.outcome == "done":
        backup = f"backup {result.backup}" if result.backup else f"no backup: {result.backup_error}"
        print(
            f"{name}: done, configuration CRC {result.old_crc} -> {result.new_crc}, "
            f"pause {result.pause_us or 0:.0f} us, {counted(result.carried or 0, 'value')} "
            f"carried over, {result.state}, {backup}"
        )
        for kept in result.kept_online:
            print(f"{name}: kept online: {kept}")
        for why in result.not_kept_online:
            print(f"{name}: not set again online: {why}")
    elif result.outcome == "refused":
        print(f"{name}: refused ({result.code}): {result.message}")
    elif result.outcome == "not tried":
        print(f"{name}: not tried")


def reload(args: argparse.Namespace) -> int:
    wrong = fleet_refusal(args.resource) or keep_online_refusal(args.keep_online)
    if wrong is not None:
        print(f"padt fleet reload: {wrong.message}", file=sys.stderr)
        return 2

    def body() -> int:
        try:
            renames = rename_map(args.rename)
        except Refusal as refused:
            raise Failed(f"--rename: {refused.message}", 2) from None
        load_project(list(args.paths))  # an unreadable project before any router is asked
        password = password_of(args.user) if args.user is not None else None
        confirmed = args.yes and not args.preview
        words = _command_words("reload", args)
        words += [word for new, old in args.rename for word in ("--rename", f"{old}={new}")]
        words += [word for name in args.keep_online for word in ("--keep-online", name)]
        how = shlex.join([*words, "--backup-dir", str(args.backup_dir), "--yes"])
        # no router: main() says so in one line, exit code 1
        with closing(open_client(args.zenoh, args.zenoh_config)) as session:

            def client_of(name: str) -> ResourceClient:
                return _logged_in(ResourceClient(session, name), args, password)

            results = reload_fleet(
                args.paths,
                args.resource,
                client_of,
                args.backup_dir,
                how,
                confirmed=confirmed,
                renames=renames,
                keep_online=args.keep_online,
                told=None if args.json else _reload_told,
            )
        done = reload_fleet_done(results)  # never after a preview: nothing was reloaded
        possible = all(result.possible for result in results)
        if args.json:
            shown = {
                "done": done,
                "possible": possible,
                "resources": [
                    {**r.as_json(), "backup": str(r.backup) if r.backup else None} for r in results
                ],
            }
            print(json.dumps(shown, indent=2, sort_keys=True))
        if confirmed:
            return 0 if done else 1
        if args.preview:
            return 0 if possible else 1
        # an online change of running controllers is never implicit
        accepts = fleet_confirmation(results)
        raise Failed(f"{accepts + '; ' if accepts else ''}nothing changed; confirm with --yes")

    return run("fleet reload", args, body)
