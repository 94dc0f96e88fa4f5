"""Access specifiers on POUs (PUBLIC W0809, INTERNAL N0802, what does not apply E0136),
names qualified by a library's namespace or a global list (N0803) and partly located inputs
and outputs of blocks (W0810), as TwinCAT libraries write them (docs/language.md, "CODESYS
and TwinCAT extensions"); behaviour traced through `padt sim` (100 ms cycles)."""

from __future__ import annotations

from pathlib import Path

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.clock import VirtualClock
from runtime.resource import Resource
from tests.conftest import sim_trace


def diagnostics(source: str) -> list[str]:
    return [str(d) for d in compile_sources([SourceFile("t.st", source)]).diagnostics]


def codes(source: str) -> list[str]:
    return [d.code for d in compile_sources([SourceFile("t.st", source)]).diagnostics]


ACCESS = """INTERFACE INTERNAL I_Counter
METHOD Count : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK PUBLIC FINAL FB_Counter IMPLEMENTS I_Counter
VAR_OUTPUT n : INT; END_VAR
n := n + Step(1);
METHOD PUBLIC Count : INT
Count := n;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK ABSTRACT INTERNAL FB_Base
END_FUNCTION_BLOCK
FUNCTION INTERNAL Step : INT
VAR_INPUT by : INT; END_VAR
Step := by * 2;
END_FUNCTION
TYPE INTERNAL E_Mode : (Idle, Busy); END_TYPE
PROGRAM PUBLIC Main
VAR fb : FB_Counter; itf : I_Counter; seen : INT; mode : E_Mode; END_VAR
fb();
itf := fb;
seen := itf.Count();
IF seen > 2 THEN mode := E_Mode#Busy; END_IF;
END_PROGRAM
"""


def test_access_specifiers_on_pous_compile_and_run(tmp_path: Path) -> None:
    trace = sim_trace(tmp_path, ACCESS, 3)
    assert trace["Main.seen"] == [2, 4, 6]
    assert trace["Main.mode"] == [0, 1, 1]


def test_public_warns_and_internal_notes_at_the_specifier() -> None:
    found = diagnostics(ACCESS)
    assert found == [
        "t.st:1:11: note: INTERNAL: padt has no namespaces, a project is one, so 'I_Counter' "
        "is visible everywhere, as if PUBLIC [N0802]",
        "t.st:5:16: warning: PUBLIC on a FUNCTION_BLOCK is CODESYS/TwinCAT; in IEC 61131-3 "
        "'FB_Counter' is public without it [W0809]",
        "t.st:12:25: note: INTERNAL: padt has no namespaces, a project is one, so 'FB_Base' "
        "is visible everywhere, as if PUBLIC [N0802]",
        "t.st:14:10: note: INTERNAL: padt has no namespaces, a project is one, so 'Step' is "
        "visible everywhere, as if PUBLIC [N0802]",
        "t.st:18:6: note: INTERNAL: padt has no namespaces, a project is one, so 'E_Mode' is "
        "visible everywhere, as if PUBLIC [N0802]",
        "t.st:19:9: warning: PUBLIC on a PROGRAM is CODESYS/TwinCAT; in IEC 61131-3 'Main' is "
        "public without it [W0809]",
    ]


def test_final_after_the_access_specifier_still_forbids_extending() -> None:
    source = """FUNCTION_BLOCK INTERNAL FINAL Base
END_FUNCTION_BLOCK
FUNCTION_BLOCK Derived EXTENDS Base
END_FUNCTION_BLOCK
PROGRAM Main
VAR d : Derived; END_VAR
d();
END_PROGRAM
"""
    assert "E0129" in codes(source)


def test_specifiers_that_do_not_apply_are_refused() -> None:
    for header, word in [
        ("FUNCTION_BLOCK PRIVATE Fb", "PRIVATE does not apply to a FUNCTION_BLOCK ('Fb')"),
        ("FUNCTION_BLOCK PROTECTED Fb", "PROTECTED does not apply to a FUNCTION_BLOCK ('Fb')"),
        ("FUNCTION_BLOCK OVERRIDE Fb", "OVERRIDE does not apply to a FUNCTION_BLOCK ('Fb')"),
        ("FUNCTION_BLOCK PUBLIC INTERNAL Fb", "'Fb' is declared PUBLIC INTERNAL: a specifier"),
        ("FUNCTION_BLOCK FINAL ABSTRACT Fb", "'Fb' is declared FINAL ABSTRACT: a specifier"),
        ("FUNCTION_BLOCK FINAL FINAL Fb", "'Fb' is declared FINAL FINAL: a specifier"),
    ]:
        found = diagnostics(f"{header}\nEND_FUNCTION_BLOCK\n")
        assert any(word in d and "[E0136]" in d for d in found), (header, found)
    found = diagnostics("FUNCTION ABSTRACT F : INT\nF := 1;\nEND_FUNCTION\n")
    assert found == ["t.st:1:10: error: ABSTRACT does not apply to a FUNCTION ('F') [E0136]"]
    found = diagnostics("PROGRAM FINAL P\nEND_PROGRAM\n")
    assert found == ["t.st:1:9: error: FINAL does not apply to a PROGRAM ('P') [E0136]"]


