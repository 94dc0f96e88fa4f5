"""What a reload carries over, pinned for both ways the switch-over moves state: a reload
that changes one POU (the running objects are adopted, only their code changes) and one
that changes every layout (every value is copied into new objects). Each is checked
against the values and internal state before it (timers' start, edge memories, SFC steps
and action timers, arrays of structs), against the same reload done by copying alone,
across renames, after an abandoned switch-over, and through a context save."""

from __future__ import annotations

import functools
from typing import Any

import pytest

from runtime import reload as reload_module
from runtime import reload_switch
from runtime.adoption import Adopted, Adoption
from runtime.context_snapshot import snapshot
from runtime.reload import SwitchOverTooLong, switch_over
from runtime.resource import Resource
from runtime.restart import take_context, warm_start
from tests.support.resource_harness import Harness, compiled, harness

PLANT = """
TYPE Point : STRUCT x : INT; y : REAL; tag : STRING[8]; END_STRUCT; END_TYPE
VAR_GLOBAL total : DINT; points : ARRAY[1..3] OF Point; flags : ARRAY[0..3] OF BOOL; END_VAR
FUNCTION_BLOCK Counter
VAR_INPUT go : BOOL; END_VAR
VAR count : INT; delay : TON; edge : R_TRIG; history : ARRAY[1..2] OF Point; END_VAR
delay(IN := go, PT := T#1s);
edge(CLK := count > 2);
IF go THEN count := count + 1; END_IF;
history[2].x := count; history[2].tag := 'h';
END_FUNCTION_BLOCK
FUNCTION_BLOCK Small
VAR_INPUT x : INT; END_VAR
VAR_OUTPUT y : INT; END_VAR
y := x * 2;
END_FUNCTION_BLOCK
PROGRAM Main
VAR_EXTERNAL total : DINT; points : ARRAY[1..3] OF Point; flags : ARRAY[0..3] OF BOOL; END_VAR
VAR c : Counter; cs : ARRAY[1..2] OF Counter; s : Small; n : INT; r : REAL; last : Point; END_VAR
n := n + 1; r := r + 0.5;
c(go := TRUE); cs[2].go := n > 1; s(x := n);
points[2].x := n; points[2].y := r; points[3].tag := 'abc'; flags[1] := n > 2;
last := points[2];  (* a new struct object each cycle *)
INITIAL_STEP Idle: END_STEP
STEP Busy: Work(L, T#5s); END_STEP
TRANSITION FROM Idle TO Busy := n > 2; END_TRANSITION
TRANSITION FROM Busy TO Idle := n > 1000; END_TRANSITION
ACTION Work: total := total + 1; END_ACTION
END_PROGRAM
"""

# one small POU's code changes: nothing changes its layout
ONE_POU = PLANT.replace("y := x * 2;", "y := x * 3;")
# one small POU gains a variable: its instance is new, the program holding it is adopted
SMALL_LAYOUT = ONE_POU.replace(
    "VAR_OUTPUT y : INT; END_VAR", "VAR_OUTPUT y : INT; END_VAR VAR k : INT; END_VAR"
)
# every type of the project gains a variable: its objects are new, their values copied
EDITS = (
    ("tag : STRING[8]; END_STRUCT", "tag : STRING[8]; z : INT; END_STRUCT"),
    ("OF BOOL; END_VAR\nFUNCTION_BLOCK", "OF BOOL; more : INT; END_VAR\nFUNCTION_BLOCK"),
    ("OF Point; END_VAR", "OF Point; e : INT; END_VAR"),
    ("VAR_OUTPUT y : INT; END_VAR", "VAR_OUTPUT y : INT; END_VAR VAR k : INT; END_VAR"),
    ("r : REAL;", "r : REAL; added : INT := 7;"),
    ("y := x * 2;", "y := x * 3;"),
)
EVERYTHING = functools.reduce(lambda text, edit: text.replace(*edit), EDITS, PLANT)
NEW_MEMBERS = {"z", "more", "e", "k", "added"}


def running(cycles: int = 6) -> Harness:
    h = harness(PLANT)
    h.cycle(cycles)
    return h


def state(resource: Resource) -> dict[str, Any]:
    """Every value and all internal state of the running instances, class names included."""
    trees = {p.name: snapshot(p.instance) for p in resource.programs}
    trees[""] = snapshot(resource.variables.globals)
    return trees


