"""`padt demo`: a Zenoh router, one runtime process with the embedded demo project loaded
and running, and the browser UI; prints the URL. Ctrl-C stops all of it."""

from __future__ import annotations

import argparse
import ctypes
import dataclasses
import json
import secrets
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from backend.engineering.client_address import TrustedProxies, add_trusted_proxy_option
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from runtime.contract.outside_json import read_json_file
from runtime.contract.private_files import write_private

if TYPE_CHECKING:
    from backend.engineering.project import Project
    from runtime.contract.artifact import Artifact
    from runtime.contract.stop_request import StopRequest

_PR_SET_PDEATHSIG = 1


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--host", default="127.0.0.1", help="address the UI listens on")
    parser.add_argument("--port", type=int, default=8080, help="HTTP port of the UI")
    parser.add_argument("--zenoh-port", type=int, default=7447, help="port of the Zenoh router")
    parser.add_argument(
        "--api-port", type=int, default=8000, help="HTTP port of the REST API (0: any free one)"
    )
    parser.add_argument(
        "--state-dir", type=Path, default=Path("state/demo"), help="the runtime's state folder"
    )
    parser.add_argument(
        "--modbus-port",
        type=int,
        default=5020,
        help="Modbus TCP port of the resource's served image on 127.0.0.1 (0: any free one)",
    )
    parser.add_argument(
        "--opcua-port",
        type=int,
        default=OPCUA_PORT,
        help=f"OPC UA port of the resource's server on 127.0.0.1 (default {OPCUA_PORT}; "
        "0: any free one)",
    )
    parser.add_argument(
        "--no-opcua",
        action="store_true",
        help="no OPC UA server (its start takes about 2 s of CPU)",
    )
    add_trusted_proxy_option(parser)


def _die_with_parent() -> None:
    """In the child: get SIGTERM when the demo process dies, so nothing is left orphaned."""
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)


def admin_file(state_dir: Path) -> Path:
    return state_dir / "demo-administrator.json"


def demo_administrator(state_dir: Path) -> tuple[UserAccount, str | None]:
    """The demo's administrator: made at the first start with a random password, which is
    returned (to be shown once) and kept nowhere; later starts read back only its hash."""
    path = admin_file(state_dir)
    if path.exists():
        try:
            return UserAccount(**read_json_file(path, 64 * 1024)), None
        except (ValueError, TypeError) as exc:  # JsonRefused, or not an account's fields
            raise SystemExit(f"padt demo: {path} is not the demo's administrator: {exc}") from None
    password = secrets.token_urlsafe(18)
    account = UserAccount("admin", "administrator", hash_password(password))
    write_private(path, json.dumps(dataclasses.asdict(account)).encode("utf-8"))
    return account, password


PLANT_PORT_LINE = "port = 5021  # the plant's port"
OPCUA_PORT = 4840
# what `padt demo` adds to the demo's padt.toml: the tank over OPC UA (docs/opcua.md)
OPCUA_SECTION = """
# OPC UA (docs/opcua.md): the tank for SCADA and HMI clients on opc.tcp://127.0.0.1:4840
# (`padt demo --opcua-port` moves it). Clients log in with the demo's accounts over
# Basic256Sha256; the demo trusts a client's certificate at first contact (a plant would
# trust each by hand).
[opcua]
host = "127.0.0.1"
port = 4840
expose = ["TankControl", "tankLevel", "pumpRunning", "pumpCommand"]
writable = ["TankControl.highLevel", "TankControl.lowLevel", "TankControl.restartDelay"]
trust_unknown_clients = true
"""


