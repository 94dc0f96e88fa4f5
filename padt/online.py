"""What every `padt` command that acts on a running resource shares: the session with the
resource (with `--user` and the password from PADT_PASSWORD), and how refusals and failures
end the command: one line on stderr and an exit code (docs/cli.md).

Exit codes: 0 done, 1 refused (by the resource, the compile-twice gate, or a missing
confirmation) or the resource did not answer, 2 bad options or an unreadable project.
"""

from __future__ import annotations

import argparse
import getpass
import os
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from backend.engineering.project import ProjectError
from backend.engineering.resource_client import ResourceClient, ResourceUnreachable
from runtime.contract.protocol import GetStatus
from runtime.contract.refusal import Refusal
from runtime.contract.setup_secret import SETUP_USER, SetupSecretError, read_secret

_SECRET_ENV = "PADT_SETUP_SECRET"


class Failed(Exception):
    """Ends a command with a message on stderr and an exit code."""

    def __init__(self, message: str, code: int = 1) -> None:
        super().__init__(message)
        self.code = code


@contextmanager
def resource_client(args: argparse.Namespace) -> Iterator[ResourceClient]:
    """A client of `--resource` over `--zenoh`, logged in as `--user` if given."""
    from runtime.contract.session import open_client
    from runtime.contract.session_options import RouterUnreachable

    try:
        session = open_client(args.zenoh, args.zenoh_config)
    except RouterUnreachable as exc:
        raise Failed(str(exc)) from None
    try:
        client = ResourceClient(session, args.resource)
        sign_in(client, args)
        yield client
    except ResourceUnreachable as exc:
        raise Failed(
            f"{exc}: is `padt runtime --resource {args.resource}` running and connected to "
            f"{args.zenoh}?"
        ) from None
    finally:
        session.close()


def sign_in(client: ResourceClient, args: argparse.Namespace, password: str | None = None) -> None:
    """Log in as `--user` (with `password`, else as `_log_in` finds it), or as the setup
    account when the command may commission a runtime that waits for it; else not at all.
    Failed when the resource refuses the login."""
    if args.user is not None:
        _log_in(client, args.user, password)
    elif _commissioning(args) and _waits_for_setup(client):
        _log_in(client, SETUP_USER, _setup_secret(args))


def password_of(user: str) -> str:
    """From PADT_PASSWORD, else asked for (never an option: shell histories keep those);
    Failed (exit 2) with no terminal to ask at: a script, a pipe, a service."""
    password = os.environ.get("PADT_PASSWORD")
    if password is not None:
        return password
    if not sys.stdin.isatty():
        raise Failed(f"no terminal to ask the password of {user} at: set PADT_PASSWORD", 2)
    return getpass.getpass(f"password of {user}: ")


def _commissioning(args: argparse.Namespace) -> bool:
    """Whether the command may commission a runtime (`padt load` with a setup secret)."""
    if not hasattr(args, "setup_secret_file"):
        return False
    return args.setup_secret_file is not None or bool(os.environ.get(_SECRET_ENV))


def _waits_for_setup(client: ResourceClient) -> bool:
    """Whether the resource has no configuration yet: only then is the secret of use (a
    later load with the same command line logs in as usual, or not at all)."""
    try:
        return client.ask(GetStatus()).status.access == "setup"
    except Refusal:
        return False


def _setup_secret(args: argparse.Namespace) -> str:
    """The setup secret: from --setup-secret-file, else PADT_SETUP_SECRET (never the
    secret itself as an option, where process lists and shell histories would keep it)."""
    if args.setup_secret_file is None:
        return os.environ[_SECRET_ENV]
    try:
        return read_secret(args.setup_secret_file)
    except SetupSecretError as exc:
        raise Failed(str(exc), 2) from None


def _log_in(client: ResourceClient, user: str, password: str | None = None) -> None:
    """Log in as `user`: the password given, else from PADT_PASSWORD, else asked for
    (never an option, so that it stays out of shell histories and process lists)."""
    if password is None:
        password = password_of(user)
    try:
        client.login(user, password)
    except Refusal as refused:
        raise Failed(f"login refused ({refused.code}): {refused.message}") from None
    # a command that runs long (a recording, --follow) logs in again when the session
    # ends: its expiry, or a restart of the runtime
    client.use_credentials(user, password)


def run(name: str, args: argparse.Namespace, body: Callable[[], int]) -> int:
    """Run a command body; refusals and failures become one line on stderr."""
    try:
        return body()
    except Refusal as refused:
        for diagnostic in refused.details.get("diagnostics", ()):
            print(diagnostic, file=sys.stderr)
        print(f"padt {name}: {refused}", file=sys.stderr)
        if refused.code == "unauthenticated":
            print(
                f"padt {name}: log in with --user NAME (the password from PADT_PASSWORD, "
                "else it is asked for)",
                file=sys.stderr,
            )
        return 1
    except ProjectError as exc:
        print(f"padt {name}: {exc}", file=sys.stderr)
        return 2
    except Failed as exc:
        print(f"padt {name}: {exc}", file=sys.stderr)
        return exc.code


def table(header: list[str], rows: list[list[str]]) -> list[str]:
    """Columns padded to their widest cell, for people at a terminal."""
    widths = [max(len(row[i]) for row in [header, *rows]) for i in range(len(header))]
    return [
        "  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True)).rstrip()
        for row in [header, *rows]
    ]
