"""The native tier in a running resource: the same values as the Python tier after every
cycle, the same faults at the same ST lines, the watchdog, time slices, reloads, and a
variable of a wrong type caught instead of crashing the process. Real C compiles (gcc),
real resources on virtual clocks."""

from __future__ import annotations

import gc
import time

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime import reload_switch
from runtime.clock import VirtualClock
from runtime.code.native.tier import NativeTier
from runtime.commands import HANDLERS
from runtime.contract import protocol as p
from runtime.contract.artifact import ProgramConfig, ResourceConfig
from runtime.contract.protocol import ResourceState
from runtime.resource import Resource
from tests.bench.bench_language import thousand_statements
from tests.support.native_runs import advance, compiled, program_error, running, side_by_side
from tests.support.resource_harness import compiled as harness_artifact
from tests.support.resource_harness import harness

CONSTRUCTS = """
VAR_GLOBAL gCount : DINT; gFlag : BOOL; gWords : ARRAY[0..3] OF WORD; END_VAR
FUNCTION_BLOCK Counter
VAR_INPUT up : BOOL; END_VAR
VAR_OUTPUT n : UINT; END_VAR
VAR edge : R_TRIG; c : CTU; fall : F_TRIG; pulse : TP; off : TOF; END_VAR
edge(CLK := up);
fall(CLK := up);
IF edge.Q THEN n := n + 1; END_IF;
c(CU := up, PV := 3, R := fall.Q AND n > 5);
pulse(IN := up, PT := T#250ms);
off(IN := up, PT := T#150ms);
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  i, j, k : INT; d : DINT := -7; u : UINT; w : WORD := 16#0F0F; b : BOOL; t : TIME;
  l : LINT := 9000000000; si : SINT; by : BYTE;
  arr : ARRAY[0..9] OF DINT; grid : ARRAY[1..3, 1..4] OF INT; cnt : Counter;
  cnts : ARRAY[1..2] OF Counter; delay : TON; n : INT;
END_VAR
n := n + 1;
CASE n MOD 7 OF
  1: j := 2;
  2..4, 6: j := j * 3 - 1;
ELSE j := -j;
END_CASE;
i := 0;
WHILE i < 10 DO i := i + 1; IF i = n MOD 9 THEN EXIT; END_IF; END_WHILE;
REPEAT j := j - 1; UNTIL j < 0 END_REPEAT;
FOR k := 10 TO 1 BY -3 DO arr[k MOD 10] := arr[k MOD 10] + k * d; END_FOR;
FOR k := 1 TO 4 DO
  IF k = 2 THEN CONTINUE; END_IF;
  grid[1 + n MOD 3, k] := grid[1 + n MOD 3, k] + k * n;
END_FOR;
d := d / 3 + d MOD 7 - 1000 * n;
u := u - 1;
w := (w XOR 16#FF00) OR SHL(w, 2) AND SHR(w, 1);
si := si + 100;
by := by + 77;
l := l * 3 + d;
gCount := gCount + n;
gFlag := NOT gFlag;
gWords[n MOD 4] := w;
cnt(up := gFlag);
cnts[1 + n MOD 2](up := n MOD 3 = 0);
delay(IN := n MOD 10 < 6, PT := T#300ms);
t := t + T#10ms - delay.ET;
b := i > j AND j <> 0 OR cnt.n > 2 XOR delay.Q;
k := MAX(i, j, -3) - MIN(si, ABS(j)) + ABS(si);
END_PROGRAM
"""


def test_the_constructs_of_control_code_run_as_c_with_the_python_values(
    native_tier: NativeTier,
) -> None:
    pair = side_by_side(CONSTRUCTS, native_tier)
    assert set(pair.report.bodies) >= {"Main", "Counter", "TON", "TP", "TOF", "CTU", "R_TRIG"}
    pair.cycle_and_compare(40)


def test_the_generated_benchmark_program_runs_as_c_with_the_python_values(
    native_tier: NativeTier,
) -> None:
    pair = side_by_side(thousand_statements(count=200), native_tier)
    assert pair.report.bodies == ("Bench", "TON") and not pair.report.left
    pair.cycle_and_compare(30)


def test_a_fault_stops_both_tiers_in_the_same_cycle_at_the_same_st_line(
    native_tier: NativeTier,
) -> None:
    text = """
PROGRAM Main
VAR n : INT; arr : ARRAY[1..5] OF INT; q : DINT; END_VAR
n := n + 1;
q := 100 / (4 - n);
arr[n] := n;
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert pair.report.bodies == ("Main",)
    pair.cycle_and_compare(3)  # n = 4 in the fourth cycle: division by zero
    assert "division by zero in POU Main (prog.st:5)" in pair.fault_of_the_next_cycle()

    index = text.replace("q := 100 / (4 - n);", "")
    pair = side_by_side(index, native_tier)
    pair.cycle_and_compare(6)  # arr[6]: out of bounds in the sixth cycle
    assert "in POU Main (prog.st:6)" in program_error(pair.native)


def test_faults_in_an_elsif_test_and_under_an_else_name_their_st_lines_on_both_tiers(
    native_tier: NativeTier,
) -> None:
    """The C numbers its statements as the printer numbers the lines of the Python: an
    ELSIF's test and the statements under an ELSE (no line of their own in C) too."""
    text = """
PROGRAM Main
VAR n, m : INT; q : DINT; arr : ARRAY[1..3] OF INT; END_VAR
n := n + 1;
IF n = 100 THEN
  q := 1;
ELSIF 10 / (3 - n) > 0 THEN
  q := 2;
ELSE
  FOR m := 1 TO 3 DO
    arr[m + n - 5] := m;
  END_FOR;
END_IF;
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert pair.report.bodies == ("Main",)
    pair.cycle_and_compare(3)  # n = 3 in the third cycle: division by zero in the ELSIF
    # the compiler gives an ELSIF's test the line of its IF (the generated line is the
    # `elif`'s, the line after the first branch's)
    assert "division by zero in POU Main (prog.st:5)" in program_error(pair.native)
    assert program_error(pair.python) == program_error(pair.native)

    under_else = text.replace("10 / (3 - n) > 0", "n < 4")
    pair = side_by_side(under_else, native_tier)
    pair.cycle_and_compare(4)  # n = 4: arr[0], out of bounds under the ELSE
    assert "in POU Main (prog.st:11)" in program_error(pair.native)
    assert program_error(pair.python) == program_error(pair.native)


def test_the_watchdog_ends_an_endless_loop_of_native_code(native_tier: NativeTier) -> None:
    text = """