def test_specifier_words_stay_names_where_no_name_follows() -> None:
    # OSCAT has a FUNCTION called OVERRIDE; a variable may be called final or internal
    source = """FUNCTION OVERRIDE : REAL
VAR_INPUT x : REAL; END_VAR
OVERRIDE := x;
END_FUNCTION
TYPE Public : INT; END_TYPE
PROGRAM Main
VAR final, internal : REAL; p : Public; END_VAR
final := OVERRIDE(1.5);
internal := final;
END_PROGRAM
"""
    result = compile_sources([SourceFile("t.st", source)])
    assert result.ok and not result.diagnostics, [str(d) for d in result.diagnostics]


QUALIFIED = """VAR_GLOBAL
  nCount : INT;
END_VAR
VAR_GLOBAL CONSTANT
  cSize : INT := 4;
END_VAR
TYPE E_Mode : (Idle, Run); END_TYPE
TYPE ST_Buffer :
STRUCT
  text : STRING(Param_Lib.cSize);
  items : ARRAY[1..GVL_Param.cSize] OF INT;
END_STRUCT
END_TYPE
INTERFACE I_Base
END_INTERFACE
INTERFACE I_Thing EXTENDS Lib.I_Base
METHOD Value : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK FB_Thing IMPLEMENTS Lib.I_Thing
METHOD PUBLIC Value : INT
Value := GVL_Main.nCount;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  t : Tc2_Standard.TON;
  thing : Lib.FB_Thing;
  mode : Lib.E_Mode := Lib.E_Mode.Idle;
  buffer : ST_Buffer;
  got, length : INT;
END_VAR
GVL_Main.nCount := GVL_Main.nCount + 1;
t(IN := TRUE, PT := T#150MS);
IF t.Q THEN mode := Lib.E_Mode.Run; END_IF;
got := thing.Value();
buffer.text := 'abc';
length := Tc2_Standard.LEN(buffer.text) + UPPER_BOUND(buffer.items, 1);
END_PROGRAM
"""


def test_names_qualified_by_a_library_or_global_list_run_as_the_names(tmp_path: Path) -> None:
    trace = sim_trace(tmp_path, QUALIFIED, 4)
    assert trace["nCount"] == [1, 2, 3, 4]
    assert trace["Main.got"] == [1, 2, 3, 4]
    assert trace["Main.length"] == [7, 7, 7, 7]
    # 100 ms cycles: the TON started at 0 ms is done in the third cycle (200 ms)
    assert trace["Main.mode"] == [0, 0, 1, 1]


def test_each_qualified_name_gets_a_note_that_its_qualifier_is_unchecked() -> None:
    found = diagnostics(QUALIFIED)
    assert all("[N0803]" in d or "[W0801]" in d for d in found), found
    assert (
        "t.st:27:7: note: 'Tc2_Standard.TON' read as 'TON': padt has no library namespaces "
        "or names of global lists, so the qualifier 'Tc2_Standard' is not checked [N0803]"
    ) in found
    assert sum("'GVL_Main.nCount' read as 'nCount'" in d for d in found) == 3
    assert sum("[N0803]" in d for d in found) == 13


def test_a_qualified_name_padt_does_not_know_is_an_error_naming_it() -> None:
    source = """INTERFACE I_Object EXTENDS __SYSTEM.IQueryInterface
END_INTERFACE
PROGRAM Main
VAR path : Tc2_System.T_MaxString; r : REAL; END_VAR
r := Tc2_System.PI;
Tc2_System.ADSLOGSTR(1, 'a', 'b');
END_PROGRAM
"""
    assert diagnostics(source) == [
        "t.st:1:11: note: '__SYSTEM.IQueryInterface' left out: padt has no __QUERYINTERFACE, "
        "and the system interface declares nothing else [N0803]",
        "t.st:4:12: error: unknown type 'Tc2_System.T_MaxString': the project declares no "
        "type 'T_MaxString', and padt has no library 'Tc2_System' [E0107]",
        "t.st:5:6: error: 'Tc2_System.PI' is not declared: the project declares no global "
        "'PI', and padt has no library 'Tc2_System' [E0201]",
        "t.st:6:12: error: 'Tc2_System.ADSLOGSTR' is not a function: the project declares no "
        "function 'ADSLOGSTR', and padt has no library 'Tc2_System' [E0411]",
    ]


def test_a_declared_qualifier_keeps_the_iec_meaning() -> None:
    # `point.x` is the member x of the variable point, even with a global x declared;
    # a global list name that a local of the same name would make ambiguous is refused
    source = """TYPE Point : STRUCT x : INT; END_STRUCT END_TYPE
VAR_GLOBAL x : INT; END_VAR
PROGRAM Main
VAR point : Point; y : INT; END_VAR
point.x := 5;
y := point.x;
END_PROGRAM
"""
    result = compile_sources([SourceFile("t.st", source)])
    assert result.ok and not result.diagnostics, [str(d) for d in result.diagnostics]
    hidden = source.replace("VAR point : Point; y : INT; END_VAR", "VAR x, y : INT; END_VAR")
    hidden = hidden.replace("y := point.x;", "y := GVL.x;").replace("point.x := 5;", "")
    assert diagnostics(hidden) == [
        "t.st:6:6: error: 'GVL.x' names the global 'x', which a variable of the same name "
        "hides here; padt has no names of global lists to reach it: rename one [E0201]"
    ]


