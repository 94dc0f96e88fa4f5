"""The bus protocol's decoder: every command survives the trip over the wire unchanged, and
nothing a hostile client can send gets past it as anything but a structured refusal."""

from __future__ import annotations

import json
import math
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from runtime.contract import protocol as p
from runtime.contract.refusal import Refusal
from runtime.contract.wire import MAX_DEPTH, decode, encode
from runtime.watch_sets import WatchSnapshot
from tests.conftest import REPO

# one well-formed instance of every command
SAMPLES: dict[str, p.Command[Any]] = {
    "login_begin": p.LoginBegin("op", "bm9uY2Utb2YtdGhlLWNsaWVudA"),
    "login": p.Login("op", "bm9uY2Utb2YtdGhlLWNsaWVudA", "A" * 43 + "="),
    "logout": p.Logout(),
    "status": p.GetStatus(),
    "values": p.GetValues(),
    "variables": p.GetVariables(),
    "parameters": p.GetParameters(),
    "io": p.GetIo(),
    "forcing": p.GetForcing(),
    "events": p.GetEvents(after=5, limit=10, log="long"),
    "watch": p.Watch("w1", ["Main.n", "gLevel"], period_ms=50, append=True),
    "unwatch": p.Unwatch("w1"),
    "watches": p.GetWatches(),
    "start": p.Start(),
    "stop": p.Stop(),
    "reset_stats": p.ResetStats(),
    "start_program": p.StartProgram("Main"),
    "stop_program": p.StopProgram("Main"),
    "force": p.Force("Main.n", [1, 2, [3]], switch=False),
    "unforce": p.Unforce("Main.n"),
    "start_forcing": p.StartForcing("Main", 1500),
    "stop_forcing": p.StopForcing(None),
    "init": p.Init(),
    "cold_start": p.ColdStart(),
    "step": p.Step(),
    "freeze": p.Freeze("Main"),
    "unfreeze": p.Unfreeze("Main"),
    "step_program": p.StepProgram("Main", 20),
    "write": p.Write("Main.s", "text"),
    "set_parameter": p.SetParameter("target_cycle_mode", "fixed"),
    "transfer_begin": p.TransferBegin(1234, "0BADC0DE"),
    "transfer_chunk": p.TransferChunk(0, "{}"),
    "load": p.Load(),
    "reload_preview": p.ReloadPreview({"Main.total": "Main.count"}),
    "reload": p.Reload({}, watchdog_ms=300, target_cycle_ms=None, expected_crc="0BADC0DE"),
    "record_start": p.RecordStart(
        ["Main.*", "gLevel"],
        all_inputs=True,
        trigger=p.Trigger("gLevel", ">", 80),
        pre_cycles=10,
        cycles=100,
        rotate_mb=8,
        id="trace-1",
    ),
    "record_stop": p.RecordStop("trace-1"),
    "record_list": p.RecordList(),
    "record_read": p.RecordRead("trace-1-1.mcap", offset=4096, length=1024),
    "record_delete": p.RecordDelete("trace-1"),
    "debug": p.DebugGet(keep=True),
    "debug_set": p.DebugSet(
        "tank.st",
        [
            p.BreakpointSpec(25, program="TankControl", condition="level > 900", hit_count=2),
            p.BreakpointSpec(30, instance="TankControl.refillDelay", log=["level", "pump"]),
        ],
    ),
    "debug_clear": p.DebugClear(),
    "debug_continue": p.DebugContinue("TankControl"),
    "debug_step": p.DebugStep("TankControl", "into"),
    "debug_run_to": p.DebugRunTo("TankControl", "tank.st", 31),
    "debug_stack": p.DebugStack("TankControl"),
    "debug_variables": p.DebugVariables("TankControl", 1, "refillDelay"),
    "debug_options": p.DebugOptions(30),
}


def refusal(payload: bytes) -> str:
    with pytest.raises(Refusal) as refused:
        p.decode_request(payload)
    return refused.value.code


def request(**fields: Any) -> bytes:
    return json.dumps(fields).encode()


def test_every_command_has_a_sample_and_survives_the_wire() -> None:
    assert sorted(SAMPLES) == sorted(p.COMMANDS)
    for name, command in SAMPLES.items():
        assert name == command.NAME
        decoded = p.decode_request(p.encode_request(command, "tok"))
        assert decoded.command == command and decoded.token == "tok"


def test_the_io_reply_and_status_survive_the_wire() -> None:
    server = p.ModbusServerStatus("127.0.0.1", 5020, True, None, 10, 1, 2)
    device = p.DeviceStatus("plant", "127.0.0.1", 5021, 1, "lost", "no answer", 9, 3, 1.5)
    io = p.IoStatus(server, [device])
    point = p.IoPoint("plant", "level", "%IW0", "INT", "input_register", 0, False, 0, "bad")
    reply = p.IoReply(io, [point])
    assert p.decode_reply(p.GetIo(), p.encode_reply(reply)) == reply


