"""CODESYS's object orientation through `padt import`: methods, properties, EXTENDS,
IMPLEMENTS and interfaces, which CODESYS exports in <addData>, become ST that compiles and
runs (fixtures written for these tests in the shape CODESYS exports)."""

from __future__ import annotations

import shutil
from pathlib import Path

from backend.engineering.plcopen.importer import import_plcopen
from backend.engineering.plcopen.reader import read_project
from backend.engineering.plcopen.st_text import interface_text
from backend.engineering.plcopen.xml_tree import parse_xml
from tests.conftest import padt
from tests.engineering.plcopen.test_plcopen_import import FIXTURES, imported, trace

PUMP_PROPERTY = """PROPERTY PUBLIC Level : INT
GET
VAR
    scale : INT := 10;
END_VAR
Level := speed * scale;
END_GET
SET
speed := Level;
END_SET
END_PROPERTY"""


def test_methods_properties_and_inheritance_are_written_as_st(tmp_path: Path) -> None:
    folder, code, stderr = imported(tmp_path, "oop")
    assert code == 0 and stderr == ""
    assert sorted(p.name for p in folder.iterdir()) == [
        "FB_FastPump.st", "FB_Pump.st", "I_Device.st", "PLC_PRG.st", "padt.toml",
    ]  # fmt: skip
    pump = (folder / "FB_Pump.st").read_text()
    assert pump.startswith("FUNCTION_BLOCK FB_Pump IMPLEMENTS I_Device\n")
    # CODESYS names no access for Start (its default, PUBLIC): written, since IEC's is PROTECTED
    assert "METHOD PUBLIC Start : BOOL\nVAR_INPUT\n    target : INT;\nEND_VAR\n" in pump
    assert "METHOD PRIVATE Clamp : INT\n" in pump  # <AccessModifiers Private="true"/>
    assert PUMP_PROPERTY in pump  # GET first, though CODESYS writes the SET first
    # the methods and the property before the body, as IEC orders them
    assert pump.index("END_PROPERTY") < pump.index("calls := calls + 1;")
    assert pump.endswith("ACTION A_Reset:\ncalls := 0;\nEND_ACTION\nEND_FUNCTION_BLOCK\n")
    assert (
        (folder / "FB_FastPump.st")
        .read_text()
        .startswith("FUNCTION_BLOCK FB_FastPump EXTENDS FB_Pump\n")
    )
    assert (folder / "I_Device.st").read_text() == (
        "INTERFACE I_Device\nMETHOD Start : BOOL\nVAR_INPUT\n    target : INT;\nEND_VAR\n"
        "END_METHOD\nPROPERTY Level : INT\nGET\nEND_GET\nSET\nEND_SET\nEND_PROPERTY\n"
        "END_INTERFACE\n"
    )
    assert "METHOD PUBLIC Twice : INT" in (folder / "PLC_PRG.st").read_text()
    compiled = padt("compile", str(folder))
    assert compiled.returncode == 0, compiled.stdout + compiled.stderr


def test_calls_through_the_interface_dispatch_and_the_override_calls_super(
    tmp_path: Path,
) -> None:
    """PLC_PRG calls Start and reads Level through an I_Device that refers to the slow
    pump in odd cycles and to the fast one (whose Start doubles the target and calls
    SUPER^.Start) in even ones; cycle 4 writes the property through the interface, cycle 3
    calls the slow pump's action."""
    folder, _, _ = imported(tmp_path, "oop")
    names = [
        "PLC_PRG.device", "PLC_PRG.running", "PLC_PRG.level", "PLC_PRG.slow.speed",
        "PLC_PRG.fast.speed", "PLC_PRG.fast.boosts", "PLC_PRG.fast.calls",
        "PLC_PRG.slow.starts", "PLC_PRG.doubled", "PLC_PRG.slow.calls",
    ]  # fmt: skip
    values = trace(folder, 4, names)
    assert values["PLC_PRG.device"] == ["PLC_PRG.slow", "PLC_PRG.fast"] * 2
    assert values["PLC_PRG.running"] == [True] * 4
    # slow: Start(10), Start(30); fast: Start(20) -> 40, Start(40) -> 80, clamped to 50
    assert values["PLC_PRG.slow.speed"] == [10, 10, 30, 30]
    assert values["PLC_PRG.fast.speed"] == [0, 40, 40, 7]  # cycle 4: device.Level := 7
    assert values["PLC_PRG.level"] == [100, 400, 300, 500]  # the GET: speed * 10
    assert values["PLC_PRG.fast.boosts"] == [0, 1, 1, 2]
    assert values["PLC_PRG.slow.starts"] == [1, 1, 2, 2]  # the inherited variable
    assert values["PLC_PRG.fast.calls"] == [1, 2, 3, 4]  # SUPER^() runs the base's body
    assert values["PLC_PRG.doubled"] == [2, 4, 6, 8]  # a method of the PROGRAM
    assert values["PLC_PRG.slow.calls"] == [1, 2, 1, 2]  # its action A_Reset in cycle 3


