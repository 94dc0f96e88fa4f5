"""The `[opcua]` settings of padt.toml: checked with the line of the setting and a code,
carried in the artifact exactly as the runtime needs them (backend/compiler/checks/opcua.py,
docs/opcua-settings.md)."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import pytest

from backend.compiler.pipeline import CompileResult, compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.project import compile_project, demo_project_path, load_project
from runtime.contract.artifact import load_artifact
from runtime.contract.opcua import OpcuaConfig, OpcuaDevice, OpcuaPoint, OpcuaServer

DEMO_OPCUA = """
[opcua]
port = 4850
expose = ["tankcontrol", "TANKLEVEL"]
writable = ["TankControl.highLevel", "TankControl.lowLevel"]
anonymous = true
"""


def _demo(tmp_path: Path, opcua: str) -> CompileResult:
    """The demo project with `opcua` after its padt.toml (the demo's files stay as they are)."""
    folder = tmp_path / "demo"
    shutil.copytree(demo_project_path(), folder)
    config = folder / "padt.toml"
    config.write_text(config.read_text(encoding="utf-8") + opcua, encoding="utf-8")
    return compile_project(load_project([folder]))


def test_the_demo_serves_its_program_and_a_global(tmp_path: Path) -> None:
    result = _demo(tmp_path, DEMO_OPCUA)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    server = result.artifact.opcua.server if result.artifact.opcua else None
    assert server is not None
    # paths in any case in padt.toml, as declared in the artifact, sorted
    assert server.exposed == ("TankControl", "tankLevel")
    assert server.writable == ("TankControl.highLevel", "TankControl.lowLevel")
    assert (server.host, server.port, server.anonymous, server.trust_unknown_clients) == (
        "127.0.0.1", 4850, True, False,
    )  # fmt: skip
    described = dict(server.descriptions)
    assert [path for path, _ in server.descriptions] == sorted(described)
    # the program instance: the comment before its PROGRAM, its lines stripped
    assert described["TankControl"].startswith("A tank drained by the plant and refilled")
    assert "\nthe level is what the plant measures" in described["TankControl"]
    # variables: the comment after the declaration; a block instance: that of its declaration
    assert described["TankControl.level"] == "the tank level: the plant's last good measurement"
    assert described["TankControl.refillDelay"] == "the pump rests this long before restarting"
    assert described["tankLevel"].startswith("the plant's level in litres")
    assert "TankControl.restartDelay" not in described  # no comment, no description
    assert "pumpCommand" not in described  # not exposed
    assert result.artifact.opcua is not None and result.artifact.opcua.devices == ()


def test_the_configuration_goes_through_the_json_and_back(tmp_path: Path) -> None:
    device = """
[[opcua.device]]
name = "remote"
endpoint = "opc.tcp://plc-2.local:4841/UA/Tank"
security = "sign"
user = "op"
password_file = "/etc/padt/remote.password"
mode = "read"
period_ms = 250
timeout_ms = 2000

[[opcua.device.point]]
variable = "remoteLevel"
node = "ns=2;s=Tank1.TankControl.level"
safe_value = -5

[[opcua.device.point]]
variable = "remoteName"
node = "ns=3;i=1001"
safe_value = "lost"

[[opcua.device.point]]
variable = "remoteValve"
node = "ns=1;g=09087e75-8e5e-499b-954f-f2a9603db28a"
"""
    folder = tmp_path / "demo"
    shutil.copytree(demo_project_path(), folder)
    with (folder / "tank.st").open("a", encoding="utf-8") as source:
        source.write(
            "\nVAR_GLOBAL\n  remoteLevel AT %IW10 : INT;\n  remoteName AT %IB20 : STRING[8];\n"
            "  remoteValve AT %QX5.0 : BOOL;\nEND_VAR\n"
        )
    with (folder / "padt.toml").open("a", encoding="utf-8") as config:
        config.write(DEMO_OPCUA + device)
    result = compile_project(load_project([folder]))
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    opcua = result.artifact.opcua
    assert opcua is not None and opcua.server is not None
    (remote,) = opcua.devices
    assert remote == OpcuaDevice(
        name="remote",
        endpoint="opc.tcp://plc-2.local:4841/UA/Tank",
        security="sign",
        user="op",
        password_file="/etc/padt/remote.password",
        mode="read",
        period_ms=250,
        timeout_ms=2000,
        points=(
            OpcuaPoint("remoteLevel", "%IW10", "INT", "ns=2;s=Tank1.TankControl.level", -5),
            OpcuaPoint("remoteName", "%IB20", "STRING[8]", "ns=3;i=1001", "lost"),
            OpcuaPoint(
                "remoteValve",
                "%QX5.0",
                "BOOL",
                "ns=1;g=09087e75-8e5e-499b-954f-f2a9603db28a",
                False,
            ),
        ),
    )
    loaded = load_artifact(result.artifact.to_json())  # checks the CRC
    assert loaded.opcua == opcua
    assert loaded.crc == result.artifact.crc
    assert json.loads(result.artifact.body_json())["opcua"]["devices"][0]["name"] == "remote"


def test_without_opcua_the_artifact_and_its_crc_are_as_before(tmp_path: Path) -> None:
    result = _demo(tmp_path, "")
    assert result.artifact is not None and result.artifact.opcua is None
    assert "opcua" not in json.loads(result.artifact.body_json())  # left out of the CRC
    assert load_artifact(result.artifact.to_json()).opcua is None
    # present, it is covered by the CRC
    served = replace(result.artifact, opcua=OpcuaConfig(OpcuaServer())).with_crc()
    assert served.crc != result.artifact.crc
    assert load_artifact(served.to_json()).opcua == OpcuaConfig(OpcuaServer())


Compile = Callable[..., CompileResult]


@pytest.fixture
def _compile(tmp_path: Path) -> Compile:
    """Compiles a project of `settings` after its [resource] and one source."""

    def compiled(settings: str, source: str = "PROGRAM Main\nEND_PROGRAM\n") -> CompileResult:
        folder = tmp_path / "project"
        folder.mkdir(exist_ok=True)
        config = '[resource]\nname = "R1"\n' + settings
        (folder / "padt.toml").write_text(config, encoding="utf-8")
        (folder / "main.st").write_text(source, encoding="utf-8")
        return compile_project(load_project([folder]))

    return compiled


def test_serving_by_default_and_not_for_a_client_only(_compile: Compile) -> None:
    result = _compile("[opcua]\n")
    assert result.artifact is not None and result.artifact.opcua == OpcuaConfig(OpcuaServer())
    device = '[[opcua.device]]\nname = "r"\nendpoint = "opc.tcp://10.0.0.2"\n'
    result = _compile(device)
    assert result.artifact is not None and result.artifact.opcua is not None
    assert result.artifact.opcua.server is None and len(result.artifact.opcua.devices) == 1
    result = _compile("[opcua]\nport = 4841\n" + device)  # server settings: it serves
    assert result.artifact is not None and result.artifact.opcua is not None
    assert result.artifact.opcua.server is not None
    result = _compile("[opcua]\ntrust_unknown_clients = true\n" + device)
    assert result.artifact is not None and result.artifact.opcua is not None
    assert result.artifact.opcua.server is not None
    result = _compile('[opcua]\nserve = false\nexpose = ["Main"]\n')
    assert result.artifact is not None and result.artifact.opcua == OpcuaConfig()


SOURCE = """TYPE Point : STRUCT
  x : REAL;  (* across *)
  y : REAL;
END_STRUCT END_TYPE
FUNCTION_BLOCK Valve
VAR_INPUT open : BOOL; (* opens it *) END_VAR
VAR_OUTPUT isOpen : BOOL; END_VAR
isOpen := open;
END_FUNCTION_BLOCK
VAR_GLOBAL
  gPoints : ARRAY[1..3] OF Point;  (* the way points *)
  gPointsB : INT;  (* between gPoints.x and gPoints[*].x in the order of paths *)
  gLimits : ARRAY[0..9] OF INT;
  gHome : Point;
  level AT %IW0 : INT;
  pump AT %QX0.0 : BOOL;
  flag AT %MX0.0 : BOOL;
  plain : INT;
END_VAR
VAR_GLOBAL CONSTANT
  gMax : INT := 100;  (* the most *)
END_VAR
(* the line *)
PROGRAM Main
VAR
  valves : ARRAY[1..2] OF Valve;  (* both valves *)
  inlet : Valve;
  setpoint : INT;
END_VAR
inlet(open := TRUE);
END_PROGRAM
"""


def test_descriptions_reach_into_structures_blocks_and_arrays(_compile: Compile) -> None:
    exposed = '[opcua]\nexpose = ["main", "gPoints", "gHome", "gLimits", "gMax"]\n'
    result = _compile(exposed, SOURCE)
    assert result.artifact is not None and result.artifact.opcua is not None
    server = result.artifact.opcua.server
    assert server is not None
    assert server.exposed == ("Main", "gHome", "gLimits", "gMax", "gPoints")
    assert server.descriptions == (
        ("Main", "the line"),
        ("Main.inlet.open", "opens it"),
        ("Main.valves", "both valves"),
        ("Main.valves[*].open", "opens it"),
        ("gHome.x", "across"),
        ("gMax", "the most"),
        ("gPoints", "the way points"),
        ("gPoints[*].x", "across"),
    )


def test_a_description_is_clipped(_compile: Compile) -> None:
    source = f"VAR_GLOBAL g : INT; (* {'x' * 5000} *) END_VAR\nPROGRAM Main\nEND_PROGRAM\n"
    result = _compile('[opcua]\nexpose = ["g"]\n', source)
    assert result.artifact is not None and result.artifact.opcua is not None
    assert result.artifact.opcua.server is not None
    ((path, text),) = result.artifact.opcua.server.descriptions
    assert path == "g" and len(text) == 2000 + len(" ...")


def test_members_of_structures_and_blocks_can_be_named(_compile: Compile) -> None:
    settings = (
        '[opcua]\nexpose = ["gHome.x", "Main.inlet", "Main.setpoint"]\n'
        'writable = ["main.INLET.open", "Main.setpoint"]\n'
    )
    result = _compile(settings, SOURCE)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    server = result.artifact.opcua.server if result.artifact.opcua else None
    assert server is not None
    assert server.exposed == ("Main.inlet", "Main.setpoint", "gHome.x")
    assert server.writable == ("Main.inlet.open", "Main.setpoint")


def _found(result: CompileResult, settings: str) -> set[tuple[str, str]]:
    """(code, the setting on the diagnostic's line) of each diagnostic."""
    lines = ('[resource]\nname = "R1"\n' + settings).splitlines()
    return {(d.code, lines[d.line - 1].split("=")[0].strip()) for d in result.diagnostics}


def test_every_bad_setting_is_reported_at_its_line_with_its_code(_compile: Compile) -> None:
    settings = """[opcua]
port = 0
expose = ["Main.setpoint", "gPoints[2]", "nothing"]
writable = ["gHome", "gMax", "Main.setpoint"]
colour = "blue"

[[opcua.device]]
name = "remote"
endpoint = "opc.tcp//127.0.0.1:4841"
security = "full"
user = "op"
password = "secret"
period_ms = 5

[[opcua.device.point]]
variable = "level"
node = "ns=2;x=Tank1.level"

[[opcua.device.point]]
variable = "pump"
node = "i=2258"
safe_value = true

[[opcua.device.point]]
variable = "flag"
node = "i=2259"

[[opcua.device.point]]
variable = "level"
node = "ns=2;i=7"
safe_value = 40000
"""
    result = _compile(settings, SOURCE)
    assert result.artifact is None
    assert _found(result, settings) == {
        ("E0621", "port"),
        ("E0622", "expose"),  # an array element, and a path to nothing
        ("E0623", "writable"),  # gHome is not exposed, gMax neither
        ("E0621", "colour"),
        ("E0624", "endpoint"),
        ("E0621", "security"),
        ("E0621", "user"),  # without a password_file
        ("E0621", "password"),
        ("E0621", "period_ms"),
        ("E0625", "node"),
        ("E0621", "safe_value"),  # of an output
        ("E0626", "variable"),  # %MX
    }  # the last point: its node failed first, so its variable is not yet mapped twice
    assert all(str(d).startswith("padt.toml:") for d in result.diagnostics)
    messages = " | ".join(d.message for d in result.diagnostics)
    assert "no password in the project" in messages and "password_file" in messages
    assert "an array is exposed whole" in messages
    assert "writable 'gHome' is not exposed" in messages


def _device(*points: tuple[str, str]) -> str:
    text = '[[opcua.device]]\nname = "remote"\nendpoint = "opc.tcp://127.0.0.1:4841"\n'
    for variable, node in points:
        text += f'\n[[opcua.device.point]]\nvariable = "{variable}"\nnode = "{node}"\n'
    return text


def _served(expose: list[str], writable: list[str] | None = None) -> str:
    text = f"[opcua]\nexpose = {json.dumps(expose)}\n"
    return text + (f"writable = {json.dumps(writable)}\n" if writable is not None else "")


LEVEL = _device(("level", "i=1"))
GUID = "09087E75-8E5E-499B-954F-F2A9603DB28A"

# (code, failing settings, passing settings) on SOURCE, one pair per code
EXAMPLES = [
    ("E0621", "[opcua]\nport = 70000\n", "[opcua]\nport = 4841\n"),
    ("E0621", '[opcua]\nexpose = "Main"\n', '[opcua]\nexpose = ["Main"]\n'),
    ("E0621", "[opcua]\nanonymous = 1\n", "[opcua]\nanonymous = true\n"),
    (
        "E0621",
        _device() + 'user = "op"\npassword = "secret"\n',
        _device() + 'user = "op"\npassword_file = "/etc/padt/remote.password"\n',
    ),
    (
        "E0621",
        _device() + 'user = "op"\npassword_file = "remote.password"\n',
        _device() + 'user = "op"\npassword_file = "/run/secrets/remote"\n',
    ),
    ("E0621", _device() + "timeout_ms = 0\n", _device() + "timeout_ms = 60000\n"),
    ("E0621", _device() + 'mode = "poll"\n', _device() + 'mode = "read"\n'),
    (
        "E0621",
        _device() + _device().replace("remote", "REMOTE", 1),
        _device() + _device().replace("remote", "other", 1),
    ),
    ("E0621", LEVEL + "safe_value = 1.5\n", LEVEL + "safe_value = -1\n"),
    ("E0622", _served(["Main.inlet.closed"]), _served(["Main.inlet.open"])),
    ("E0622", _served(["gLimits[3]"]), _served(["gLimits"])),
    ("E0622", _served(["Main"], ["Main.x"]), _served(["Main"], ["Main"])),
    ("E0623", _served(["gHome.x"], ["gHome"]), _served(["gHome"], ["gHome.y"])),
    ("E0623", _served(["gMax"], ["gMax"]), _served(["gMax"])),
    ("E0624", _device().replace("opc.tcp://", "opc.https://"), _device()),
    ("E0624", _device().replace(":4841", ":65536"), _device().replace(":4841", ":65535")),
    ("E0624", _device().replace(":4841", ":4841/a b"), _device().replace(":4841", ":4841/a_b")),
    ("E0624", _device().replace("127.0.0.1", ""), _device().replace("127.0.0.1", "[::1]")),
    ("E0625", _device(("level", "ns=2;s=")), _device(("level", "ns=2;s=Tank 1.level"))),
    ("E0625", _device(("level", "s=Tank1.level")), _device(("level", "i=2258"))),
    ("E0625", _device(("level", "ns=70000;i=1")), _device(("level", "ns=65535;i=1"))),
    ("E0625", _device(("level", "ns=1;i=4294967296")), _device(("level", "ns=1;i=4294967295"))),
    ("E0625", _device(("level", "ns=1;g=1234")), _device(("level", f"ns=1;g={GUID}"))),
    ("E0625", _device(("level", "ns=1;b=no base64!")), _device(("level", "ns=1;b=M/RbKBsR"))),
    ("E0626", _device(("plain", "i=1")), _device(("level", "i=1"))),
    ("E0626", _device(("flag", "i=1")), _device(("pump", "i=1"))),
    ("E0626", _device(("gHome", "i=1")), _device(("level", "i=1"))),
    (
        "E0627",
        _device(("level", "i=1"), ("LEVEL", "i=2")),
        _device(("level", "i=1"), ("pump", "i=2")),
    ),
]  # fmt: skip


@pytest.mark.parametrize(("code", "failing", "passing"), EXAMPLES)
def test_each_code_fails_and_passes(
    _compile: Compile, code: str, failing: str, passing: str
) -> None:
    failed = _compile(failing, SOURCE)
    assert failed.artifact is None and code in [d.code for d in failed.diagnostics], [
        str(d) for d in failed.diagnostics
    ]
    passed = _compile(passing, SOURCE)
    assert passed.artifact is not None, [str(d) for d in passed.diagnostics]


def test_a_variable_mapped_by_modbus_is_not_mapped_again(_compile: Compile) -> None:
    modbus = (
        '[[modbus.device]]\nname = "plant"\nhost = "127.0.0.1"\nport = 5021\n\n'
        '[[modbus.device.point]]\nvariable = "level"\narea = "input_register"\naddress = 0\n\n'
    )
    result = _compile(modbus + _device(("Level", "i=1")), SOURCE)
    assert [(d.code, d.message) for d in result.diagnostics] == [
        (
            "E0627",
            "'level' (%IW0) of OPC UA device 'remote': already mapped by Modbus device 'plant'",
        )
    ]


def test_compile_sources_takes_the_table_as_read() -> None:
    source = [SourceFile("main.st", SOURCE)]
    result = compile_sources(source, opcua={"expose": ["Main.setpoint"]})
    assert result.artifact is not None and result.artifact.opcua is not None
    assert result.artifact.opcua.server == OpcuaServer(exposed=("Main.setpoint",))
    result = compile_sources(source, opcua=["not", "a", "table"])
    assert [d.code for d in result.diagnostics] == ["E0621"]
    assert compile_sources(source).artifact.opcua is None  # type: ignore[union-attr]


def test_a_comment_is_a_declarations_own_or_none(_compile: Compile) -> None:
    source = (
        "VAR_GLOBAL\n  a : STRING := '(* no comment *)';\n  b : INT; (* bee *)\n  c : INT;\n"
        "  (* see\n     two lines *)\n  d : INT;\nEND_VAR\nPROGRAM Main\nEND_PROGRAM\n"
    )
    result = _compile('[opcua]\nexpose = ["a", "b", "c", "d"]\n', source)
    assert result.artifact is not None and result.artifact.opcua is not None
    assert result.artifact.opcua.server is not None
    # the comment after b's declaration is b's, not c's
    assert result.artifact.opcua.server.descriptions == (("b", "bee"), ("d", "see\ntwo lines"))