PROGRAM Main
VAR n : DINT; END_VAR
WHILE TRUE DO n := n + 1; END_WHILE;
END_PROGRAM
"""
    config = ResourceConfig(name="R", watchdog_ms=200, safety_time_ms=400)
    result = compile_sources([SourceFile("prog.st", text)], resource=config)
    assert result.artifact is not None
    resource = running(result.artifact, native_tier)
    report = resource.variables.code.native if resource.variables.code else None
    assert report is not None and report.bodies == ("Main",)
    started = time.monotonic()
    resource.cycle()
    assert time.monotonic() - started < 30
    assert resource.state == ResourceState.ERROR_STOP
    assert "watchdog" in (resource.error or "").lower()


def test_a_sliced_program_suspends_and_resumes_inside_native_code(
    native_tier: NativeTier,
) -> None:
    text = """
PROGRAM Slow
VAR i, k : DINT; total : DINT; rounds : INT; END_VAR
FOR i := 1 TO 300 DO
  FOR k := 1 TO 3 DO total := total + i * k; END_FOR;
END_FOR;
rounds := rounds + 1;
END_PROGRAM
"""
    programs = [
        ProgramConfig(name="Slow", pou="Slow", program_id=1, max_duration_us=500, max_cycles=10)
    ]
    pair = side_by_side(text, native_tier, programs)
    assert pair.report.bodies == ("Slow",)
    pair.cycle_and_compare(40)
    assert 0 < pair.native.variables.values()["Slow.rounds"] < 40  # it did span cycles

    # the inner loop in a FUNCTION (its body C too, function_body.py): suspended inside it
    called = text.replace(
        "FOR k := 1 TO 3 DO total := total + i * k; END_FOR;", "total := total + Sum3(i);"
    )
    function = (
        "FUNCTION Sum3 : DINT\nVAR_INPUT i : DINT; END_VAR\nVAR k : DINT; END_VAR\n"
        "FOR k := 1 TO 3 DO Sum3 := Sum3 + i * k; END_FOR;\nEND_FUNCTION\n"
    )
    pair = side_by_side(function + called, native_tier, programs)
    assert pair.report.bodies == ("Slow", "Sum3")
    pair.cycle_and_compare(40)
    assert 0 < pair.native.variables.values()["Slow.rounds"] < 40


def test_a_breakpoint_armed_mid_cycle_stops_once_the_values_are_back_on_objects(
    native_tier: NativeTier,
) -> None:
    text = """