def test_the_same_file_gives_the_same_bytes(tmp_path: Path) -> None:
    first, second = tmp_path / "first", tmp_path / "elsewhere" / "second"
    import_plcopen(FIXTURES / "oop.xml", first)
    shutil.copy(FIXTURES / "oop.xml", tmp_path / "oop.xml")  # the name is in padt.toml
    import_plcopen(tmp_path / "oop.xml", second)
    names = sorted(p.name for p in first.iterdir())
    assert names == sorted(p.name for p in second.iterdir())
    for name in names:
        assert (first / name).read_bytes() == (second / name).read_bytes(), name


def test_a_method_or_accessor_not_in_st_is_named_and_its_block_left_out(tmp_path: Path) -> None:
    folder, code, stderr = imported(tmp_path, "graphical_method")
    assert code == 1
    assert stderr.splitlines() == [
        f"{FIXTURES / 'graphical_method.xml'}:17:7: error: 2 POUs not imported: FB_Drawn "
        "(method Reset in FBD, which padt takes as the body of a POU or an action only), FB_Listed "
        "(property Count GET in IL); IL is deprecated in IEC 61131-3 edition 3, and padt does "
        "not compile it [P0006]"
    ]
    toml = (folder / "padt.toml").read_text()
    assert (
        "#   FB_Drawn: method Reset in FBD, which padt takes as the body of a POU or an "
        "action only\n"
        "#   FB_Listed: property Count GET in IL\n"
    ) in toml
    assert sorted(p.name for p in folder.iterdir()) == ["FB_Text.st", "padt.toml"]
    assert "METHOD PUBLIC Clear\nz := 0;\nEND_METHOD" in (folder / "FB_Text.st").read_text()


def test_access_modifiers_and_abstract_methods(tmp_path: Path) -> None:
    """Every access CODESYS marks is written as it is; an ABSTRACT method has no body."""
    text = (FIXTURES / "oop.xml").read_text()
    text = text.replace(
        '<AccessModifiers Private="true" />', '<AccessModifiers Protected="true" Final="true" />'
    ).replace("<AccessModifiers />", '<AccessModifiers Internal="true" />')
    (tmp_path / "marked.xml").write_text(text)
    import_plcopen(tmp_path / "marked.xml", tmp_path / "marked")
    pump = (tmp_path / "marked" / "FB_Pump.st").read_text()
    assert "METHOD PROTECTED FINAL Clamp : INT\n" in pump
    assert "PROPERTY INTERNAL Level : INT\n" in pump
    abstract = text.replace(
        '<AccessModifiers Protected="true" Final="true" />', '<AccessModifiers Abstract="true" />'
    )
    project = read_project(parse_xml(abstract.encode()))
    clamp = next(m for p in project.pous for m in p.methods if m.name == "Clamp")
    assert (clamp.access, clamp.modifiers, clamp.body) == ("PUBLIC", ("ABSTRACT",), None)


def test_an_interface_that_extends_others() -> None:
    """CODESYS's <Inheritance> in an interface's <addData>, read as in a POU's."""
    xml = b"""<project xmlns="http://www.plcopen.org/xml/tc6_0200"><types><pous/></types>
<addData><data name="http://www.3s-software.com/plcopenxml/interface">
  <Interface name="I_Valve">
    <Methods><Method name="Open"><interface/><addData/></Method></Methods>
    <addData><data name="http://www.3s-software.com/plcopenxml/pouinheritance">
      <Inheritance><Extends>I_Device, I_Named</Extends></Inheritance>
    </data></addData>
  </Interface>
</data></addData></project>"""
    (valve,) = read_project(parse_xml(xml)).interfaces
    assert interface_text(valve) == (
        "INTERFACE I_Valve EXTENDS I_Device, I_Named\nMETHOD Open\nEND_METHOD\nEND_INTERFACE\n"
    )
