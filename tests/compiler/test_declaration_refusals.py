"""Declarations padt refuses with a code of their own instead of compiling them into
something else or failing on the syntax (docs/language.md, docs/diagnostics.md):
CODESYS's implicit methods (E0715), located structure members (E0716), a PROGRAM's own
VAR_GLOBAL and VAR_ACCESS (E0717), and a location without its area (E0137)."""

from __future__ import annotations

from tests.compiler.test_references import diagnostics


def errors(source: str) -> list[str]:
    return [d for d in diagnostics(source) if "error" in d]


def test_methods_codesys_calls_by_itself_are_refused_not_ignored() -> None:
    source = """
FUNCTION_BLOCK Valve
VAR limit : INT; END_VAR
METHOD FB_INIT : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; END_VAR
limit := 80;
END_METHOD
METHOD PUBLIC fb_exit : BOOL
VAR_INPUT bInCopyCode : BOOL; END_VAR
END_METHOD
METHOD FB_Reinit : BOOL
END_METHOD
METHOD PUBLIC Init
limit := 80;
END_METHOD
END_FUNCTION_BLOCK
"""
    found = errors(source)
    assert [d.split(": error: ")[0] for d in found] == ["t.st:4:8", "t.st:8:15", "t.st:11:8"]
    assert all(d.endswith("[E0715]") for d in found)
    assert "'FB_INIT' is a method CODESYS calls by itself (when an instance is made" in found[0]


def test_a_structure_member_has_no_location() -> None:
    source = """
TYPE Frame : STRUCT
  ready AT %X3.0 : BOOL;
  count AT %B0 : BYTE;
  rest : INT;
END_STRUCT END_TYPE
"""
    assert errors(source) == [
        "t.st:3:3: error: 'ready' AT %X3.0: padt does not lay structure members out at "
        "locations; declare the member without AT [E0716]",
        "t.st:4:3: error: 'count' AT %B0: padt does not lay structure members out at "
        "locations; declare the member without AT [E0716]",
    ]


def test_a_program_declares_no_globals_or_access_paths_of_its_own() -> None:
    source = """
PROGRAM Main
VAR_GLOBAL level : INT; END_VAR
VAR_ACCESS seen : Main.x : INT READ_ONLY; END_VAR
VAR x : INT; END_VAR
x := x + 1;
END_PROGRAM
"""
    found = errors(source)
    assert [d.split(": error: ")[0] for d in found] == ["t.st:3:1", "t.st:4:1"]
    assert "VAR_GLOBAL inside a PROGRAM" in found[0] and found[0].endswith("[E0717]")
    assert "VAR_ACCESS inside a PROGRAM" in found[1] and found[1].endswith("[E0717]")


def test_a_location_names_its_area() -> None:
    source = """
VAR_GLOBAL g AT %W3 : WORD; fine AT %QW3 : WORD; END_VAR
PROGRAM Main
VAR head AT %B0 : INT; AT %X1.2 : BOOL; m AT %MB0 : BYTE; i AT %IX0.0 : BOOL; END_VAR
m := %B7;
END_PROGRAM
"""
    assert errors(source) == [
        "t.st:2:12: error: 'g' AT %W3: a location names its area, %I (input), %Q (output) or "
        "%M (memory), as in %IW3 [E0137]",
        "t.st:4:5: error: 'head' AT %B0: a location names its area, %I (input), %Q (output) "
        "or %M (memory), as in %IB0 [E0137]",
        "t.st:4:24: error: %X1.2: a location names its area, %I (input), %Q (output) or %M "
        "(memory), as in %IX1.2 [E0137]",
        "t.st:5:6: error: %B7: a location names its area, %I (input), %Q (output) or %M "
        "(memory), as in %IB7 [E0137]",
    ]
