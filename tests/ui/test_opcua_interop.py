"""The resource's OPC UA server as a client nobody here wrote sees it: node-opcua (npm,
pinned by scripts/install-opcua-client.sh), not asyncua, over Basic256Sha256 with a user
and password.

- `padt demo`: browse the tank, subscribe to its level and see it move, write a writable
  setting (the runtime's event names the user), be refused a read-only one, and be refused
  as anonymous.
- A resource with a variable of every IEC elementary type, STRING and arrays included:
  each read with its value and its OPC UA type.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from backend.engineering.project import compile_project, load_project, user_entry
from backend.engineering.resource_client import ResourceClient
from runtime.contract.accounts import hash_password
from runtime.contract.artifact import UserAccount
from runtime.contract.protocol import GetEvents
from runtime.contract.session import open_client
from tests.conftest import free_port
from tests.support.opcua_client import browsed, node_or_skip, run_plan
from tests.support.ports import wait_until_listening
from tests.support.runtime_process import running_resource, store_artifact
from tests.ui.browser_steps import Demo

PASSWORD = "interop-test"


@pytest.fixture(scope="module")
def pki(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """node-opcua's own certificate, made once for the module (0.7 s)."""
    node_or_skip()
    return tmp_path_factory.mktemp("node-opcua-pki")


def plan(port: int, user: str | None, password: str, pki: Path, *steps: Any) -> dict[str, Any]:
    return {
        "endpoint": f"opc.tcp://127.0.0.1:{port}",
        "security": "SignAndEncrypt",
        "user": user,
        "password": password if user is not None else None,
        "pki": str(pki),
        "steps": list(steps),
    }


@pytest.mark.parametrize("demo", ["opcua"], indirect=True)
def test_node_opcua_browses_subscribes_and_writes_the_demo(demo: Demo, pki: Path) -> None:
    tank = "ns=2;s=Tank1"
    level, high = f"{tank}.TankControl.level", f"{tank}.TankControl.highLevel"
    result = run_plan(
        plan(
            demo.opcua_port, "admin", demo.password, pki,
            {"browse": tank, "depth": 3},
            {"subscribe": {"nodes": [level], "sampling_ms": 100, "publishing_ms": 100,
                           "for_ms": 2000}},
            {"write": [{"node": high, "value": 790, "dataType": "Int16"}]},
            {"write": [{"node": level, "value": 1, "dataType": "Int16"}]},
            {"read": [high]},
        ),
        timeout_s=90,
    )  # fmt: skip
    assert "error" not in result, result
    tree, subscribed, written, refused, read = (step for step in result["results"])
    nodes = {n["nodeId"]: n for n in browsed(tree["browse"])}
    assert nodes[f"{tank}.TankControl"]["nodeClass"] == "Object"
    assert nodes[f"{tank}.TankControl.refillDelay"]["nodeClass"] == "Object"
    assert nodes[level]["dataType"] == "Int16"
    assert nodes[level]["description"] == "the tank level: the plant's last good measurement"
    assert nodes[f"{tank}.TankControl.restartDelay"]["dataType"] == "Duration"
    assert nodes[f"{tank}.tankLevel"]["dataType"] == "Int16"
    # the level as the plant moves it
    notifications = subscribed["subscribe"][0]["notifications"]
    levels = [n["value"] for n in notifications if n["statusCode"] == "Good"]
    assert len(set(levels)) >= 2, notifications
    # a writable setting is written, a read-only variable is not
    assert written["write"][0]["statusCode"] == "Good"
    assert refused["write"][0]["statusCode"] == "BadNotWritable"
    assert read["read"][0]["value"] == 790
    with open_client(demo.zenoh) as session:
        client = ResourceClient(session, "Tank1")
        client.login("admin", demo.password)
        events = client.ask(GetEvents(limit=500)).events
    written_events = [(e.message, e.user) for e in events if e.kind == "write"]
    assert ("TankControl.highLevel written: 800 -> 790", "admin") in written_events
    # anonymous is refused
    anonymous = run_plan(plan(demo.opcua_port, None, "", pki, {"read": [level]}))
    assert anonymous.get("error") == "BadIdentityTokenRejected", anonymous


EVERY_TYPE = """VAR_GLOBAL
  vBool : BOOL := TRUE;
  vSint : SINT := -8;
  vUsint : USINT := 200;
  vByte : BYTE := 16#AB;
  vInt : INT := -1234;
  vUint : UINT := 60000;
  vWord : WORD := 16#BEEF;
  vDint : DINT := -123456;
  vUdint : UDINT := 4000000000;
  vDword : DWORD := 16#DEADBEEF;
  vLint : LINT := -9000000000;
  vUlint : ULINT := 18000000000000000000;
  vLword : LWORD := 16#0123456789ABCDEF;
  vReal : REAL := 1.5;
  vLreal : LREAL := 2.25;
  vString : STRING[20] := 'hello, world';
  vWstring : WSTRING[10] := "wide";
  vChar : CHAR := 'c';
  vTime : TIME := T#1m30s;
  vLtime : LTIME := LTIME#1s500ms;
  vDate : DATE := D#2024-01-15;
  vTod : TOD := TOD#12:30:05;
  vDt : DT := DT#2024-01-15-12:30:05;
  vInts : ARRAY[1..3] OF INT := [1, 2, 3];
  vReals : ARRAY[0..1] OF LREAL := [0.5, 1.5];
  vStrings : ARRAY[1..2] OF STRING[8] := ['a', 'bc'];
  vMatrix : ARRAY[1..2, 1..3] OF DINT := [1, 2, 3, 4, 5, 6];
END_VAR
PROGRAM Main
VAR n : INT; END_VAR
n := n + 1;
END_PROGRAM
"""