def demo_project_with_accounts(
    state_dir: Path,
    accounts: list[UserAccount],
    plant_port: int | None = None,
    opcua: bool = False,
) -> Path:
    """The embedded demo project, copied into the state folder with the demo's accounts
    added (and the port the simulated plant listens on, and the OPC UA server): the
    runtime gets it from there, and the REST API serves it as `demo`, so a load through
    the API keeps the accounts."""
    from backend.engineering.project import (
        PROJECT_FILE,
        copy_template_sources,
        demo_project_path,
        user_entry,
    )

    folder = state_dir / "project"
    folder.mkdir(parents=True, exist_ok=True)
    copy_template_sources(demo_project_path(), folder)  # its tests too: the tank template
    entries = "".join("\n" + user_entry(account) for account in accounts)
    config = (demo_project_path() / PROJECT_FILE).read_text(encoding="utf-8")
    config += (OPCUA_SECTION if opcua else "") + entries
    if plant_port is not None:
        assert PLANT_PORT_LINE in config, "the demo's padt.toml names the plant's port"
        config = config.replace(PLANT_PORT_LINE, f"port = {plant_port}  # the plant's port")
    write_private(folder / PROJECT_FILE, config.encode("utf-8"))  # it holds the verifiers
    return folder


def run(args: argparse.Namespace) -> int:
    from padt.demo_plant import DemoPlant
    from runtime.contract.stop_request import StopRequest

    stop = StopRequest()
    admin, admin_password = demo_administrator(args.state_dir)
    plant = DemoPlant()
    try:
        plant_port = plant.start()
    except OSError as exc:
        print(f"padt demo: {exc}", file=sys.stderr)
        return 1
    try:
        return _run_with_plant(args, stop, admin, admin_password, plant_port)
    finally:
        plant.close()


def _keep_demo_backup(state_dir: Path, folder: Path, project: Project, artifact: Artifact) -> None:
    from backend.engineering.backup import BackupError, BackupInfo, write_backup
    from backend.engineering.project import PROJECT_FILE

    sources = {source.name: source.text for source in project.sources}
    config = (folder / PROJECT_FILE).read_text(encoding="utf-8")
    info = BackupInfo(project.name, project.version, artifact.resource.name, "load", "padt demo")
    try:
        write_backup(state_dir / "backups", info, artifact.to_json(), sources, config)
    except BackupError as exc:  # the demo runs all the same; only the record is missing
        print(f"padt demo: no backup of the loaded configuration: {exc}", file=sys.stderr)