SYSTEM_INTERFACE = """INTERFACE I_Object EXTENDS __SYSTEM.IQueryInterface
METHOD Id : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK FB_Object IMPLEMENTS I_Object, __SYSTEM.IQueryInterface
VAR calls : INT; END_VAR
METHOD PUBLIC Id : INT
calls := calls + 1;
Id := 40 + calls;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR o : FB_Object; itf : I_Object; id : INT; END_VAR
itf := o;
id := itf.Id();
END_PROGRAM
"""


def test_an_interface_extending_the_system_interface_works_as_one_extending_nothing(
    tmp_path: Path,
) -> None:
    trace = sim_trace(tmp_path, SYSTEM_INTERFACE, 3)
    assert trace["Main.id"] == [41, 42, 43]
    assert codes(SYSTEM_INTERFACE) == ["N0803", "N0803"]


def test_a_method_call_through_an_unknown_qualified_global_names_the_global() -> None:
    found = diagnostics("PROGRAM Main\nGVL_TcUnit.Runner.Run();\nEND_PROGRAM\n")
    assert found[0] == (
        "t.st:2:1: error: 'GVL_TcUnit.Runner' is not declared: the project declares no global "
        "'Runner', and padt has no library 'GVL_TcUnit' [E0201]"
    )


ANALOG = """FUNCTION_BLOCK FB_AnalogInput
VAR_INPUT iRaw AT %I* : INT; fScale : REAL := 0.5; END_VAR
VAR_OUTPUT fReal : REAL; bHigh AT %QX* : BOOL; END_VAR
fReal := INT_TO_REAL(iRaw) * fScale;
bHigh := iRaw > 10;
END_FUNCTION_BLOCK
PROGRAM Main
VAR ai : FB_AnalogInput; value : REAL; END_VAR
ai();
value := ai.fReal;
END_PROGRAM
CONFIGURATION Plant
  RESOURCE Cpu ON PLC
    TASK Cyclic (INTERVAL := T#100ms, PRIORITY := 1);
    PROGRAM Main WITH Cyclic : Main;
  END_RESOURCE
  VAR_CONFIG
    Cpu.Main.ai.iRaw AT %IW2 : INT;
    Cpu.Main.ai.bHigh AT %QX0.3 : BOOL;
  END_VAR
END_CONFIGURATION
"""


def test_a_partly_located_input_or_output_of_a_block_is_linked_per_instance(
    tmp_path: Path,
) -> None:
    # TwinCAT links a block's terminals this way (W0810); VAR_CONFIG completes it
    assert diagnostics(ANALOG) == [
        "t.st:2:11: warning: 'iRaw' AT %I* in VAR_INPUT is TwinCAT; IEC 61131-3 locates only "
        "a VAR of a program or function block partly [W0810]",
        "t.st:3:26: warning: 'bHigh' AT %QX* in VAR_OUTPUT is TwinCAT; IEC 61131-3 locates "
        "only a VAR of a program or function block partly [W0810]",
    ]
    trace = sim_trace(tmp_path, ANALOG, 3, "Main.ai.iRaw=20@2", "Main.ai.iRaw=4@3")
    assert trace["Main.value"] == [0.0, 10.0, 2.0]
    assert trace["Main.ai.bHigh"] == [False, True, False]
    result = compile_sources([SourceFile("t.st", ANALOG)])
    assert result.artifact is not None
    resource = Resource("Cpu", VirtualClock())
    resource.load(result.artifact)
    resource.start()
    resource.io.set_inputs({"Main.ai.iRaw": 30})
    resource.cycle()
    assert resource.io.outputs == {"Main.ai.bHigh": True}


def test_a_partly_located_input_of_a_function_is_still_refused() -> None:
    source = "FUNCTION F : INT\nVAR_INPUT x AT %I* : INT; END_VAR\nF := x;\nEND_FUNCTION\n"
    assert diagnostics(source) == [
        "t.st:2:11: error: 'x' AT %I* is no VAR of a program or function block, so no "
        "instance has it [E0616]"
    ]


def test_a_call_that_passes_a_located_input_overwrites_it_for_that_call() -> None:
    result = compile_sources([SourceFile("t.st", ANALOG.replace("ai();", "ai(iRaw := 3);"))])
    assert result.artifact is not None
    resource = Resource("Cpu", VirtualClock())
    resource.load(result.artifact)
    resource.start()
    resource.io.set_inputs({"Main.ai.iRaw": 30})
    resource.cycle()
    assert resource.io.outputs == {"Main.ai.bHigh": False}  # 3, not 30, is no more than 10