PROGRAM Slow
VAR i : DINT; total : DINT; rounds : INT; END_VAR
FOR i := 1 TO 900 DO total := total + i; END_FOR;
rounds := rounds + 1;
END_PROGRAM
"""
    programs = [
        ProgramConfig(name="Slow", pou="Slow", program_id=1, max_duration_us=500, max_cycles=10)
    ]
    config = ResourceConfig(name="R", watchdog_ms=5_000, safety_operation=False)
    built = compile_sources([SourceFile("prog.st", text)], resource=config, programs=programs)
    assert built.artifact is not None
    resource = running(built.artifact, native_tier)
    assert resource.variables.image is not None
    advance(resource)
    assert resource.programs[0].in_progress  # suspended in its loop, in the image
    answer = HANDLERS[p.DebugSet](resource, p.DebugSet("prog.st", [p.BreakpointSpec(5)]))
    assert answer.debug.breakpoints[0].verified
    assert resource.variables.image is not None  # a program cycle holds its instances
    for _ in range(4):  # the cycle ends; the values go back to objects; the next one stops
        advance(resource)
        resource.tier_up()
    assert HANDLERS[p.DebugGet](resource, p.DebugGet()).debug.paused is not None
    assert resource.variables.image is None
    HANDLERS[p.DebugClear](resource, p.DebugClear())
    resource.stop()


# a reference keeps a configuration on objects, its bodies C on their slots (image_plan.py):
# in an image no variable can hold a value of another type (its view refuses it)
ON_SLOTS = "VAR_GLOBAL keep_on_slots : REF_TO INT; END_VAR\n"


def test_a_variable_that_holds_a_wrong_type_is_a_fault_not_a_crash(
    native_tier: NativeTier,
) -> None:
    text = ON_SLOTS + "PROGRAM Main\nVAR n : INT; m : INT; END_VAR\nm := n + 1;\nEND_PROGRAM\n"
    resource = running(compiled(text), native_tier)
    resource.programs[0].instance.n = "not an INT"  # what no checked writer would store
    resource.cycle()
    error = program_error(resource)
    assert "another type" in error and "prog.st:4" in error


PLANT = """
VAR_GLOBAL total : DINT; flags : ARRAY[0..3] OF BOOL; END_VAR
FUNCTION_BLOCK Counter
VAR_INPUT go : BOOL; END_VAR
VAR count : INT; delay : TON; edge : R_TRIG; END_VAR
delay(IN := go, PT := T#1s);
edge(CLK := count > 2);
IF go THEN count := count + 1; END_IF;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Small
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT y : INT; END_VAR
y := x * 2;
END_FUNCTION_BLOCK
PROGRAM Main
VAR c : Counter; cs : ARRAY[1..2] OF Counter; s : Small; n : INT; END_VAR
n := n + 1;
c(go := TRUE); cs[2](go := n > 1); s(x := n);
total := total + s.y;
flags[n MOD 4] := n > 2;
END_PROGRAM
"""
ONE_POU = PLANT.replace("y := x * 2;", "y := x * 3;")
EVERYTHING = ONE_POU.replace("count : INT;", "count : INT; extra : INT;").replace(
    "n : INT; END_VAR\nn :=", "n : INT; added : INT := 7; END_VAR\nn :="
)


MIGRATED = ONE_POU.replace("VAR count : INT;", "VAR count : DINT;")  # a type changes


def test_a_reload_carries_every_value_and_runs_as_c_from_its_first_cycle(
    native_tier: NativeTier,
) -> None:
    """A reload of one POU's body, of new variables, and of a type that changes (the value
    migrated): the values adopted from native memory are the Python tier's, and go back
    into native memory for the cycles after."""
    for text in (ONE_POU, EVERYTHING, MIGRATED):
        python, native = harness(PLANT), harness(PLANT, native=native_tier)
        python.cycle(6)
        native.cycle(6)
        for h in (python, native):
            job = reload_switch.begin(h.resource, harness_artifact(text), {})
            job.prepare()
            assert job.failure is None, job.failure
            reload_switch.finish(h.resource, job)
            del job  # done with, as the cycle driver is: the values may go back
            h.resource.tier_up()  # between two cycles, as the cycle driver does
        code = native.resource.variables.code
        assert code is not None and code.native is not None
        assert set(code.native.bodies) == {"Main", "Counter", "Small", "TON", "R_TRIG"}
        assert native.resource.variables.values() == python.resource.variables.values()
        for _ in range(5):
            assert native.cycle() == python.cycle()
            assert native.resource.variables.image is not None  # back in native memory
        assert native.value("Main.s.y") == 3 * native.value("Main.n")


def test_the_bodies_of_a_load_come_in_between_two_cycles_with_an_event(
    fresh_tier: NativeTier,
) -> None:
    resource = running(compiled(PLANT), None)  # started as Python
    resource.native = fresh_tier
    resource.stop()
    resource.cold_start()  # a new image: its native bodies are made on a thread
    resource.start()
    deadline = time.monotonic() + 120
    while resource.variables.code and resource.variables.code.native is None:
        assert time.monotonic() < deadline
        resource.cycle()
        resource.tier_up()
        time.sleep(0.01)
    events = [e for e in resource.events.recent() if e.kind == "native"]
    assert events and "5 of 5 POU bodies run as C" in events[-1].message


def test_module_copies_are_bound_again_once_their_classes_are_gone(
    fresh_tier: NativeTier,
) -> None:
    resource = running(compiled(PLANT), fresh_tier)
    for _ in range(6):
        resource.stop()
        resource.cold_start()
        resource.tier_up(wait=True)
        resource.start()
        resource.cycle()
        gc.collect()
    loaded = [copies.loaded for copies in fresh_tier._copies.values()]
    assert loaded and max(loaded) <= 3  # not one per cold start


def test_the_variables_go_into_native_memory_and_the_event_says_where_they_are(
    native_tier: NativeTier,
) -> None:
    resource = running(compiled(PLANT), native_tier)
    native = [e.message for e in resource.events.recent() if e.kind == "native"]
    assert native[-1].endswith(
        "5 of 5 POU bodies run as C, the variables in native memory, the usual CPU cycle in C"
    )
    assert resource.variables.image is not None
    kept = running(compiled(ON_SLOTS + PLANT), native_tier)
    native = [e.message for e in kept.events.recent() if e.kind == "native"]
    assert "5 of 5 POU bodies run as C, the variables on Python objects (no view" in native[-1]
    assert kept.variables.image is None
    for _ in range(3):  # the same values either way
        resource.cycle()
        kept.cycle()
    values = {k: v for k, v in kept.variables.values().items() if "keep_on_slots" not in k}
    assert resource.variables.values() == values


def test_a_body_image_mode_would_leave_to_python_keeps_the_configuration_on_slots(
    native_tier: NativeTier,
) -> None:
    text = """TYPE Pt : STRUCT x : DINT; END_STRUCT; END_TYPE
FUNCTION Total : DINT
VAR_INPUT a : ARRAY[1..3] OF Pt; END_VAR
Total := a[1].x + a[2].x + a[3].x;
END_FUNCTION
PROGRAM Main
VAR xs : ARRAY[1..3] OF Pt := [(x := 1), (x := 2), (x := 3)]; s : DINT; END_VAR
xs[1].x := xs[1].x + 1;
s := Total(xs);
END_PROGRAM
"""
    resource = running(compiled(text), native_tier)
    native = [e.message for e in resource.events.recent() if e.kind == "native"]
    assert native[-1].startswith(
        "native code in place: 1 of 2 POU bodies run as C, the variables on Python objects "
        "(in native memory Main would run as Python: "
    )
    assert "not yet in image mode" in native[-1]
    assert resource.variables.image is None
    for _ in range(3):
        resource.cycle()
    assert resource.variables.values()["Main.s"] == 9  # (1 + 3) + 2 + 3


def test_a_value_the_image_refuses_keeps_the_variables_on_objects_whole(
    native_tier: NativeTier,
) -> None:
    text = "PROGRAM Main\nVAR n : INT; m : INT; END_VAR\nm := m + 1;\nEND_PROGRAM\n"
    resource = Resource("R", VirtualClock())
    resource.native = native_tier
    resource.load(compiled(text))
    resource.programs[0].instance.n = "not an INT"  # what no checked writer would store
    resource.tier_up(wait=True)
    native = [e.message for e in resource.events.recent() if e.kind == "native"]
    assert "the variables stay on Python objects: a variable of an integer" in native[-1]
    assert resource.variables.image is None
    resource.start()
    resource.cycle()
    resource.tier_up()  # not tried again
    assert resource.variables.image is None
    assert resource.variables.values()["Main.m"] == 1


def test_integer_division_at_the_limits_of_64_bits(native_tier: NativeTier) -> None:
    text = """
PROGRAM Main
VAR a : LINT := -9223372036854775807; b : LINT := -1; q, r : LINT; n : INT; END_VAR
n := n + 1;
a := a - 1;  (* the smallest LINT in the second cycle *)
q := a / b;  (* 2**63 in Python, wrapped back to the smallest *)
r := a MOD b + a MOD 7;
b := b - n;
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert pair.report.bodies == ("Main",)
    pair.cycle_and_compare(4)