# each variable: its OPC UA type, and its value as node-opcua gives it
EXPECTED = {
    "vBool": ("Boolean", True),
    "vSint": ("SByte", -8),
    "vUsint": ("Byte", 200),
    "vByte": ("Byte", 0xAB),
    "vInt": ("Int16", -1234),
    "vUint": ("UInt16", 60000),
    "vWord": ("UInt16", 0xBEEF),
    "vDint": ("Int32", -123456),
    "vUdint": ("UInt32", 4000000000),
    "vDword": ("UInt32", 0xDEADBEEF),
    "vLint": ("Int64", "-9000000000"),
    "vUlint": ("UInt64", "18000000000000000000"),
    "vLword": ("UInt64", str(0x0123456789ABCDEF)),
    "vReal": ("Float", 1.5),
    "vLreal": ("Double", 2.25),
    "vString": ("String", "hello, world"),
    "vWstring": ("String", "wide"),
    "vChar": ("String", "c"),
    "vTime": ("Duration", 90000),
    "vLtime": ("Duration", 1500),
    "vDate": ("DateTime", "2024-01-15T00:00:00.000Z"),
    "vTod": ("Duration", 45005000),
    "vDt": ("DateTime", "2024-01-15T12:30:05.000Z"),
    "vInts": ("Int16", [1, 2, 3]),
    "vReals": ("Double", [0.5, 1.5]),
    "vStrings": ("String", ["a", "bc"]),
    "vMatrix": ("Int32", [1, 2, 3, 4, 5, 6]),
}


@pytest.fixture(scope="module")
def every_type(tmp_path_factory: pytest.TempPathFactory) -> Iterator[int]:
    """A runtime process serving a global of every type over OPC UA: its port."""
    tmp = tmp_path_factory.mktemp("every-type")
    folder = tmp / "project"
    folder.mkdir()
    verifier = hash_password(PASSWORD)
    user = user_entry(UserAccount("admin", "administrator", verifier)) + "\n"
    user += user_entry(UserAccount("reader", "read", verifier))
    settings = (
        '[resource]\nname = "Types"\ntarget_cycle_ms = 20\nautostart = "cold"\n\n'
        f"[opcua]\nexpose = {sorted(EXPECTED)!r}\ntrust_unknown_clients = true\n\n{user}"
    ).replace("'", '"')
    (folder / "padt.toml").write_text(settings)
    (folder / "types.st").write_text(EVERY_TYPE)
    result = compile_project(load_project([folder]))
    assert result.artifact is not None, result.diagnostics
    state = tmp / "state"
    store_artifact(state, result.artifact)
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with running_resource("Types", state, endpoint, "--opcua-port", str(port)):
        wait_until_listening(port)
        yield port


def test_node_opcua_reads_every_iec_type(every_type: int, pki: Path) -> None:
    nodes = [f"ns=2;s=Types.{name}" for name in EXPECTED]
    result: dict[str, Any] = {}
    for _ in range(3):  # the first snapshot may still be on its way after the server listens
        result = run_plan(plan(every_type, "reader", PASSWORD, pki, {"read": nodes}))
        assert "error" not in result, result
        if all(r["statusCode"] == "Good" for r in result["results"][0]["read"]):
            break
    read = {r["node"].rsplit(".", 1)[1]: r for r in result["results"][0]["read"]}
    seen = {name: (r["dataType"], r["value"]) for name, r in read.items()}
    expected = {
        name: (kind.replace("Duration", "Double"), value)
        for name, (kind, value) in EXPECTED.items()
    }
    assert seen == expected
    browse = run_plan(
        plan(every_type, "reader", PASSWORD, pki, {"browse": "ns=2;s=Types", "depth": 1})
    )
    types = {n["browseName"].split(":")[-1]: n for n in browsed(browse["results"][0]["browse"])}
    assert {name: types[name]["dataType"] for name in EXPECTED} == {
        name: kind for name, (kind, _) in EXPECTED.items()
    }
    assert types["vMatrix"]["valueRank"] == 2 and types["vMatrix"]["arrayDimensions"] == [2, 3]
    assert types["vInts"]["valueRank"] == 1 and types["vInts"]["arrayDimensions"] == [3]