def test_the_levels_are_those_of_the_spec() -> None:
    assert p.COMMAND_LEVELS["status"] == "read"
    assert p.COMMAND_LEVELS["force"] == "operator"
    assert p.COMMAND_LEVELS["reload"] == "read-write"
    assert "login_begin" not in p.COMMAND_LEVELS and "login" not in p.COMMAND_LEVELS
    assert p.COMMAND_LEVELS["logout"] == "read"  # a request of the session: signed
    assert p.SetParameter("allow_online_settings", True).level() == "administrator"
    assert p.SetParameter("watchdog_ms", 100).level() == "read-write"


def test_hostile_requests_are_refused_with_a_code() -> None:
    deep = b"[" * 500 + b"]" * 500  # nested far past any message (and past json's stack)
    assert refusal(deep) == "bad_request"
    assert refusal(b"[" * 100_000) in ("bad_request", "too_large")
    assert refusal(b"x" * (p.MAX_REQUEST_BYTES + 1)) == "too_large"
    assert refusal(b"\xff\xfe") == "bad_request"  # not UTF-8
    assert refusal(b"[]") == "bad_request"
    assert refusal(request(cmd=7)) == "bad_request"
    assert refusal(request(cmd="self_destruct")) == "unknown_command"
    assert refusal(request(cmd="status", token=["x"])) == "bad_request"
    nested_value = {"cmd": "write", "variable": "Main.a", "value": 1}
    for _ in range(MAX_DEPTH + 1):
        nested_value["value"] = [nested_value["value"]]
    assert refusal(json.dumps(nested_value).encode()) == "bad_request"


@pytest.mark.parametrize(
    "fields",
    [
        {"cmd": "events", "limit": -1},
        {"cmd": "events", "limit": 10**6},
        {"cmd": "events", "after": "3"},
        {"cmd": "events", "after": True},  # a boolean is no integer
        {"cmd": "events", "log": "both"},
        {"cmd": "start_forcing", "timeout_ms": 10**100},
        {"cmd": "start_forcing", "timeout_ms": 0},
        {"cmd": "watch", "id": "a/b", "variables": []},
        {"cmd": "watch", "id": "w", "variables": ["x"] * (p.MAX_WATCHED + 1)},
        {"cmd": "watch", "id": "w", "variables": ["x"], "period_ms": 1},
        {"cmd": "watch", "id": "w"},  # a required argument missing
        {"cmd": "write", "variable": "x" * (p.MAX_PATH + 1), "value": 1},
        {"cmd": "write", "variable": "Main.n", "value": 1, "extra": 2},  # unknown argument
        {"cmd": "login", "user": "x" * 60_000, "password": "p"},
        {"cmd": "transfer_begin", "size": 0, "crc": "0BADC0DE"},
        {"cmd": "transfer_begin", "size": 10, "crc": "0"},
        {"cmd": "reload", "renames": {"a": 1}},
        {"cmd": "set_parameter", "name": "watchdog_ms", "value": [1]},
    ],
)
def test_wrong_types_and_ranges_are_bad_requests(fields: dict[str, Any]) -> None:
    assert refusal(json.dumps(fields).encode()) == "bad_request"


json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(),
    lambda inner: st.lists(inner) | st.dictionaries(st.text(), inner),
    max_leaves=30,
)


@settings(max_examples=300)
@given(
    st.sampled_from(sorted(p.COMMANDS)),
    st.dictionaries(st.text(max_size=12), json_values, max_size=4),
)
def test_any_json_is_a_command_or_a_refusal(name: str, fields: dict[str, Any]) -> None:
    payload = json.dumps({**fields, "cmd": name}).encode()
    try:
        decoded = p.decode_request(payload)
    except Refusal as refused:
        assert refused.code == "bad_request"
        return
    assert type(decoded.command) is p.COMMANDS[name]


@settings(max_examples=300)
@given(st.binary(max_size=200))
def test_any_bytes_are_a_command_or_a_refusal(payload: bytes) -> None:
    try:
        p.decode_request(payload)
    except Refusal as refused:
        assert refused.code in ("bad_request", "unknown_command", "too_large")


def test_replies_are_checked_on_the_client_too() -> None:
    status = p.GetStatus()
    with pytest.raises(Refusal) as refused:
        p.decode_reply(status, b'{"ok": false, "error": {"code": "forbidden", "message": "no"}}')
    assert (refused.value.code, refused.value.message) == ("forbidden", "no")
    for bad in (b"", b"[]", b'{"ok": true}', b'{"ok": true, "status": {"state": 1}}'):
        with pytest.raises(Refusal) as wrong:
            p.decode_reply(status, bad)
        assert wrong.value.code == "bad_reply"
    watch = p.WatchPublication(3, 2, [5, [1.5, "nan"], "text", None], "FLSD")
    assert p.decode_publication(p.WatchPublication, json.dumps(encode(watch)).encode()) == watch
    snapshot = WatchSnapshot(3, 2, [5, [1.5, math.nan], "text", None], "FLSD")
    assert p.decode_publication(p.WatchPublication, snapshot.message()) == watch
    for bad in (
        b'{"cycle": 1, "values": {"x": {"value": 1}}}',
        b'{"cycle": 1, "revision": 1, "values": [1], "qualities": "X"}',
        b'{"cycle": 1, "revision": 1, "values": 1, "qualities": "L"}',
    ):
        with pytest.raises(Refusal):
            p.decode_publication(p.WatchPublication, bad)