def test_shifts_by_the_width_or_more_are_zero_at_once_on_both_tiers(
    native_tier: NativeTier,
) -> None:
    # SHL by a DINT of two thousand million made a 250 MB number before the wrap masked
    # it, by a LINT of 10**15 a MemoryError that stopped the program. Counts that cannot
    # be negative run as C, and so do LWORD's (shifted left by up to 64, computed modulo
    # 2**64 in C, which is all the wrap keeps of Python's exact 128 bits)
    text = """
PROGRAM Main
VAR
  w : DWORD := 1; k : USINT := 3; u : UDINT := 4000000000; i : INT := -5;
  a, b : DWORD; f, g : INT; by : BYTE := 16#81;
END_VAR
a := SHL(w, k); b := SHL(w, u); f := SHL(i, u); g := SHR(i, u); by := SHL(by, 1);
k := k + 10;
END_PROGRAM
PROGRAM Wide
VAR
  w : LWORD := 1; n : DINT := 2000000000; l : LINT := 1000000000000000;
  a, b, c, d : LWORD; i : INT := -5; f, g : INT;
END_VAR
a := SHL(w, n); b := SHL(w, l); c := SHL(w, 63); d := SHL(w, 64);
f := SHL(i, n); g := SHR(i, n);
END_PROGRAM
"""
    programs = [ProgramConfig(name, name, n) for n, name in enumerate(("Main", "Wide"), 1)]
    pair = side_by_side(text, native_tier, programs)
    assert pair.report.bodies == ("Main", "Wide")
    pair.cycle_and_compare(4)  # k is 33 in the fourth cycle: beyond a DWORD's 32 bits
    values = pair.native.variables.values()
    main = [values[f"Main.{x}"] for x in ("a", "b", "f", "g", "by")]
    assert main == [0, 0, 0, -1, 0x10]
    wide = [values[f"Wide.{x}"] for x in ("a", "b", "c", "d", "f", "g")]
    assert wide == [0, 0, 1 << 63, 0, 0, -1]


def test_a_negative_shift_count_is_the_same_fault_on_both_tiers(native_tier: NativeTier) -> None:
    text = """
PROGRAM Main
VAR w : DWORD := 16#F0; n : DINT := 2; a, b : DWORD; i : INT := -64; c : INT; END_VAR
n := n - 1;
a := SHL(w, n);
b := SHR(w, n + 1) OR SHR(w, n * 1000);
c := SHR(i, n * 1000);
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert pair.report.bodies == ("Main",)
    pair.cycle_and_compare(2)  # n 1 and 0: shifts by 1, 0, 2, 1,000 and 1
    assert "negative shift count in POU Main (prog.st:5)" in pair.fault_of_the_next_cycle()


def test_the_real_functions_run_as_c_nan_out_of_their_domain_as_in_python(
    native_tier: NativeTier,
) -> None:
    text = """
PROGRAM Main
VAR
  x : LREAL := -3.0; r : REAL := 0.5; big : LREAL := 700.0;
  a, b, c, d, e, f, g, h, i, j, k : LREAL; q : REAL;
