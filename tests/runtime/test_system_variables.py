"""System variables `SYS.<NAME>` (docs/language.md, section System variables): one table
for compiler and runtime, typing and write protection at compile time, generated code that
reads and writes the resource's `SystemView`, and the user's own SYS hiding the namespace."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from backend.compiler.types import elementary
from backend.engineering.check_twice import check_twice
from runtime.clock import VirtualClock
from runtime.code.code_image import CodeImage
from runtime.code.intrinsics import SystemView
from runtime.contract.artifact import Artifact
from runtime.contract.system_variables import BY_NAME, NAMESPACE, SYSTEM_VARIABLES, initial_value
from runtime.resource import Resource

EXPECTED = {
    "COLDSTART": ("BOOL", False),
    "WARMSTART": ("BOOL", False),
    "START_CYCLE": ("BOOL", False),
    "CYCLE_TIME_LAST": ("TIME", False),
    "CYCLE_TIME_MIN": ("TIME", False),
    "CYCLE_TIME_MAX": ("TIME", False),
    "CYCLE_TIME_MEAN": ("TIME", False),
    "WATCHDOG_TIME": ("TIME", False),
    "SYSTEM_TICK": ("UDINT", False),
    "FORCE_TIME_REMAINING": ("TIME", False),
    "CONFIGURATION_CRC": ("DWORD", False),
    "DATE_AND_TIME": ("DT", False),
    "FORCE_DEACTIVATION": ("BOOL", True),
    "RELOAD_DEACTIVATION": ("BOOL", True),
    "READ_ONLY_IN_RUN": ("BOOL", True),
    "EMERGENCY_STOP_1": ("BOOL", True),
    "EMERGENCY_STOP_2": ("BOOL", True),
    "EMERGENCY_STOP_3": ("BOOL", True),
    "EMERGENCY_STOP_4": ("BOOL", True),
}


def compiled(text: str) -> Artifact:
    result = compile_sources([SourceFile("t.st", text)])
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


def diagnostics(text: str) -> list[str]:
    result = compile_sources([SourceFile("t.st", text)])
    return [str(d) for d in result.diagnostics]


def loaded(text: str) -> Resource:
    """A resource on virtual time with `text` loaded and started (as `padt sim` does)."""
    resource = Resource("R", VirtualClock())
    resource.load(compiled(text))
    resource.start()
    return resource


def source_of(artifact: Artifact, pou: str) -> str:
    return next(p.source for p in artifact.pous if p.name == pou)


# ---- the table


def test_the_table_names_types_and_access() -> None:
    assert {v.name: (v.type, v.writable) for v in SYSTEM_VARIABLES} == EXPECTED
    assert list(BY_NAME) == [v.name for v in SYSTEM_VARIABLES]  # no name twice
    assert NAMESPACE == "SYS"
    for variable in SYSTEM_VARIABLES:
        assert variable.name.isupper() and variable.meaning
        assert elementary(variable.type) is not None, variable.type


def test_system_view_has_one_attribute_per_system_variable() -> None:
    fields = {f.name: f.default for f in dataclasses.fields(SystemView)}
    assert fields.pop("now_ns") == 0  # the program's time (__CURRENT_TIME) stays
    assert fields == {v.name: initial_value(v) for v in SYSTEM_VARIABLES}
    view = SystemView()
    for variable in SYSTEM_VARIABLES:  # BOOL as bool, TIME / DT / integers as int
        expected_type = bool if variable.type == "BOOL" else int
        assert type(getattr(view, variable.name)) is expected_type


# ---- compile errors


ERRORS = [
    (
        "assignment to a read-only one",
        "PROGRAM P\nVAR b : BOOL; END_VAR\nSYS.COLDSTART := TRUE;\nEND_PROGRAM",
        ["t.st:3:1: error: SYS.COLDSTART is a read-only system variable [E0306]"],
    ),
    (
        "names are case-insensitive, messages use the table's spelling",
        "PROGRAM P\nVAR END_VAR\n  sys.Cycle_Time_Last := T#1s;\nEND_PROGRAM",
        ["t.st:3:3: error: SYS.CYCLE_TIME_LAST is a read-only system variable [E0306]"],
    ),
    (
        "a bit of a read-only one",
        "PROGRAM P\nVAR END_VAR\nSYS.CONFIGURATION_CRC.3 := TRUE;\nEND_PROGRAM",
        ["t.st:3:1: error: SYS.CONFIGURATION_CRC is a read-only system variable [E0306]"],
    ),
    (
        "unknown member read",
        "PROGRAM P\nVAR b : BOOL; END_VAR\nb := SYS.FOO;\nEND_PROGRAM",
        ["t.st:3:6: error: SYS has no system variable 'FOO' [E0203]"],
    ),
    (
        "unknown member written",
        "PROGRAM P\nVAR END_VAR\nSYS.Foo := TRUE;\nEND_PROGRAM",
        ["t.st:3:1: error: SYS has no system variable 'Foo' [E0203]"],
    ),
    (
        "SYS alone in an expression",
        "PROGRAM P\nVAR b : BOOL; END_VAR\nb := SYS AND b;\nEND_PROGRAM",
        ["t.st:3:6: error: SYS holds the system variables; name one, as in SYS.COLDSTART [E0202]"],
    ),
    (
        "SYS alone as a target",
        "PROGRAM P\nVAR END_VAR\nsys := 1;\nEND_PROGRAM",
        ["t.st:3:1: error: sys holds the system variables; name one, as in sys.COLDSTART [E0202]"],
    ),
    (
        "typed as in the table",
        "PROGRAM P\nVAR i : INT; END_VAR\ni := SYS.DATE_AND_TIME;\nSYS.EMERGENCY_STOP_1 := T#1s;"
        "\nEND_PROGRAM",
        [
            "t.st:3:6: error: type mismatch: cannot assign DT to INT [E0209]",
            "t.st:4:25: error: type mismatch: cannot assign TIME to BOOL [E0209]",
        ],
    ),
    (
        "not a constant initial value",
        "PROGRAM P\nVAR b : BOOL := SYS.COLDSTART; END_VAR\nEND_PROGRAM",
        ["t.st:2:17: error: initial value of 'b' must be a constant expression [E0117]"],
    ),
    (
        "output and in-out of a function block",
        "FUNCTION_BLOCK FB\nVAR_IN_OUT io : BOOL; END_VAR\nVAR_OUTPUT o : BOOL; END_VAR\n"
        "END_FUNCTION_BLOCK\n"
        "PROGRAM P\nVAR fb : FB; END_VAR\nfb(io := SYS.WARMSTART, o => SYS.START_CYCLE);\n"
        "fb(io := SYS.EMERGENCY_STOP_1, o => SYS.EMERGENCY_STOP_2);\nEND_PROGRAM",
        [
            "t.st:7:10: error: SYS.WARMSTART is a read-only system variable [E0306]",
            "t.st:7:30: error: SYS.START_CYCLE is a read-only system variable [E0306]",
        ],
    ),
    (
        "output and in-out of a function",
        "FUNCTION F : INT\nVAR_IN_OUT io : BOOL; END_VAR\nVAR_OUTPUT o : BOOL; END_VAR\n"
        "F := 1;\nEND_FUNCTION\n"
        "PROGRAM P\nVAR i : INT; END_VAR\ni := F(io := SYS.COLDSTART, o => SYS.WARMSTART);\n"
        "i := F(io := SYS.FORCE_DEACTIVATION, o => SYS.RELOAD_DEACTIVATION);\nEND_PROGRAM",
        [
            "t.st:8:14: error: SYS.COLDSTART is a read-only system variable [E0306]",
            "t.st:8:34: error: SYS.WARMSTART is a read-only system variable [E0306]",
        ],
    ),
    (
        "in a function, a function block and an SFC action",
        "FUNCTION F : BOOL\nVAR END_VAR\nSYS.SYSTEM_TICK := 1;\nF := SYS.COLDSTART;\n"
        "END_FUNCTION\n"
        "FUNCTION_BLOCK FB\nVAR END_VAR\nSYS.WATCHDOG_TIME := T#1s;\nEND_FUNCTION_BLOCK\n"
        "PROGRAM P\nVAR END_VAR\nINITIAL_STEP S1: A(N); END_STEP\n"
        "TRANSITION FROM S1 TO S1 := SYS.NOPE; END_TRANSITION\n"
        "ACTION A: SYS.DATE_AND_TIME := DT#2024-01-01-00:00:00; END_ACTION\nEND_PROGRAM",
        [
            "t.st:3:1: error: SYS.SYSTEM_TICK is a read-only system variable [E0306]",
            "t.st:8:1: error: SYS.WATCHDOG_TIME is a read-only system variable [E0306]",
            "t.st:14:11: error: SYS.DATE_AND_TIME is a read-only system variable [E0306]",
            "t.st:13:29: error: SYS has no system variable 'NOPE' [E0203]",
        ],
    ),
]


@pytest.mark.parametrize(
    ("text", "expected"), [(t, e) for _, t, e in ERRORS], ids=[name for name, _, _ in ERRORS]
)
def test_compile_errors(text: str, expected: list[str]) -> None:
    assert sorted(diagnostics(text)) == sorted(expected)


# ---- the user's SYS wins


def test_a_local_variable_named_sys_hides_the_namespace_in_its_pou_only() -> None:
    artifact = compiled(
        """
        TYPE Flags : STRUCT COLDSTART : BOOL; END_STRUCT; END_TYPE
        PROGRAM Mine
        VAR sys : Flags; b : BOOL; END_VAR
        SYS.COLDSTART := TRUE;   (* the user's variable: writable *)
        b := SYS.COLDSTART;
        END_PROGRAM
        PROGRAM Other
        VAR b : BOOL; END_VAR
        b := SYS.COLDSTART;
        END_PROGRAM
        """
    )
    assert "s.sys.COLDSTART = True" in source_of(artifact, "Mine")
    assert "_SYS" not in source_of(artifact, "Mine")
    assert "s.b = _SYS.COLDSTART" in source_of(artifact, "Other")


def test_a_global_named_sys_hides_the_namespace() -> None:
    text = """
    VAR_GLOBAL Sys : INT; END_VAR
    PROGRAM P
    VAR i : INT; END_VAR
    i := SYS + 1;
    SYS := i;
    END_PROGRAM
    """
    assert "_G.Sys = " in source_of(compiled(text), "P")


def test_a_type_named_sys_hides_the_namespace() -> None:
    declared = """
    TYPE SYS : STRUCT COLDSTART : BOOL; END_STRUCT; END_TYPE
    PROGRAM P
    VAR v : SYS; b : BOOL; END_VAR
    v.COLDSTART := TRUE;
    b := v.COLDSTART;
    END_PROGRAM
    """
    compiled(declared)  # the user's type is usable
    hidden = declared.replace("b := v.COLDSTART;", "b := SYS.COLDSTART;")
    assert diagnostics(hidden) == ["t.st:6:10: error: 'SYS' is not declared [E0201]"]


def test_a_function_block_named_sys_hides_the_namespace() -> None:
    text = """
    FUNCTION_BLOCK Sys
    VAR_OUTPUT COLDSTART : BOOL; END_VAR
    COLDSTART := TRUE;
    END_FUNCTION_BLOCK
    PROGRAM P
    VAR fb : SYS; b : BOOL; END_VAR
    fb();
    b := fb.COLDSTART;
    END_PROGRAM
    """
    compiled(text)
    assert diagnostics(text.replace("b := fb.COLDSTART", "b := SYS.WARMSTART")) == [
        "t.st:9:10: error: 'SYS' is not declared [E0201]"
    ]


# ---- generated code: the contract with the runtime (a SystemView of our own)


def run_image(text: str, system: SystemView, cycles: int = 1) -> Any:
    """Run PROGRAM P of `text` for `cycles` calls on `system`, as the runtime's code image
    does but without a resource (whose own policy sets and reacts to the values)."""
    image = CodeImage(compiled(text), system)
    program = image.new_instance("P")
    image.register_program("P", program)
    for _ in range(cycles):
        program()
    return program


def test_generated_code_reads_and_writes_the_system_view() -> None:
    artifact = compiled(
        """
        PROGRAM P
        VAR b : BOOL; END_VAR
        b := sys.ColdStart;
        SYS.EMERGENCY_STOP_1 := b;
        END_PROGRAM
        """
    )
    source = source_of(artifact, "P")
    assert "s.b = _SYS.COLDSTART" in source
    assert "_SYS.EMERGENCY_STOP_1 = s.b" in source


def test_every_read_only_value_reaches_the_program_with_its_type() -> None:
    ms = 1_000_000
    given: dict[str, Any] = {
        "COLDSTART": True, "WARMSTART": True, "START_CYCLE": True,
        "CYCLE_TIME_LAST": 12 * ms, "CYCLE_TIME_MIN": 3 * ms, "CYCLE_TIME_MAX": 20 * ms,
        "CYCLE_TIME_MEAN": 9 * ms, "WATCHDOG_TIME": 200 * ms, "FORCE_TIME_REMAINING": 5 * ms,
        "SYSTEM_TICK": 2**32 - 1, "CONFIGURATION_CRC": 0xDEADBEEF,
        "DATE_AND_TIME": 1_717_243_200 * 1_000_000_000,  # 2024-06-01 12:00:00 UTC
    }  # fmt: skip
    assert set(given) == {v.name for v in SYSTEM_VARIABLES if not v.writable}
    program = run_image(
        """
        PROGRAM P
        VAR
          cold, warm, first : BOOL;
          last, shortest, longest, mean, watchdog, forcing : TIME;
          tick : UDINT; crc : DWORD; now : DT; late : BOOL; next_tick : UDINT;
        END_VAR
        cold := SYS.COLDSTART; warm := SYS.WARMSTART; first := SYS.START_CYCLE;
        last := SYS.CYCLE_TIME_LAST; shortest := SYS.CYCLE_TIME_MIN;
        longest := SYS.CYCLE_TIME_MAX; mean := SYS.CYCLE_TIME_MEAN;
        watchdog := SYS.WATCHDOG_TIME; forcing := SYS.FORCE_TIME_REMAINING;
        tick := SYS.SYSTEM_TICK; crc := SYS.CONFIGURATION_CRC; now := SYS.DATE_AND_TIME;
        late := SYS.DATE_AND_TIME > DT#2024-01-01-00:00:00 AND SYS.CYCLE_TIME_MAX >= T#20ms;
        next_tick := SYS.SYSTEM_TICK + 1;   (* UDINT arithmetic wraps at 2^32 *)
        END_PROGRAM
        """,
        SystemView(**given),
    )
    copies = {
        "cold": "COLDSTART", "warm": "WARMSTART", "first": "START_CYCLE",
        "last": "CYCLE_TIME_LAST", "shortest": "CYCLE_TIME_MIN", "longest": "CYCLE_TIME_MAX",
        "mean": "CYCLE_TIME_MEAN", "watchdog": "WATCHDOG_TIME", "forcing": "FORCE_TIME_REMAINING",
        "tick": "SYSTEM_TICK", "crc": "CONFIGURATION_CRC", "now": "DATE_AND_TIME",
    }  # fmt: skip
    assert {copy: getattr(program, copy) for copy in copies} == {
        copy: given[name] for copy, name in copies.items()
    }
    assert program.late is True
    assert program.next_tick == 0


def test_logic_writes_the_writable_ones() -> None:
    system = SystemView()
    program = run_image(
        """
        PROGRAM P
        VAR n : INT; seen : BOOL; END_VAR
        n := n + 1;
        SYS.EMERGENCY_STOP_1 := TRUE;
        sys.force_deactivation := n >= 2;
        Sys.Reload_Deactivation := NOT SYS.RELOAD_DEACTIVATION;
        SYS.READ_ONLY_IN_RUN := SYS.EMERGENCY_STOP_1 AND NOT SYS.COLDSTART;
        seen := SYS.EMERGENCY_STOP_1;   (* a written value reads back in the same cycle *)
        END_PROGRAM
        """,
        system,
    )
    assert system.EMERGENCY_STOP_1 is True and program.seen is True
    assert system.FORCE_DEACTIVATION is False
    assert system.RELOAD_DEACTIVATION is True
    assert system.READ_ONLY_IN_RUN is True
    assert (system.EMERGENCY_STOP_2, system.EMERGENCY_STOP_3) == (False, False)  # untouched
    program()
    assert system.FORCE_DEACTIVATION is True
    assert system.RELOAD_DEACTIVATION is False


def test_function_block_function_and_chart_use_system_variables() -> None:
    system = SystemView()
    text = """
        FUNCTION Stopped : BOOL
        VAR_INPUT which : INT; END_VAR
        CASE which OF
          1: Stopped := SYS.EMERGENCY_STOP_1;
          4: Stopped := SYS.EMERGENCY_STOP_4;
        END_CASE;
        END_FUNCTION
        FUNCTION_BLOCK Guard
        VAR_OUTPUT tripped : BOOL; END_VAR
        IF Stopped(which := 1) THEN SYS.EMERGENCY_STOP_4 := TRUE; END_IF;
        tripped := Stopped(which := 4);
        END_FUNCTION_BLOCK
        PROGRAM P
        VAR g : Guard; tripped : BOOL; END_VAR
        g();
        tripped := g.tripped;
        INITIAL_STEP Wait: END_STEP
        STEP Go: Trip(P); END_STEP
        TRANSITION FROM Wait TO Go := SYS.START_CYCLE; END_TRANSITION
        ACTION Trip: SYS.EMERGENCY_STOP_1 := TRUE; END_ACTION
        END_PROGRAM
        """
    program = run_image(text, system)  # START_CYCLE FALSE: the chart waits
    assert program.Go.X is False
    system.START_CYCLE = True
    program()  # the transition fires; Go acts from the next call
    assert program.Go.X is True
    assert system.EMERGENCY_STOP_1 is False
    system.START_CYCLE = False
    program()  # Trip (P) sets EMERGENCY_STOP_1 after the body ran
    assert system.EMERGENCY_STOP_1 is True
    assert program.tripped is False
    program()  # the FB sees EMERGENCY_STOP_1 and sets EMERGENCY_STOP_4
    assert system.EMERGENCY_STOP_4 is True
    assert program.tripped is True


# ---- on a resource (its own rules for setting and reacting to the values are not tested
# here: only that its SystemView is the one the generated code reads and writes)


def test_a_program_on_a_resource_sees_coldstart() -> None:
    resource = loaded(
        """
        PROGRAM P
        VAR cold : BOOL; END_VAR
        cold := SYS.COLDSTART;
        END_PROGRAM
        """
    )
    resource.system.COLDSTART = True  # the first cycle after a cold start
    resource.cycle()
    assert resource.variables.values()["P.cold"] is True
    resource.system.COLDSTART = False
    resource.cycle()
    assert resource.variables.values()["P.cold"] is False


def test_a_program_on_a_resource_writes_an_emergency_stop() -> None:
    resource = loaded(
        """
        PROGRAM P
        VAR END_VAR
        SYS.EMERGENCY_STOP_1 := TRUE;
        END_PROGRAM
        """
    )
    assert resource.system.EMERGENCY_STOP_1 is False
    resource.cycle()
    assert resource.system.EMERGENCY_STOP_1 is True


# ---- determinism


SOURCE = """
PROGRAM P
VAR t : TIME; stop : BOOL; END_VAR
t := SYS.CYCLE_TIME_MAX;
SYS.EMERGENCY_STOP_3 := stop OR SYS.COLDSTART;
END_PROGRAM
"""


def test_the_same_sources_give_the_same_crcs() -> None:
    first, second = compiled(SOURCE), compiled(SOURCE)
    assert first.crc == second.crc
    assert [(p.name, p.crc) for p in first.pous] == [(p.name, p.crc) for p in second.pous]
    other = compiled(SOURCE.replace("EMERGENCY_STOP_3", "EMERGENCY_STOP_2"))
    assert other.crc != first.crc  # which system variable is written is part of the code


def test_the_same_crcs_in_two_processes(tmp_path: Path) -> None:
    path = tmp_path / "sys.st"
    path.write_text(SOURCE)
    result = check_twice([path])
    assert result.ok, (result.mismatches, result.first, result.second)
