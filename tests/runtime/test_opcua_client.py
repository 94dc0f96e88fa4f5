"""A resource reaches another resource's OPC UA server as remote I/O: two runtime
processes, the one (Sink) subscribing a variable of the other (Src) into a located input
and writing a located output to a writable variable there. Src killed: Sink's input holds
its safe value, quality bad, and an event says so; Src back: connected again, values
again. (The client against a plain asyncua server: test_opcua_remote.py.)"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from backend.engineering.project import compile_project, load_project, user_entry
from backend.engineering.resource_client import ResourceClient
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from runtime.contract.private_files import write_private
from runtime.contract.protocol import GetEvents, GetIo, GetValues
from tests.conftest import free_port
from tests.support.runtime_process import (
    client_session,
    router,
    runtime_process,
    store_artifact,
    wait_for,
    wait_until_answering,
)

PASSWORD = "link-password"

SOURCE = """VAR_GLOBAL
  srcLevel : INT;
  srcCommand : INT;
END_VAR
PROGRAM Main
srcLevel := srcLevel + 1;
IF srcLevel > 30000 THEN srcLevel := 1; END_IF;
END_PROGRAM
"""

SOURCE_SETTINGS = """[resource]
name = "Src"
target_cycle_ms = 20
autostart = "cold"
safety_operation = false

[opcua]
expose = ["srcLevel", "srcCommand"]
writable = ["srcCommand"]
trust_unknown_clients = true
"""

SINK = """VAR_GLOBAL
  remoteLevel AT %IW0 : INT;
  command AT %QW0 : INT;
END_VAR
PROGRAM Main
command := 7;
END_PROGRAM
"""

SINK_SETTINGS = """[resource]
name = "Sink"
target_cycle_ms = 20
autostart = "cold"

[[opcua.device]]
name = "source"
endpoint = "opc.tcp://127.0.0.1:{port}"
user = "link"
password_file = "{password_file}"
period_ms = 50
timeout_ms = 1000

[[opcua.device.point]]
variable = "remoteLevel"
node = "ns=2;s=Src.srcLevel"
safe_value = -1

[[opcua.device.point]]
variable = "command"
node = "ns=2;s=Src.srcCommand"
"""


def project(folder: Path, settings: str, source: str, accounts: list[UserAccount]) -> Path:
    folder.mkdir()
    users = "".join("\n" + user_entry(account) for account in accounts)
    (folder / "padt.toml").write_text(settings + users)
    (folder / "main.st").write_text(source)
    result = compile_project(load_project([folder]))
    assert result.artifact is not None, result.diagnostics
    state = folder.parent / f"{folder.name}-state"
    store_artifact(state, result.artifact)
    return state


def test_a_resource_reads_and_writes_another_over_opc_ua_and_survives_its_loss(
    tmp_path: Path,
) -> None:
    verifier = hash_password(PASSWORD)
    admin = UserAccount("admin", "administrator", verifier)
    src_state = project(
        tmp_path / "src", SOURCE_SETTINGS, SOURCE,
        [admin, UserAccount("link", "operator", verifier)],
    )  # fmt: skip
    password_file = tmp_path / "link.password"
    write_private(password_file, f"{PASSWORD}\n".encode())
    port = free_port()
    sink_settings = SINK_SETTINGS.format(port=port, password_file=password_file)
    sink_state = project(tmp_path / "sink", sink_settings, SINK, [admin])
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    source = ("Src", src_state, endpoint, "--opcua-port", str(port))
    with (
        router(endpoint),
        client_session(endpoint) as session,
        runtime_process("Sink", sink_state, endpoint, "--modbus-port", "0"),
    ):
        sink = ResourceClient(session, "Sink")
        wait_until_answering(sink)
        sink.login("admin", PASSWORD)

        def remote_level() -> Any:
            return sink.ask(GetValues()).values["remoteLevel"]

        def quality() -> str:
            points = sink.ask(GetIo()).points
            return next(
                p.quality for p in points if (p.source, p.variable) == ("source", "remoteLevel")
            )

        def lines() -> list[str]:
            return [e.message for e in sink.ask(GetEvents(limit=500)).events if e.kind == "io"]

        with runtime_process(*source) as src_process:
            src = ResourceClient(session, "Src")
            wait_until_answering(src)
            src.login("admin", PASSWORD)
            wait_for("the level arrives", lambda: remote_level() > 0)
            first = remote_level()
            wait_for("the level moves", lambda: remote_level() > first)
            assert quality() == "good"
            wait_for("the output arrives", lambda: src.ask(GetValues()).values["srcCommand"] == 7)
            # connected (or, had Src not been up yet, lost first and then connected again)
            assert any(m.startswith("OPC UA server source connected") for m in lines())
            device = sink.ask(GetIo()).io
            assert device is not None and device.devices[0].protocol == "opcua"
            assert device.devices[0].host == f"opc.tcp://127.0.0.1:{port}"

            src_process.kill()  # the source fails hard
            wait_for("the safe value", lambda: remote_level() == -1)
            assert quality() == "bad"
            wait_for("the loss is an event", lambda: any("source lost" in m for m in lines()))

        with runtime_process(*source):
            wait_for(
                "connected again", lambda: lines()[-1] == "OPC UA server source connected again"
            )
            wait_for("the level again", lambda: remote_level() > 0)
            assert quality() == "good"
