"""The `[modbus]` settings of padt.toml: checked with the line of the setting and a code,
carried in the artifact exactly as the runtime needs them."""

from __future__ import annotations

from pathlib import Path

from backend.engineering.project import compile_project, load_project
from runtime.contract.artifact import load_artifact

SOURCE = """VAR_GLOBAL
  level AT %IW0 : INT;
  flow AT %ID1 : REAL;
  pump AT %QX0.0 : BOOL;
  running AT %IX0.1 : BOOL;
  setpoint AT %MW3 : INT;
  gain AT %MD1 : REAL;
  speed AT %QW2 : UINT;
END_VAR
PROGRAM Main
pump := level < setpoint;
END_PROGRAM
"""

SETTINGS = """[resource]
name = "R1"

[modbus]
port = 5030
writable = ["%MW3", "%QX0.0"]

[[modbus.device]]
name = "plant"
host = "127.0.0.1"
port = 5031
period_ms = 50
timeout_ms = 300

[[modbus.device.point]]
variable = "level"
area = "input_register"
address = 0
safe_value = -1

[[modbus.device.point]]
variable = "flow"
area = "holding_register"
address = 2
word_order = "little"

[[modbus.device.point]]
variable = "pump"
area = "coil"
address = 0
"""


def _compile(tmp_path: Path, settings: str, source: str = SOURCE):
    (tmp_path / "padt.toml").write_text(settings)
    (tmp_path / "main.st").write_text(source)
    return compile_project(load_project([tmp_path]))


def test_the_served_map_is_openplcs_and_devices_are_carried(tmp_path: Path) -> None:
    result = _compile(tmp_path, SETTINGS)
    assert result.artifact is not None, result.diagnostics
    modbus = load_artifact(result.artifact.to_json()).modbus  # through the JSON and back
    assert (modbus.serve, modbus.host, modbus.port) == (True, "127.0.0.1", 5030)
    served = {p.location: (p.area, p.address, p.writable) for p in modbus.served}
    assert served == {
        "%IX0.1": ("discrete_input", 1, False),
        "%QX0.0": ("coil", 0, True),
        "%IW0": ("input_register", 0, False),
        "%QW2": ("holding_register", 2, False),
        "%MW3": ("holding_register", 1027, True),
        "%MD1": ("holding_register", 2050, False),
    }  # %ID1 has no place in the default map
    (plant,) = modbus.devices
    assert (plant.name, plant.port, plant.unit_id, plant.period_ms, plant.timeout_ms) == (
        "plant", 5031, 1, 50, 300,
    )  # fmt: skip
    points = {p.variable: p for p in plant.points}
    assert points["level"].safe_value == -1
    assert (points["flow"].type, points["flow"].word_order, points["flow"].count) == (
        "REAL", "little", 2,
    )  # fmt: skip


def test_a_project_without_located_variables_serves_nothing(tmp_path: Path) -> None:
    result = _compile(tmp_path, '[resource]\nname = "R1"\n', "PROGRAM Main\nEND_PROGRAM\n")
    assert result.artifact is not None
    assert not result.artifact.modbus.serve and result.artifact.modbus.devices == ()


def test_serving_can_be_turned_off(tmp_path: Path) -> None:
    result = _compile(tmp_path, '[resource]\nname = "R1"\n[modbus]\nserve = false\n')
    assert result.artifact is not None
    assert not result.artifact.modbus.serve and result.artifact.modbus.served == ()


def test_every_bad_setting_is_reported_at_its_line_with_its_code(tmp_path: Path) -> None:
    bad = (
        SETTINGS.replace("port = 5031", "port = 5031\nretries = 3")
        .replace('area = "coil"', 'area = "discrete_input"')
        .replace('word_order = "little"', 'word_order = "middle"')
        .replace('["%MW3", "%QX0.0"]', '["%MW3", "%IW0"]')
        .replace("safe_value = -1", "safe_value = 40000")
    )
    result = _compile(tmp_path, bad)
    assert result.artifact is None
    lines = bad.splitlines()
    found = {(d.code, lines[d.line - 1].split("=")[0].strip()) for d in result.diagnostics}
    assert found == {
        ("E0612", "retries"),
        ("E0612", "word_order"),
        ("E0612", "safe_value"),
        ("E0613", "writable"),
        ("E0613", "area"),
    }
    assert all(str(d).startswith("padt.toml:") for d in result.diagnostics)


def _point(variable: str, area: str, address: int) -> str:
    entry = f'variable = "{variable}"\narea = "{area}"\naddress = {address}\n'
    return "\n[[modbus.device.point]]\n" + entry


def test_overlapping_points_and_unfit_types(tmp_path: Path) -> None:
    bad = SETTINGS + _point("running", "holding_register", 3)
    result = _compile(tmp_path, bad)
    codes = sorted(d.code for d in result.diagnostics)
    assert codes == ["E0614"]  # a BOOL on a register
    bad = SETTINGS + _point("running", "discrete_input", 0) + _point("level", "input_register", 5)
    result = _compile(tmp_path, bad)
    assert sorted(d.code for d in result.diagnostics) == ["E0615"]  # level delivered twice
