"""Located variables without a name (`AT %IX1.1 : BOOL;`) and direct addresses in
statements (`%MW10 := 42;`), traced through `padt sim` (100 ms cycles)."""

from __future__ import annotations

from pathlib import Path

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.contract.artifact import ProgramConfig
from tests.compiler.test_checks import diagnostics
from tests.conftest import sim_trace

SOURCE = """
VAR_GLOBAL
  AT %QX0.0 : BOOL;
  start AT %IX0.0 : BOOL;
END_VAR
PROGRAM Main
VAR
  AT %IX1.1 : BOOL;
  AT %MW4 : INT := 7;
  n : INT;
END_VAR
%MW10 := %MW10 + 1;
%QX0.0 := %IX0.0 AND NOT %IX1.1;
n := %MW4 + WORD_TO_INT(%MW10);
%MX20.3 := %MW10 > 2;
%MD30 := 16#FFFF_FFFF;
END_PROGRAM
"""


def test_direct_addresses_read_and_write_the_variables_located_there(tmp_path: Path) -> None:
    t = sim_trace(tmp_path, SOURCE, 4, "start=TRUE@2", "Main.%IX1.1=TRUE@3")
    # an address no declaration locates is a global of its own, typed by its size letter
    assert t["%MW10"] == [1, 2, 3, 4]
    assert t["%MX20.3"] == [False, False, True, True]
    assert t["%MD30"] == [0xFFFF_FFFF] * 4
    # %IX0.0 is the named global `start`; %IX1.1 the program's unnamed input
    assert t["%QX0.0"] == [False, True, False, False]
    assert t["Main.%MW4"] == [7] * 4
    assert t["Main.n"] == [8, 9, 10, 11]


def test_an_address_of_another_pous_variable_is_refused() -> None:
    source = (
        "FUNCTION_BLOCK Door\nVAR AT %IX0.0 : BOOL; END_VAR\nEND_FUNCTION_BLOCK\n"
        "PROGRAM Main\nVAR d : Door; run : BOOL; END_VAR\nd();\nrun := %IX0.0;\nEND_PROGRAM"
    )
    assert diagnostics(source) == [
        "t.st:7:8: error: %IX0.0 is located in a variable of another POU; declare it in a "
        "VAR_GLOBAL to use it here [E0703]"
    ]


def test_an_address_written_by_two_programs_has_two_writers() -> None:
    source = "PROGRAM A\n%QX0.0 := TRUE;\nEND_PROGRAM\nPROGRAM B\n%QX0.0 := FALSE;\nEND_PROGRAM"
    programs = [ProgramConfig(name="A", pou="A", program_id=1),
                ProgramConfig(name="B", pou="B", program_id=2)]  # fmt: skip
    assert any("[E0606]" in d and "%QX0.0" in d for d in diagnostics(source, programs))


def test_types_and_addresses_are_checked_like_names() -> None:
    source = (
        "PROGRAM P\nVAR AT %IW2 : INT; s : STRING; END_VAR\n%IW2 := s;\n%MX1.0 := 5;\nEND_PROGRAM"
    )
    assert diagnostics(source) == [
        "t.st:3:9: error: type mismatch: cannot assign STRING to INT [E0209]",
        "t.st:4:11: error: type mismatch: cannot assign ANY_INT to BOOL [E0209]",
    ]


def test_addresses_in_ignored_program_arguments_declare_nothing() -> None:
    """A configuration's program arguments are ignored (W0602), the addresses in them too."""
    source = (
        "PROGRAM G\nVAR_INPUT go : BOOL; END_VAR\nEND_PROGRAM\n"
        "CONFIGURATION C\nRESOURCE R ON CPU\nPROGRAM g : G (go := %I0.0);\n"
        "END_RESOURCE\nEND_CONFIGURATION"
    )
    result = compile_sources([SourceFile("t.st", source)])
    assert result.artifact is not None and result.artifact.globals is not None
    assert result.artifact.globals.variables == ()
    assert [d.code for d in result.diagnostics] == ["W0602"]