END_VAR
x := x + 0.75;
big := big + 5.0;  (* EXP overflows past 709.78: NaN, as Python's OverflowError *)
a := SQRT(x); b := LN(x); c := LOG(x); d := EXP(big); e := SIN(x * 1.0E308 * 10.0);
f := COS(x); g := TAN(x); h := ASIN(x); i := ACOS(x / 4.0); j := ATAN(x); k := LN(x - x);
q := SQRT(r) + SIN(r);
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert pair.report.bodies == ("Main",)
    pair.cycle_and_compare(8)  # x from -2.25 to 3.0, through 0: every domain's edge


def test_expt_rotations_and_conversions_run_as_c_with_the_python_values(
    native_tier: NativeTier,
) -> None:
    # EXPT of a negative base to a fraction was a complex number held in a REAL
    text = """
PROGRAM Main
VAR
  x : LREAL := -2.5; y : LREAL := -3.0; big : LREAL := 1.0E300; z : LREAL := -0.0;
  p, q, o, u, v, m : LREAL; r : REAL := -8.0; rq : REAL; i : INT := 3; n : DINT := -70;
  w : DWORD := 16#8000_0001; by : BYTE := 16#81; a, b : DWORD; c, d : BYTE; e : BOOL;
  k : INT; t : TIME := T#1s; t2 : TIME;
END_VAR
x := x + 0.5; y := y + 1.0; n := n + 13; e := NOT e;
p := EXPT(x, y); q := EXPT(x, 0.5); o := EXPT(big, 2.0); u := EXPT(z, -1.0);
v := EXPT(y, 3); m := EXPT(1.0 / y, x); rq := EXPT(r, REAL#1.0 / 3.0) + EXPT(r, i);
a := ROL(w, n); b := ROR(w, n); c := ROL(by, i); d := ROR(by, n);
k := BOOL_TO_INT(e) + BOOL_TO_INT(NOT e) * 2;
t2 := t * (2 * i);
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert pair.report.bodies == ("Main",)
    pair.cycle_and_compare(8)  # x and y from negative through 0 to positive, n past 0


def test_arrays_and_structures_assigned_whole_are_copies_on_both_tiers(
    native_tier: NativeTier,
) -> None:
    text = """
TYPE Pair : STRUCT a : INT; b : REAL; END_STRUCT; END_TYPE
FUNCTION_BLOCK Sum
VAR_INPUT p : Pair; values : ARRAY[1..3] OF DINT; END_VAR
VAR_OUTPUT total : DINT; last : Pair; END_VAR
total := values[1] + values[2] + values[3] + p.a;
last := p;
p.a := 0;
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  x, y : Pair; list, other : ARRAY[1..3] OF DINT; pairs : ARRAY[0..2] OF Pair;
  s : Sum; n : INT; kept : Pair;
END_VAR
n := n + 1;
x.a := x.a + n; x.b := x.b + 0.5;
list[1 + n MOD 3] := n * 10;
y := x;             (* a copy: changing x later leaves y *)
x.a := x.a * 2;
other := list;
list[1] := -1;
pairs[n MOD 3] := y;
kept := pairs[(n + 1) MOD 3];
s(p := y, values := other);
kept.b := kept.b + REAL#1.0;
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert set(pair.report.bodies) == {"Main", "Sum"}
    pair.cycle_and_compare(6)
    values = pair.native.variables.values()
    assert values["Main.y.a"] != values["Main.x.a"] and values["Main.other"][0] != -1
    assert values["Main.s.last.a"] == values["Main.y.a"] != 0 == values["Main.s.p.a"]


def test_strings_run_as_c_with_the_python_values(native_tier: NativeTier) -> None:
    text = """
FUNCTION Tag : STRING[12]
VAR_INPUT n : INT; END_VAR
IF n MOD 2 = 0 THEN Tag := 'even'; ELSE Tag := 'odd'; END_IF;
END_FUNCTION
FUNCTION_BLOCK Join
VAR_INPUT a, b : STRING[8]; END_VAR
VAR_OUTPUT both : STRING[10]; longer : BOOL; END_VAR
both := CONCAT(a, b);
longer := LEN(a) > LEN(b);
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  s : STRING[5]; t : STRING := 'Grüße$N'; w : WSTRING[6] := "Ωmega"; n : INT;
  j : Join; same, less : BOOL; l : DINT; kept, odd, f1, f2, f3, f4 : STRING; r : REAL;
  ws : WSTRING;
END_VAR
n := n + 1;
odd := 'q"\\??=*/é$$$N$T';  (* C's quote, escape, trigraph and comment end, UTF-8 *)
s := CONCAT(s, 'ab');   (* cut to 5 *)
IF LEN(s) = 5 THEN s := ''; END_IF;
same := s = 'abab'; less := s < t;
w := CONCAT(w, "λ");
j(a := s, b := Tag(n));
kept := j.both;
l := LEN(kept) + LEN(w) + LEN(t) + FIND(t, 'ß');
(* the string functions: the runtime's helpers, called from C *)
f1 := CONCAT(LEFT(t, n), RIGHT(kept, 2), MID(t, 3, n));
f2 := REPLACE(INSERT(f1, 'xy', n), '-', 1, n MOD 4);
f3 := DELETE(f2, 2, n);
f4 := CONCAT(INT_TO_STRING(n * 1000), REAL_TO_STRING(INT_TO_REAL(n) / 3.0),
             TIME_TO_STRING(T#1s * n));
r := STRING_TO_REAL('2.5') * INT_TO_REAL(n);
ws := STRING_TO_WSTRING(f1);
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert set(pair.report.bodies) == {"Main", "Join", "Tag"}  # Tag: a FUNCTION of texts
    pair.cycle_and_compare(7)
    values = pair.native.variables.values()
    assert values["Main.kept"] == "abodd" and values["Main.w"] == "Ωmegaλ"
    assert values["Main.odd"] == 'q"\\??=*/\u00c3\u00a9$\n\t'  # a STRING holds bytes: é in UTF-8


def test_the_rest_of_the_standard_functions_run_from_c_with_the_python_values(
    native_tier: NativeTier,
) -> None:
    # integers of any size from a string, wrapped to the type: exact below 2**126, beyond a
    # stand-in equal to them modulo 2**64 (STRING_TO_TIME's was stored whole, unwrapped)
    text = """
PROGRAM Main
VAR
  i : INT := 5; w : WORD; b : BOOL := TRUE; n : INT; k, k2, k3 : DINT; l : LINT;
  d : WORD := 16#0012; x, m : INT; t : TIME;
  huge : STRING := '-99999999999999999999999999999999999999999999';
  mid : STRING := '170141183460469231731687303715884105727';
END_VAR
n := n + 1;
b := NOT b;
i.15 := b; w.%B1 := INT_TO_BYTE(n * 40); i.3 := NOT b;
k := STRING_TO_DINT(huge); k2 := STRING_TO_DINT(mid); k3 := STRING_TO_DINT('16#7FFF_FFFF');
l := STRING_TO_LINT(CONCAT('-', mid)) + STRING_TO_LINT('1e3');
x := BCD_TO_INT(d); d := INT_TO_BCD(x + n);
t := STRING_TO_TIME('T#5s') + STRING_TO_TIME('T#999999999999d');
m := MUX(n - 1, x, i, 7);  (* the fourth cycle: no fourth input, the same fault *)
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert pair.report.bodies == ("Main",)
    pair.cycle_and_compare(3)
    assert "Main" in pair.fault_of_the_next_cycle()


def test_references_run_as_c_with_the_python_values_null_the_same_fault(
    native_tier: NativeTier,
) -> None:
    text = """
TYPE Pt : STRUCT x : INT; y : REAL; END_STRUCT; END_TYPE
VAR_GLOBAL g : DINT; END_VAR
FUNCTION_BLOCK Holder
VAR_INPUT r : REF_TO INT; END_VAR
VAR_OUTPUT v : INT; ok : BOOL; END_VAR
ok := r <> NULL;
IF ok THEN v := r^; r^ := v + 1; END_IF;
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  n : INT; a : ARRAY[1..3] OF INT; h : Holder; rg : REF_TO DINT; p : Pt; rp : REF_TO Pt;
  i : INT := 1; rr : REFERENCE TO INT; same : BOOL; other : REF_TO INT; k : INT;
END_VAR
k := k + 1;
h(r := REF(n));
h(r := REF(a[i]));
i := i MOD 3 + 1;
rg := REF(g); rg^ := rg^ + 1;
rp := REF(p); rp^.x := rp^.x + 5; rp^.y := rp^.y + 0.5;
rr REF= n; rr := rr + 7;
other := REF(a[2]);
same := other = h.r;
IF k = 5 THEN other := NULL; END_IF;
IF other = NULL THEN n := other^; END_IF;  (* NULL: the same fault on both tiers *)
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert set(pair.report.bodies) == {"Main", "Holder"}
    pair.cycle_and_compare(4)
    found = pair.native.variables.values()
    assert found["g"] == 4 and found["Main.p.x"] == 20 and found["Main.rp"] == "Main.p"
    assert "dereference of NULL in POU Main (prog.st:25)" in pair.fault_of_the_next_cycle()


def test_enumerations_run_as_c_with_the_python_values(native_tier: NativeTier) -> None:
    text = """
TYPE Mode : (Idle, Filling, Draining := 7); END_TYPE
FUNCTION_BLOCK Valve
VAR_INPUT mode : Mode; END_VAR
VAR_OUTPUT open : BOOL; END_VAR
open := mode = Filling;
END_FUNCTION_BLOCK
PROGRAM Main
VAR state : Mode; n : INT; v : Valve; seen : ARRAY[0..2] OF Mode; END_VAR
n := n + 1;
CASE state OF
  Idle: IF n MOD 2 = 0 THEN state := Filling; END_IF;
  Filling: state := Draining;
ELSE state := Idle;
END_CASE;
v(mode := state);
seen[n MOD 3] := state;
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert set(pair.report.bodies) == {"Main", "Valve"}
    pair.cycle_and_compare(7)


FUNCTIONS = """
FUNCTION Scale : INT
VAR_INPUT a : INT; b : INT; END_VAR
VAR t : DINT; END_VAR
t := a * b;
Scale := DINT_TO_INT(t / (b - 7));
END_FUNCTION
FUNCTION Above : BOOL
VAR_INPUT x : REAL; limit : REAL := 2.5; END_VAR
Above := x > limit;
END_FUNCTION
FUNCTION Half : LREAL
VAR_INPUT x : LREAL; on : BOOL; END_VAR
IF on THEN Half := x / 2.0; ELSE Half := x; END_IF;
END_FUNCTION
FUNCTION Ticks : TIME
Ticks := T#5s;
END_FUNCTION
FUNCTION Note
VAR_INPUT a : INT; END_VAR
END_FUNCTION
FUNCTION Split : BOOL
VAR_INPUT a : INT; END_VAR
VAR_OUTPUT q : INT; END_VAR
q := a * 2;
Split := a > 0;
END_FUNCTION
PROGRAM Main
VAR n, x : INT; b, up : BOOL; r : REAL; l : LREAL; t : TIME; END_VAR
n := n + 1;
x := Scale(x + 1, n) + 2;
x := Scale(a := x, b := 2) - Scale(b := n, a := 3);
r := r + 0.75;
up := Above(r) AND NOT Above(x := r, limit := 4.0);
l := Half(l + 3.0, up);
t := Ticks() + T#1s;
Note(a := x);
END_PROGRAM
FUNCTION Swap : BOOL
VAR_IN_OUT x, y : INT; END_VAR
VAR t : INT; END_VAR
t := x; x := y; y := t;
Swap := x > y;
END_FUNCTION
PROGRAM Outputs
VAR q, p : INT; b, c : BOOL; n : INT; u : INT := 5; v : INT := -5; END_VAR
n := n + 1;
b := Split(a := n - 3, q => q) AND Split(a := q, q => p);
c := Swap(u, v);
END_PROGRAM
"""


def test_function_calls_run_from_c_and_faults_in_them_name_the_function_line(
    native_tier: NativeTier,
) -> None:
    programs = [ProgramConfig(name="Main", pou="Main", program_id=1),
                ProgramConfig(name="Outputs", pou="Outputs", program_id=2)]  # fmt: skip
    pair = side_by_side(FUNCTIONS, native_tier, programs)
    # every FUNCTION's body is C too (outputs: the result and q, where Python has a tuple)
    functions = ("Above", "Half", "Note", "Scale", "Split", "Swap", "Ticks")
    assert pair.report.bodies == tuple(sorted(("Main", "Outputs", *functions)))
    pair.cycle_and_compare(6)  # n = 7 in the seventh cycle: Scale divides by zero
    assert "division by zero in POU Scale (prog.st:6)" in pair.fault_of_the_next_cycle()


# A chart of a block, run by a program: timed and stored qualifiers, a step's time in a
# transition, and a transition that divides by the block's input (zero in the fifth cycle)
CHART = """
FUNCTION_BLOCK Mixer
VAR_INPUT speed : INT; END_VAR
VAR stirring, warm : BOOL; turns : INT; END_VAR
INITIAL_STEP Wait: warm(R); END_STEP
TRANSITION FROM Wait TO Stir := Wait.T >= T#200ms; END_TRANSITION
STEP Stir: stirring(L, T#300ms); warm(S); Turn(N); END_STEP
TRANSITION FROM Stir TO Wait := 100 / speed > 30 AND Stir.T >= T#100ms; END_TRANSITION
ACTION Turn: turns := turns + speed; END_ACTION
END_FUNCTION_BLOCK
PROGRAM Main
VAR mixer : Mixer; n : INT; END_VAR
n := n + 1;
mixer(speed := 5 - n);
END_PROGRAM
"""


def test_a_chart_runs_as_c_with_the_python_values_and_the_same_fault(
    native_tier: NativeTier,
) -> None:
    pair = side_by_side(CHART, native_tier)
    assert pair.report.bodies == ("Main", "Mixer")  # the chart's body as C
    pair.cycle_and_compare(4)  # speed 4, 3, 2, 1; in the fifth cycle 0
    assert "division by zero in POU Mixer (prog.st:8)" in pair.fault_of_the_next_cycle()


WIDE = """
FUNCTION Twice : ULINT
VAR_INPUT v : ULINT; END_VAR
Twice := v * 2;
END_FUNCTION
FUNCTION_BLOCK Holder
VAR_INPUT w : LWORD; END_VAR
VAR_OUTPUT q : LWORD; END_VAR
VAR kept : LWORD := 16#F0F0_0000_0000_000F; END_VAR
q := ROL(w XOR kept, 13);
kept := kept + w;
END_FUNCTION_BLOCK
PROGRAM Main
VAR
  a : ULINT := 18446744073709551000; b : ULINT := 4294967311;
  big : ULINT := 9223372036854775809; sum, dif, prod, quo, rem, tw, mx, mn : ULINT;
  lt, eq, ge : BOOL; n : DINT := -9;
  w : LWORD := 16#8000_0000_0000_0001; bits, andw, orw, xorw, notw : LWORD;
  shl1, shr1, rol1, ror1, shln, shrn : LWORD;
  l : LINT := -5; ul : ULINT; back : LINT; dw : DWORD := 16#FFFF_FFFF; lw : LWORD;
  dw2 : DWORD; r : LREAL; fromr : ULINT; si : SINT; s : STRING;
  arr : ARRAY[1..5] OF ULINT; i : INT; total : ULINT; h : Holder; hq : LWORD; dig : INT;
END_VAR
a := a + 97;  (* past 2**64 in the seventh cycle: wrapped *)
b := b * 65537 + 3;  (* beyond 64 bits before the wrap, and beyond 128 with big *)
n := n + 9;  (* 0 to 72: shifts and rotations by the width and more *)
sum := a + big; dif := b - a; prod := a * b * big + 7; tw := Twice(a);
quo := a / (b MOD 1000 + 1); rem := a MOD b;
dig := ULINT_TO_INT(a MOD 10) * 100 + ULINT_TO_INT(b / 1000000000000000000);
lt := a < b; eq := a = sum - big; ge := a >= 16#FFFF_FFFF_FFFF_FF00;
mx := MAX(a, b, big); mn := MIN(a, b);
bits := ULINT_TO_LWORD(a);
andw := w AND bits; orw := w OR ULINT_TO_LWORD(b); xorw := bits XOR ULINT_TO_LWORD(b);
notw := NOT bits;
shl1 := SHL(bits, 3); shr1 := SHR(bits, 5); shln := SHL(w, n); shrn := SHR(bits, n);
rol1 := ROL(w, n); ror1 := ROR(bits, n + 1);
w := w + 16#0101_0101_0101_0101;
l := l * 7 - 3; ul := LINT_TO_ULINT(l); back := ULINT_TO_LINT(a);
lw := DWORD_TO_LWORD(dw); dw2 := LWORD_TO_DWORD(bits); si := ULINT_TO_SINT(b);
r := ULINT_TO_LREAL(a) - ULINT_TO_LREAL(b MOD a);
fromr := LREAL_TO_ULINT(r / 3.0); s := ULINT_TO_STRING(a);
FOR i := 1 TO 5 DO
  arr[i] := arr[i] * 3 + a;
  total := total + arr[i];
END_FOR;
h.w := bits;  (* a member of another POU's instance, written and read *)
h();
hq := h.q;
h(w := hq XOR w);
END_PROGRAM
"""


def test_ulint_and_lword_run_as_c_with_the_python_values(native_tier: NativeTier) -> None:
    """ULINT and LWORD (0..2**64-1) are padt_i128 in C: exact where Python's value fits
    128 bits, modulo 2**64 where only the wrap's 64 bits of it are kept (a product of
    three ULINTs)."""
    pair = side_by_side(WIDE, native_tier)
    assert pair.report.bodies == ("Holder", "Main", "Twice") and not pair.report.left
    pair.cycle_and_compare(12)
    values = pair.native.variables.values()
    assert values["Main.a"] == (18446744073709551000 + 12 * 97) % 2**64  # wrapped
    assert values["Main.shln"] == 0 and values["Main.rol1"] != 0  # by 99: 0, rotated
    assert min(values["Main.arr"]) > 2**63 and values["Main.h.q"] != 0


def test_ulint_division_by_zero_is_the_same_fault_on_both_tiers(native_tier: NativeTier) -> None:
    text = """
PROGRAM Main
VAR a : ULINT := 18446744073709551615; z : ULINT := 3; q, r : ULINT; END_VAR
z := z - 1;
r := a MOD (z + 1);
q := a / z;
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert pair.report.bodies == ("Main",)
    pair.cycle_and_compare(2)  # z = 0 in the third cycle
    assert "division by zero in POU Main (prog.st:6)" in pair.fault_of_the_next_cycle()

    modulo = text.replace("r := a MOD (z + 1);", "r := a MOD z;")
    pair = side_by_side(modulo, native_tier)
    assert pair.report.bodies == ("Main",)
    pair.cycle_and_compare(2)
    assert "division by zero in POU Main (prog.st:5)" in pair.fault_of_the_next_cycle()


def test_a_ulint_variable_beyond_its_range_is_a_fault_not_a_wrong_value(
    native_tier: NativeTier,
) -> None:
    text = ON_SLOTS + "PROGRAM Main\nVAR n, m : ULINT; END_VAR\nm := n + 1;\nEND_PROGRAM\n"
    for wrong in (-1, 2**64, "not a ULINT"):  # what no checked writer would store
        resource = running(compiled(text), native_tier)
        resource.programs[0].instance.n = wrong
        resource.cycle()
        error = program_error(resource)
        assert "another type" in error and "prog.st:4" in error, wrong


WIDE_PLACES = """VAR_GLOBAL gU : ULINT := 18446744073709551615; gW : ARRAY[0..2] OF LWORD; END_VAR
TYPE Pair : STRUCT lo, hi : ULINT; END_STRUCT; END_TYPE
FUNCTION Split : BOOL
VAR_INPUT v : ULINT; END_VAR
VAR_OUTPUT hi, lo : ULINT; END_VAR
hi := v / 4294967296; lo := v MOD 4294967296;
Split := hi > lo;
END_FUNCTION
PROGRAM Main
VAR
  a : ULINT := 18446744073709551000; r : REF_TO ULINT; p : Pair; q : ULINT; bo : BOOL;
  k : INT; m : ULINT; st : STRING := '18446744073709551615'; n : INT;
  texts : ARRAY[0..3] OF STRING := ['18446744073709551617', '-5',
    '170141183460469231731687303715884105729', '-170141183460469231731687303715884105729'];
END_VAR
a := a + 101;
r := REF(a); q := r^ * 3; r^ := r^ + 5;
bo := Split(v := a, hi => p.hi, lo => p.lo);
m := MUX(k, a, p.hi, p.lo); k := (k + 1) MOD 3;
CASE a MOD 4 OF 0: n := 1; 1, 2: n := 2; ELSE n := 3; END_CASE;
WHILE m > 1000 DO m := m / 1000; END_WHILE;
gU := gU - 1 + a; gW[k] := ULINT_TO_LWORD(gU) XOR gW[(k + 1) MOD 3];
m := m + STRING_TO_ULINT(st);  (* beyond 2**126 too: a stand-in in max() *)
st := texts[ULINT_TO_INT(a MOD 4)];
IF a > 18446744073709551000 THEN n := n + 10; END_IF;
END_PROGRAM
"""


def test_ulint_through_references_outputs_globals_and_strings_runs_as_c(
    native_tier: NativeTier,
) -> None:
    pair = side_by_side(WIDE_PLACES, native_tier)
    assert pair.report.bodies == ("Main", "Split")  # on slots (references): Split's C too
    pair.cycle_and_compare(12)  # a MOD 4 takes every text


def test_a_literal_converted_is_what_its_type_keeps_of_it_on_both_tiers(
    native_tier: NativeTier,
) -> None:
    """A literal is taken as the conversion's input type, then converted: what the target
    keeps of it (the Python tier stored LWORD_TO_DWORD(16#FFFF_FFFF_FFFF_FFFF) whole in a
    DWORD, where the C faulted on its range check)."""
    text = """
PROGRAM Main
VAR u : UINT := 7; d : DWORD; l : LINT; i : INT; s : SINT; END_VAR
u := WORD_TO_UINT(NOT 16#FFFF);
d := LWORD_TO_DWORD(16#FFFF_FFFF_FFFF_FFFF);
l := ULINT_TO_LINT(18446744073709551615);
i := DINT_TO_INT(16#1_8000 + 1);
s := INT_TO_SINT(-129);
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert pair.report.bodies == ("Main",)
    pair.cycle_and_compare(2)
    values = pair.python.variables.values()
    assert [values[f"Main.{name}"] for name in "udlis"] == [0, 0xFFFF_FFFF, -1, -32767, 127]


def test_a_literal_too_large_for_a_dint_is_shifted_and_rotated_whole_on_both_tiers(
    native_tier: NativeTier,
) -> None:
    """A literal without a type that needs more than 32 bits is shifted and rotated as
    LWORD (a based literal), LINT or ULINT: ROR(16#8000_0000_0000_0001, 1) kept only the
    bits of a DINT until December 2026. One that fits 32 bits is a DINT as before."""
    text = """
PROGRAM Main
VAR a, b : LWORD; c : LINT; d : DINT; e : ULINT; END_VAR
a := ROR(16#8000_0000_0000_0001, 1);
b := SHR(16#FFFF_FFFF_FFFF_FFFF, 60);
c := SHL(5000000000, 1);
d := SHR(16#FFFF_FFFF, 4);
e := ROL(18446744073709551615, 4);
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert pair.report.bodies == ("Main",)
    pair.cycle_and_compare(2)
    values = pair.python.variables.values()
    assert [values[f"Main.{name}"] for name in "abcde"] == [
        0xC000_0000_0000_0000,
        15,
        10_000_000_000,
        0x0FFF_FFFF,
        2**64 - 1,
    ]


SHARED_GLOBALS = """
TYPE Pair : STRUCT a : INT; b : STRING[8]; END_STRUCT; END_TYPE
VAR_GLOBAL buf : ARRAY[1..6] OF INT; name : STRING[12]; p : Pair; n : DINT; r : LREAL; END_VAR
PROGRAM Writer
VAR k : INT; END_VAR
k := k + 1;
n := n + 1;
buf[(k MOD 6) + 1] := k;
IF k MOD 2 = 0 THEN name := 'even'; ELSE name := 'odd one'; END_IF;
p.a := k * 2;
p.b := name;
r := r + 0.5;
END_PROGRAM
PROGRAM Reader
VAR seen : DINT; total : INT; copy : Pair; last : STRING[12]; i : INT; x : LREAL; END_VAR
seen := n;
total := 0;
FOR i := 1 TO 6 DO total := total + buf[i]; END_FOR;
copy := p;
last := name;
x := r;
END_PROGRAM
"""


def test_programs_own_globals_are_copied_by_their_bytes_in_native_memory(
    native_tier: NativeTier,
) -> None:
    """Two programs, each with a view of its own of the globals (an array, a text, a
    structure, numbers), copied in and published every cycle: in native memory as bytes
    (`__padt_copy__`), with every value the Python tier's on objects."""
    programs = [ProgramConfig("Writer", "Writer", 1), ProgramConfig("Reader", "Reader", 2)]
    pair = side_by_side(SHARED_GLOBALS, native_tier, programs)
    native = pair.native
    assert native.variables.image is not None
    assert all(program.view is not native.variables.globals for program in native.programs)
    pair.cycle_and_compare(12)


def test_an_endless_recursion_of_blocks_is_a_program_error_not_a_dead_process(
    native_tier: NativeTier,
) -> None:
    """A block calling itself through a reference: its C body called its C body on the C
    stack until the process died of SIGSEGV (the Python tier faults). Now each body looks
    at the stack left as it begins: the same program error, at the same ST line. The depth
    it faults at is not the Python tier's (its recursion limit counts Python's frames), so
    what the recursion wrote before differs: only the fault is compared."""
    text = """
FUNCTION_BLOCK Node
VAR_INPUT next : REF_TO Node; END_VAR
VAR d : INT; END_VAR
d := d + 1;
IF next <> NULL THEN next^(); END_IF;
END_FUNCTION_BLOCK
PROGRAM Main
VAR a : Node; k : INT; END_VAR
k := k + 1;
IF k > 2 THEN a.next := REF(a); END_IF;
a();
END_PROGRAM
"""
    pair = side_by_side(text, native_tier)
    assert pair.report.bodies == ("Main", "Node")
    pair.cycle_and_compare(2)
    for resource in (pair.python, pair.native):
        advance(resource)
        assert (
            program_error(resource) == "calls nested too deep (recursion) in POU Node (prog.st:6)"
        )
    assert pair.native.state == pair.python.state  # the resource goes on, as on Python