def _run_with_plant(
    args: argparse.Namespace,
    stop: StopRequest,
    admin: UserAccount,
    admin_password: str | None,
    plant_port: int,
) -> int:
    from backend.api.server import ApiServer
    from backend.api.service import PadtService
    from backend.engineering.known_resources import KnownResources
    from backend.engineering.padt_accounts import PadtAccounts, write_accounts
    from backend.engineering.project import compile_project, load_project
    from backend.engineering.project_shelf import shelf_of
    from backend.engineering.resource_directory import ResourceDirectory
    from backend.engineering.start_up_freeze import freeze_start_up
    from backend.engineering.watch_lists import WatchLists
    from frontend.app import PadtUi
    from frontend.ui_context import UiContext
    from runtime.contract.session import open_client, open_router
    from runtime.contract.state_folder import artifact_path

    folder = demo_project_with_accounts(args.state_dir, [admin], plant_port, not args.no_opcua)
    project = load_project([folder])
    result = compile_project(project)
    if result.artifact is None:  # the embedded project always compiles; guard all the same
        for diagnostic in result.diagnostics:
            print(diagnostic, file=sys.stderr)
        return 1
    resource = result.artifact.resource.name
    # where the runtime finds it at power-up; it holds the verifiers: owner-only
    write_private(artifact_path(args.state_dir), result.artifact.to_json().encode("ascii"))
    # and its backup, as after a download: an online change shows what changed since
    _keep_demo_backup(args.state_dir, folder, project, result.artifact)

    endpoint = f"tcp/127.0.0.1:{args.zenoh_port}"
    try:
        router = open_router(endpoint)
    except Exception as exc:  # zenoh reports a busy port as a plain exception
        print(f"padt demo: cannot open the Zenoh router on {endpoint}: {exc}", file=sys.stderr)
        print("padt demo: is another demo running? try --zenoh-port", file=sys.stderr)
        return 1
    command = [sys.executable, "-m", "padt.cli", "runtime", "--resource", resource]
    command += ["--state-dir", str(args.state_dir), "--zenoh", endpoint]
    command += ["--modbus-port", str(args.modbus_port)]
    if not args.no_opcua:
        command += ["--opcua-port", str(args.opcua_port)]
    # in a process group of its own: a Ctrl-C at the terminal reaches the demo alone, which
    # ends the runtime in order (the runtime ends its own workers)
    runtime = subprocess.Popen(command, preexec_fn=_die_with_parent, process_group=0)
    session = open_client(endpoint)
    try:
        # the REST API and the UI know the demo's administrator as its Security Administrator
        accounts_file = args.state_dir / "padt-accounts.json"
        write_accounts(accounts_file, (dataclasses.replace(admin, level="security-administrator"),))
        accounts = PadtAccounts(accounts_file, time.monotonic_ns)
        # the demo's project, and a folder for the projects its users make from templates;
        # the tank template is the demo's copy, so that a project made from it keeps the
        # demo's accounts and its plant's port, and loads into Tank1 as the demo does
        projects = shelf_of(
            {"demo": folder},
            args.state_dir / "projects",
            args.state_dir / "padt-audit.jsonl",
            {"tank": folder},
        )
        # the demo's resource keeps its key in the state folder: so do its UI and API
        known = KnownResources(args.state_dir / "known_resources")
        directory = ResourceDirectory(session, known)
        service = PadtService(directory, accounts, projects, args.state_dir / "backups")
        trusted = TrustedProxies(tuple(args.trusted_proxy))
        try:
            api = ApiServer(service, args.host, args.api_port, trusted)
        except OSError:  # busy: like the UI, take another port rather than fail
            api = ApiServer(service, args.host, 0, trusted)
        watch_lists = WatchLists(args.state_dir / "watch-lists.json")
        # the UI knows the same project as the API: the demo's copy in the state folder
        backups = args.state_dir / "backups"
        context = UiContext(directory, accounts, endpoint, watch_lists, projects, backups)
        ui = PadtUi(context, host=args.host, port=args.port, trusted=trusted)
        freeze_start_up()
        try:
            _announce(args.state_dir, resource, result.artifact.crc, admin, admin_password)
            print(f"padt demo: REST API {api.url}/docs (log in as {admin.name})", flush=True)
            print(f"padt demo: open {ui.url} (log in as {admin.name})", flush=True)
            print(
                f"padt demo: Modbus TCP 127.0.0.1:{args.modbus_port}: the tank level is input "
                f"register 0, the pump command coil 0 (the plant: 127.0.0.1:{plant_port})",
                flush=True,
            )
            if not args.no_opcua:
                where = args.opcua_port or "a free port (padt status --io shows it)"
                print(
                    f"padt demo: OPC UA opc.tcp://127.0.0.1:{where} (Basic256Sha256, log in "
                    f"as {admin.name}): the tank is the object ns=2;s={resource}",
                    flush=True,
                )
            stop.sleep_until_requested(lambda: runtime.poll() is None)
            if runtime.returncode is not None:
                code = runtime.returncode
                print(f"padt demo: the runtime ended with code {code}", file=sys.stderr)
        finally:
            ui.close()
            api.close()
            service.close()
    finally:
        session.close()
        runtime.terminate()
        try:
            runtime.wait(timeout=5)
        except subprocess.TimeoutExpired:
            runtime.kill()
        router.close()
    return 0


def _announce(
    state_dir: Path, resource: str, crc: str, admin: UserAccount, password: str | None
) -> None:
    print(f"padt demo: resource {resource} (CRC {crc})", flush=True)
    if password is not None:
        print(
            f"padt demo: administrator '{admin.name}', password {password} "
            "(shown only now; the state folder keeps only its hash)",
            flush=True,
        )
    else:
        print(
            f"padt demo: administrator '{admin.name}' (its password was shown at the first "
            f"start; delete {admin_file(state_dir)} for a new one)",
            flush=True,
        )
