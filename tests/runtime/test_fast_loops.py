"""What the faster FOR loop (a counted loop: constant end and step, the counter in a Python
local; without a loop inside, a Python `for` over a range while no slice is metered) and
the inline bounds check must keep: the counter's value after the loop, also past
the end of its type; a write to the counter from outside while a sliced program is
suspended in the loop; a body or a call that writes the counter; an index
outside the bounds as a program fault at its ST line; the resource watchdog ending an
endless loop and naming where it was."""

from __future__ import annotations

from tests.support.resource_harness import Harness, harness


def _generated(h: Harness, pou: str) -> str:
    artifact = h.resource.artifact
    assert artifact is not None
    return next(p.source for p in artifact.pous if p.name == pou)


def test_the_counter_after_a_counted_loop_and_past_the_end_of_its_type() -> None:
    text = """
    PROGRAM P
    VAR i, n : INT; s : SINT; m : INT; u : USINT; q : INT; empty : INT := 7; e : INT; END_VAR
    n := 0; FOR i := 1 TO 10 DO n := n + i; END_FOR;
    (* the step past 127 wraps: the loop ends with the wrapped value, as the plain loop *)
    m := 0; FOR s := 120 TO 127 DO m := m + 1; END_FOR;
    q := 0; FOR u := 3 TO 0 BY -1 DO q := q + 1; END_FOR;
    e := 0; FOR empty := 5 TO 1 DO e := e + 1; END_FOR;
    END_PROGRAM
    """
    h = harness(text, [{"name": "P"}])
    h.cycle()
    assert (h.value("P.i"), h.value("P.n")) == (11, 55)
    assert (h.value("P.s"), h.value("P.m")) == (-128, 8)
    assert (h.value("P.u"), h.value("P.q")) == (255, 4)
    assert (h.value("P.empty"), h.value("P.e")) == (5, 0)  # no pass: the start value
    assert "while __t" in _generated(h, "P")  # the counted form, not `while s.i <= ...`


def test_a_counter_the_body_writes_keeps_the_plain_loop() -> None:
    text = """
    PROGRAM P
    VAR i, n : INT; END_VAR
    n := 0;
    FOR i := 1 TO 10 DO i := i + 1; n := n + 1; END_FOR;
    END_PROGRAM
    """
    h = harness(text, [{"name": "P"}])
    h.cycle()
    assert (h.value("P.i"), h.value("P.n")) == (11, 5)
    assert "while s.i <= 10:" in _generated(h, "P")


def test_a_counter_a_call_writes_through_in_out_keeps_the_plain_loop() -> None:
    text = """
    FUNCTION_BLOCK Bump
    VAR_IN_OUT x : INT; END_VAR
    x := 100;
    END_FUNCTION_BLOCK
    PROGRAM P
    VAR k, n : INT; b : Bump; END_VAR
    n := 0;
    FOR k := 1 TO 10 DO n := n + 1; b(x := k); END_FOR;
    END_PROGRAM
    """
    h = harness(text, [{"name": "P"}])
    h.cycle()
    assert (h.value("P.k"), h.value("P.n")) == (101, 1)


def test_a_write_while_suspended_in_a_counted_loop_is_taken_over() -> None:
    # 4 us per CPU cycle, one pass per us: suspended after k = 4 (its 4th pass done)
    text = """
    PROGRAM Worker
    VAR k, passes : DINT; END_VAR
    passes := 0;
    FOR k := 1 TO 20 DO passes := passes + 1; END_FOR;
    END_PROGRAM
    """
    h = harness(text, [{"name": "Worker", "max_duration_us": 4, "max_cycles": 10}])
    h.cycle()
    assert (h.value("Worker.k"), h.value("Worker.passes")) == (5, 4)
    h.ok("write", variable="Worker.k", value=17)  # between two CPU cycles
    h.cycle()
    # the loop goes on from 17: passes 17, 18, 19, 20, then it ends
    assert (h.value("Worker.k"), h.value("Worker.passes")) == (21, 8)


