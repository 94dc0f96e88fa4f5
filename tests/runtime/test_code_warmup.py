"""Fresh code warmed up when it is compiled (runtime/code/code_warmup.py): a program runs its
first CPU cycle on quickened code, after a load and after a reload (also where the reload
kept its code), and the warm-up's calls change nothing a program, a function block, a
function or the globals hold."""

from __future__ import annotations

import dis
import sys
from types import CodeType
from typing import Any

import pytest

from runtime.code import code_warmup
from runtime.code.code_warmup import warm_up
from tests.support.resource_harness import compiled, harness

# side effects everywhere a warm-up call could reach: globals, a function writing through
# VAR_IN_OUT, function block state, an array of instances (a comprehension), loops that
# never count towards CPython's own warm-up, a method, a string
PROGRAM = """
TYPE Counter : STRUCT n : DINT; text : STRING[20]; END_STRUCT; END_TYPE
VAR_GLOBAL g : DINT := 5; shared : Counter; END_VAR
FUNCTION Bump : DINT
VAR_IN_OUT x : DINT; END_VAR
x := x + 1; Bump := x;
END_FUNCTION
FUNCTION_BLOCK Acc
VAR_INPUT step : DINT; END_VAR
VAR_OUTPUT total : DINT := 100; END_VAR
total := total + step;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Meter
VAR count : DINT; END_VAR
METHOD PUBLIC Tick : DINT
count := count + 1; Tick := count;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM P
VAR
  accs : ARRAY[1..3] OF Acc;
  meter : Meter;
  i : DINT;
  k : DINT := 1;
  ticks : DINT;
  last : DINT;
END_VAR
g := g + 1;
last := Bump(shared.n);
shared.text := CONCAT(shared.text, 'a');
FOR i := 1 TO 3 DO accs[i](step := i); END_FOR;
WHILE k < 4 DO k := k + 1; END_WHILE;
REPEAT k := k - 1; UNTIL k <= 1 END_REPEAT;
ticks := meter.Tick();
END_PROGRAM
"""


def _values(cycles: int) -> dict[str, Any]:
    h = harness(PROGRAM, [{"name": "P"}])
    for _ in range(cycles):
        h.cycle()
    return h.resource.variables.values()


def test_the_warm_up_changes_no_value(monkeypatch: pytest.MonkeyPatch) -> None:
    warmed = {cycles: _values(cycles) for cycles in (0, 3)}
    monkeypatch.setattr(code_warmup, "CALLS_BEFORE_QUICKENING", 0)  # no warm-up at all
    cold = {cycles: _values(cycles) for cycles in (0, 3)}
    assert warmed == cold
    assert (warmed[0]["g"], warmed[0]["shared.n"], warmed[0]["P.accs[1].total"]) == (5, 0, 100)
    assert (warmed[3]["g"], warmed[3]["shared.n"], warmed[3]["P.accs[3].total"]) == (8, 3, 109)
    assert (warmed[3]["shared.text"], warmed[3]["P.ticks"]) == ("aaa", 3)


def _opnames(code: CodeType) -> list[str]:
    return [i.opname for i in dis.get_instructions(code, adaptive=True)]


@pytest.mark.skipif(sys.version_info[:2] != (3, 11), reason="only CPython 3.11 delays quickening")
def test_a_program_runs_quickened_code_from_its_first_cycle() -> None:
    h = harness(PROGRAM, [{"name": "P"}])
    body = type(h.resource.programs[0].instance).__call__.__code__
    # one call short of it: the first real call quickens, on the real values
    assert _opnames(body)[0] == "RESUME"
    h.cycle()
    names = _opnames(body)
    assert names[0] == "RESUME_QUICK"
    assert "LOAD_ATTR_SLOT" in names  # `s.k` and friends specialized on the instance


@pytest.mark.skipif(sys.version_info[:2] != (3, 11), reason="only CPython 3.11 delays quickening")
def test_code_a_reload_kept_starts_afresh_on_the_new_classes() -> None:
    """A reload of another POU keeps P's code, as a copy that never ran and is warmed up:
    the old code's specializations were made for the classes the reload replaced, and
    would miss for 50 to 90 cycles."""
    h = harness(PROGRAM, [{"name": "P"}])
    h.cycle(10)
    h.send(
        compiled(
            PROGRAM.replace("total := total + step;", "total := total + 2 * step;"), [{"name": "P"}]
        )
    )
    assert h.cmd("reload")["ok"]
    body = type(h.resource.programs[0].instance).__call__.__code__
    assert _opnames(body)[0] == "RESUME"
    h.cycle()
    assert _opnames(body)[0] == "RESUME_QUICK"
    assert h.value("P.accs[3].total") == 100 + 10 * 3 + 2 * 3


@pytest.mark.skipif(sys.version_info[:2] != (3, 11), reason="only CPython 3.11 delays quickening")
def test_without_the_warm_up_the_first_seven_calls_run_unquickened() -> None:
    """What the warm-up is for, pinned: should CPython change its threshold, this says so."""
    code = compile("def f(x):\n    return x + 1\n", "<test>", "exec")
    namespace: dict[str, Any] = {}
    exec(code, namespace)
    for _ in range(7):
        namespace["f"](1)
    assert _opnames(namespace["f"].__code__)[0] == "RESUME"
    namespace["f"](1)
    assert _opnames(namespace["f"].__code__)[0] == "RESUME_QUICK"


def test_the_warm_up_stops_at_the_first_reference_of_every_kind_of_function() -> None:
    """Generators, comprehensions, closures, keyword-only arguments: each one is called and
    raises at once; an endless loop behind a name is never reached."""
    source = (
        "def endless(a, *, b):\n    while tick:\n        pass\n"
        "def numbers(n):\n    yield n.first\n"
        "def built(n):\n    return [x for x in range(n)]\n"
        "def outer():\n    v = 1\n    def inner():\n        return v + w\n    w = 2\n"
        "    return inner\n"
    )
    warm_up([compile(source, "<test>", "exec")])  # returns: nothing loops, nothing escapes