def without(tree: Any, names: set[str]) -> Any:
    """A snapshot tree without the fields named `names` (the members a reload added)."""
    if isinstance(tree, dict):
        return {k: without(v, names) for k, v in tree.items() if k not in names}
    if isinstance(tree, list):
        return [without(item, names) for item in tree]
    return tree


def prepared(h: Harness, text: str, renames: dict[str, str] | None = None) -> Any:
    job = reload_switch.begin(h.resource, compiled(text), renames or {})
    job.prepare()
    assert job.failure is None and job.prepared is not None, job.failure
    return job


def copy_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """The switch-over as it was before objects were adopted: every value copied."""
    monkeypatch.setattr(
        reload_module, "plan_adoption", lambda old, new, plan: (Adoption(), Adopted())
    )


def test_a_reload_of_one_pou_adopts_the_running_objects_and_carries_everything() -> None:
    h = running()
    before = state(h.resource)
    assert before["Main"]["v"]["Busy"]["v"]["X"] is True  # the chain and its action timer run
    job = prepared(h, ONE_POU)
    assert job.prepared.copied == 0  # nothing copied: the program and the globals adopted
    assert len(job.prepared.adoption.grafts) == 2
    old_main = h.resource.programs[0].instance
    reload_switch.finish(h.resource, job)
    assert h.resource.programs[0].instance is old_main  # the very object, with new code
    assert state(h.resource) == before  # every value, timers' start, edges, steps, actions
    runs_on(h)


def runs_on(h: Harness, added: tuple[str, ...] = ()) -> None:
    """The next cycle gives what it gives without the reload (timers, steps and the action
    timer run on), but for the changed POU's output and the variables the reload added."""
    unreloaded = running()
    expected = unreloaded.cycle()
    values = h.cycle()
    assert values.pop("Main.s.y") == 3 * 7 and expected.pop("Main.s.y") == 2 * 7
    assert {k: v for k, v in values.items() if k not in added} == expected
    assert values["Main.Busy.X"] is True and values["Main.Busy.T"] > 0


def test_a_pou_that_gains_a_variable_is_copied_and_the_program_around_it_adopted() -> None:
    h = running()
    before = state(h.resource)
    main = h.resource.programs[0].instance
    counter, small = main.c, main.s
    job = prepared(h, SMALL_LAYOUT)
    assert job.prepared.copied == 3  # Small's x, y and ENO; everything else comes along
    reload_switch.finish(h.resource, job)
    assert h.resource.programs[0].instance is main and main.c is counter
    assert main.s is not small and h.value("Main.s.k") == 0
    assert without(state(h.resource), {"k"}) == before
    runs_on(h, ("Main.s.k",))


def after_values(h: Harness) -> list[str]:
    return list(h.resource.variables.values())


def test_a_reload_that_changes_every_layout_copies_every_value() -> None:
    h = running()
    before = state(h.resource)
    job = prepared(h, EVERYTHING)
    # only the objects of classes no edit touched stay: the library's FBs and the steps
    kept = {type(graft.fresh).__name__ for graft in job.prepared.adoption.grafts}
    assert kept == {"POU_TON", "POU_R_TRIG", "_SfcStep"} and job.prepared.copied > 0
    reload_switch.finish(h.resource, job)
    after = state(h.resource)
    assert without(after, NEW_MEMBERS) == before  # every value and all internal state
    assert h.value("Main.added") == 7 and h.value("points[1].z") == 0
    runs_on(h, tuple(k for k in after_values(h) if k.rpartition(".")[2] in NEW_MEMBERS))


@pytest.mark.parametrize(
    "text", [ONE_POU, SMALL_LAYOUT, EVERYTHING], ids=["one POU", "one layout", "everything"]
)
def test_adopting_gives_what_copying_gives(text: str, monkeypatch: pytest.MonkeyPatch) -> None:
    adopted, copied = running(), running()
    assert reload_switch.finish(adopted.resource, prepared(adopted, text))
    with monkeypatch.context() as patch:
        copy_only(patch)
        job = prepared(copied, text)
        assert job.prepared.copied > 0
        assert reload_switch.finish(copied.resource, job)
    for _ in range(4):
        assert state(adopted.resource) == state(copied.resource)
        adopted.cycle()
        copied.cycle()