def test_decoding_makes_the_declared_types() -> None:
    plan = decode(p.ReloadPlanInfo, encode(_plan()))
    assert plan == _plan() and isinstance(plan.hazards[0], p.Hazard)


def _plan() -> p.ReloadPlanInfo:
    return p.ReloadPlanInfo(
        old_crc="00000001",
        new_crc="00000002",
        possible=True,
        refusals=[],
        hazards=[p.Hazard("active-step-deleted", "Main", "step S2 is active")],
        programs=p.ProgramChanges([], [], ["Main"]),
        summary={"kept": 1},
        changes=[p.VariableChange("Main.n", "kept", "INT", "INT")],
        estimate_us=3.0,
    )


def test_the_protocol_reference_lists_every_command_with_its_level() -> None:
    text = (REPO / "docs" / "protocol.md").read_text().split("## Commands")[1].split("\n## ")[0]
    rows = {
        cells[1].strip("` "): cells[2].strip()
        for line in text.splitlines()
        if line.startswith("| `") and len(cells := line.split("|")) > 3
    }
    for name, kind in p.COMMANDS.items():
        assert name in rows, f"docs/protocol.md has no row for {name}"
        assert rows[name] == (kind.LEVEL or "none"), name


def test_a_large_reply_is_encoded_in_batches_to_the_same_bytes() -> None:
    values: dict[str, p.Value] = {f"Main.v{n}": n * 0.5 for n in range(5_001)}
    values["Main.text"] = 'a "quoted" \u00e9'
    reply = p.ValuesReply(values, 7)
    encoded = p.encode_reply(reply)
    assert encoded == json.dumps({"ok": True, **encode(reply)}).encode()
    assert p.decode_reply(p.GetValues(), encoded) == reply


def test_watch_values_plain_or_nested_within_the_limit_pass_and_deeper_ones_are_refused() -> None:
    plain = [1, -2.5, True, "text", None] * 2_000
    message = {"cycle": 7, "revision": 1, "values": plain, "qualities": "L" * len(plain)}
    assert decode(p.WatchPublication, message).values == plain
    nested: object = 1
    for _ in range(MAX_DEPTH):
        nested = [nested]
    message["values"] = [*plain[:5], nested]
    message["qualities"] = "L" * 6
    assert decode(p.WatchPublication, message).values[5] == nested  # an array of arrays
    message["values"] = [*plain[:5], [nested]]
    with pytest.raises(Refusal) as refused:
        decode(p.WatchPublication, message)
    assert "values[5]" in refused.value.message


def _status(**where: Any) -> dict[str, Any]:
    stats = p.CycleStatistics(1, 0.1, 0.1, 0.1, 0.1, 20.0, 0.0, 0, 0)
    status = p.Status(
        "Line1", p.ResourceState.RUN, "0A1B2C3D", None, "P", 1, 20.0, stats, False, "users",
        None, [], None, **where,
    )  # fmt: skip
    data: dict[str, Any] = encode(status)
    return data


def test_the_host_of_a_status_is_optional_bounded_and_of_a_safe_set() -> None:
    host = "plc-hall1.example_site"
    data = _status(host=host, zenoh_id="3f0c2a9d1e7b4c55a1d0e8f2b6c49a17")
    decoded = p.decode_publication(p.Status, json.dumps(data).encode())
    assert (decoded.host, decoded.zenoh_id) == (host, "3f0c2a9d1e7b4c55a1d0e8f2b6c49a17")
    # a runtime before the fields: they decode as None
    older = {k: v for k, v in _status().items() if k not in ("host", "zenoh_id")}
    decoded = p.decode_publication(p.Status, json.dumps(older).encode())
    assert (decoded.host, decoded.zenoh_id) == (None, None)
    assert p.decode_publication(p.Status, json.dumps({**older, "host": "a" * 253}).encode())
    for bad in ("a" * 254, "", "-lead", "plc 1", "plc\x1b[2J", "<b>plc</b>", "plc/1", 7):
        with pytest.raises(Refusal) as refused:
            p.decode_publication(p.Status, json.dumps({**older, "host": bad}).encode())
        assert refused.value.code == "bad_reply"
    for bad_id in ("XYZ", "a" * 33, ""):
        with pytest.raises(Refusal):
            p.decode_publication(p.Status, json.dumps({**older, "zenoh_id": bad_id}).encode())
    # the runtime gives no name outside the set: None rather than an undecodable status
    assert p.safe_host("plc-1") == "plc-1"
    assert p.safe_host("plc 1") is None and p.safe_host("a" * 254) is None