def test_an_index_outside_the_bounds_in_a_loop_is_a_fault_at_its_line() -> None:
    text = """PROGRAM P
VAR a : ARRAY[1..5] OF INT; i : INT; END_VAR
FOR i := 0 TO 5 DO
  a[i] := i;
END_FOR;
END_PROGRAM
"""
    h = harness(text, [{"name": "P"}])
    h.cycle()
    assert h.state("P") == "ERROR"
    error = next(p for p in h.resource.status().programs if p.name == "P").error
    assert "0" in str(error) and "test.st:4" in str(error), error


def test_the_watchdog_ends_an_endless_loop_and_names_its_line() -> None:
    text = """PROGRAM P
VAR n : DINT; END_VAR
WHILE TRUE DO
  n := n + 1;
END_WHILE;
END_PROGRAM
"""
    h = harness(text, [{"name": "P"}], watchdog_ms=20, safety_time_ms=40)
    h.cycle()
    assert h.state() == "ERROR STOP"
    assert "watchdog" in str(h.resource.error) and "test.st:" in str(h.resource.error)


def test_a_loop_condition_with_a_call_of_outputs_is_evaluated_for_every_test() -> None:
    # the call is hoisted out of the condition (its output is stored first): it belongs in
    # the loop, so that WHILE and the end of FOR see the values of this pass
    text = """
    FUNCTION Echo : INT
    VAR_INPUT x : INT; END_VAR
    VAR_OUTPUT y : INT; END_VAR
    y := x; Echo := x;
    END_FUNCTION
    PROGRAM P
    VAR n, o, i, limit, passes : INT; END_VAR
    n := 0;
    WHILE Echo(x := n, y => o) < 5 DO n := n + 1; END_WHILE;
    limit := 3; passes := 0;
    FOR i := 1 TO Echo(x := limit, y => o) DO limit := limit + 1; passes := passes + 1;
      IF passes > 20 THEN EXIT; END_IF;
    END_FOR;
    END_PROGRAM
    """
    h = harness(text, [{"name": "P"}])
    h.cycle()
    assert h.value("P.n") == 5  # once before the loop, it would never end
    # the end grows with every pass (evaluated at each test: the last before pass 21 saw
    # limit 23): EXIT ends it
    assert (h.value("P.passes"), h.value("P.o")) == (21, 23)


def test_a_loop_over_a_constant_range_needs_no_bounds_check_and_exit_keeps_the_counter() -> None:
    text = """
    PROGRAM P
    VAR a : ARRAY[1..5] OF INT; i, j, k : INT; n : INT; END_VAR
    FOR i := 1 TO 5 DO a[i] := i * 2; END_FOR;
    n := 0; FOR j := 1 TO 5 DO IF j = 3 THEN EXIT; END_IF; n := n + 1; END_FOR;
    FOR k := 10 TO 1 BY -3 DO n := n + k; END_FOR;
    END_PROGRAM
    """
    h = harness(text, [{"name": "P"}])
    h.cycle()
    assert h.value("P.a") == [2, 4, 6, 8, 10] and h.value("P.i") == 6
    assert (h.value("P.j"), h.value("P.k")) == (3, -2)  # EXIT at 3; 10, 7, 4, 1, then -2
    assert h.value("P.n") == 2 + 10 + 7 + 4 + 1
    generated = _generated(h, "P")
    assert "for __t" in generated and "s.a[__t" in generated  # the counter indexes unchecked
    assert "_ix(" not in generated.split("else:")[0]


def test_a_fault_in_a_pass_leaves_the_counter_at_that_pass() -> None:
    text = """PROGRAM P
VAR i, n : INT; END_VAR
FOR i := 1 TO 5 DO
  n := 10 / (3 - i);
END_FOR;
END_PROGRAM
"""
    h = harness(text, [{"name": "P"}])
    h.cycle()
    assert h.state("P") == "ERROR"
    assert (h.value("P.i"), h.value("P.n")) == (3, 10)  # as the tree-walking oracle has it