def test_renamed_instances_are_adopted_once_and_never_shared() -> None:
    h = running()
    renamed = ONE_POU.replace("c : Counter;", "c2 : Counter; c : Counter;").replace(
        "c(go := TRUE);", "c(go := TRUE); c2(go := FALSE);"
    )
    job = prepared(h, renamed, renames={"Main.c2": "Main.c"})  # c's values go to both
    reload_switch.finish(h.resource, job)
    main = h.resource.programs[0].instance
    assert main.c is not main.c2 and main.c.history is not main.c2.history
    assert h.value("Main.c.count") == h.value("Main.c2.count") == 6
    h.cycle()
    assert (h.value("Main.c.count"), h.value("Main.c2.count")) == (7, 6)
    moved = PLANT.replace("c : Counter;", "counter : Counter;").replace("c(go", "counter(go")
    job = prepared(h, moved, renames={"Main.counter": "Main.c"})
    kept = main.c
    reload_switch.finish(h.resource, job)
    assert h.resource.programs[0].instance.counter is kept  # adopted under its new name
    assert h.value("Main.counter.count") == 7


def test_an_abandoned_switch_over_leaves_the_adopted_objects_as_they_were() -> None:
    h = running()
    before = state(h.resource)
    main = h.resource.programs[0].instance
    old_class = type(main.s)
    job = prepared(h, ONE_POU)
    assert job.instances is not None
    with pytest.raises(SwitchOverTooLong):
        switch_over(job.prepared, job.instances, deadline_ns=0)  # long past
    assert type(main.s) is old_class and state(h.resource) == before
    h.cycle()
    assert h.value("Main.s.y") == 2 * 7  # the old code runs on


def test_a_context_saved_after_an_adopting_reload_restores_warm() -> None:
    h = running()
    reload_switch.finish(h.resource, prepared(h, ONE_POU))
    h.cycle()
    context = take_context(h.resource)
    assert context is not None
    fresh = harness(ONE_POU, start=False)
    warm_start(fresh.resource, context)
    assert fresh.resource.variables.values() == h.resource.variables.values()
    assert state(fresh.resource) == state(h.resource)


TWO_PROGRAMS = [{"name": "Main"}, {"name": "Other", "pou": "OtherPou"}]
OTHER = """
PROGRAM OtherPou
VAR_EXTERNAL total : DINT; points : ARRAY[1..3] OF Point; END_VAR
VAR seen : DINT; END_VAR
seen := total + points[2].x;
END_PROGRAM
"""


@pytest.mark.parametrize("text", [ONE_POU, EVERYTHING], ids=["one POU", "everything"])
def test_two_programs_see_the_globals_as_before(text: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """With two programs each has its own view of the globals, filled from them."""
    adopted, copied = harness(PLANT + OTHER, TWO_PROGRAMS), harness(PLANT + OTHER, TWO_PROGRAMS)
    adopted.cycle(6)
    copied.cycle(6)
    new = compiled(text + OTHER, TWO_PROGRAMS)
    assert reload_switch.reload(adopted.resource, new, {})
    with monkeypatch.context() as patch:
        copy_only(patch)
        assert reload_switch.reload(copied.resource, new, {})
    for _ in range(4):
        assert state(adopted.resource) == state(copied.resource)
        views = [snapshot(p.view) for p in adopted.resource.programs]
        assert views == [snapshot(p.view) for p in copied.resource.programs]
        assert adopted.cycle() == copied.cycle()
    assert (
        adopted.value("Other.seen") == adopted.value("total") - 1 + adopted.value("points[2].x") - 1
    )


@pytest.mark.parametrize("text", [ONE_POU, SMALL_LAYOUT], ids=["one POU", "one layout"])
def test_cycles_between_preparing_and_switching_are_carried(text: str) -> None:
    """The cycles go on while a reload prepares: the switch-over takes the objects and
    values as they are then (a struct assignment makes a new object every cycle)."""
    h = running()
    job = prepared(h, text)
    h.cycle(2)
    before = state(h.resource)
    reload_switch.finish(h.resource, job)
    assert without(state(h.resource), {"k"}) == before
    assert h.value("Main.last.x") == h.value("Main.n") == 8
