"""The CPU cycle with several user programs: priorities, time slices that suspend a program
and resume it where it stopped, the program watchdog, multitasking modes, and the rule
that another program sees a program's writes to globals one CPU cycle later at the
earliest. Everything runs on virtual time, where one loop pass costs 1 us."""

from __future__ import annotations

from tests.support.resource_harness import harness

ORDER = """
VAR_GLOBAL order : STRING[40]; END_VAR
PROGRAM A VAR_EXTERNAL order : STRING[40]; END_VAR order := CONCAT(order, 'A'); END_PROGRAM
PROGRAM B VAR_EXTERNAL order : STRING[40]; END_VAR order := CONCAT(order, 'B'); END_PROGRAM
"""


def test_programs_run_by_priority_zero_first() -> None:
    # one writer per global, so the two programs log into their own strings
    text = """
    VAR_GLOBAL log : STRING[40]; END_VAR
    PROGRAM Low VAR n : INT; END_VAR n := n + 1; END_PROGRAM
    PROGRAM High VAR n : INT; END_VAR n := n + 1; END_PROGRAM
    """
    h = harness(text, [{"name": "Low", "priority": 5}, {"name": "High", "priority": 0}])
    assert [p.name for p in h.resource.status().programs] == ["High", "Low"]
    h.cycle(3)
    assert (h.value("High.n"), h.value("Low.n")) == (3, 3)


# A program that counts to 10 with one loop pass per count: 10 us of virtual work.
COUNTER = """
VAR_GLOBAL done : DINT; END_VAR
PROGRAM Worker
VAR_EXTERNAL done : DINT; END_VAR
VAR i, k : DINT; started : DINT; END_VAR
started := started + 1;
FOR i := 1 TO 10 DO
  k := k + 1;
END_FOR;
done := done + 1;
END_PROGRAM
PROGRAM Watcher
VAR_EXTERNAL done : DINT; END_VAR
VAR seen : DINT; END_VAR
seen := done;
END_PROGRAM
"""


def test_a_program_over_its_slice_resumes_where_it_stopped() -> None:
    # 4 us per CPU cycle: the ten passes take three CPU cycles (4 + 4 + 2)
    h = harness(
        COUNTER,
        [{"name": "Worker", "max_duration_us": 4, "max_cycles": 5}, {"name": "Watcher"}],
    )
    h.cycle()
    assert (h.value("Worker.started"), h.value("Worker.k")) == (1, 4)
    assert h.value("done") == 0
    h.cycle()
    assert (h.value("Worker.started"), h.value("Worker.k")) == (1, 8)  # not restarted
    h.cycle()
    assert (h.value("Worker.k"), h.value("done")) == (10, 1)  # the program cycle ended
    assert h.value("Watcher.seen") == 0  # published at the end of that CPU cycle
    h.cycle()
    assert h.value("Watcher.seen") == 1  # ... so seen one CPU cycle later
    assert (h.value("Worker.started"), h.value("Worker.k")) == (2, 14)
    program = next(p for p in h.resource.status().programs if p.name == "Worker")
    assert program.cpu_cycles_max == 3


def test_the_program_watchdog_puts_only_that_program_in_error() -> None:
    # ten passes need three slices of 4 us; Max. Cycles 2 is not enough
    h = harness(
        COUNTER,
        [{"name": "Worker", "max_duration_us": 4, "max_cycles": 2}, {"name": "Watcher"}],
    )
    h.cycle(2)
    assert h.state("Worker") == "ERROR"
    assert h.state("Watcher") == "RUN"
    assert h.state() == "RUN"
    error = next(p for p in h.resource.status().programs if p.name == "Worker").error
    assert "program watchdog" in str(error)
    events = h.ok("events")["events"]
    assert any(e["kind"] == "error" and "Worker" in e["message"] for e in events)
    assert h.value("done") == 0  # the half-done program cycle is never published


def test_an_endless_loop_in_a_sliced_program_is_a_program_error_not_a_halt() -> None:
    text = """
    PROGRAM Spin VAR n : DINT; END_VAR WHILE TRUE DO n := n + 1; END_WHILE; END_PROGRAM
    PROGRAM Tick VAR n : DINT; END_VAR n := n + 1; END_PROGRAM
    """
    h = harness(text, [{"name": "Spin", "max_duration_us": 50, "max_cycles": 3}, {"name": "Tick"}])
    h.cycle(2)
    assert h.value("Spin.n") == 100  # 50 passes per CPU cycle, suspended each time
    h.cycle(2)
    assert h.state("Spin") == "ERROR"
    assert h.value("Tick.n") == 4  # the other program never missed a cycle
    assert h.state() == "RUN"


def test_mode_2_gives_unused_time_to_the_unfinished_program() -> None:
    text = """
    PROGRAM Quick VAR n : DINT; END_VAR n := n + 1; END_PROGRAM
    PROGRAM Long VAR i, k : DINT; END_VAR FOR i := 1 TO 10 DO k := k + 1; END_FOR; END_PROGRAM
    """
    programs = [
        {"name": "Long", "max_duration_us": 4, "max_cycles": 5},
        {"name": "Quick", "priority": 1, "max_duration_us": 8},
    ]
    mode1 = harness(text, programs, multitasking_mode=1)
    mode2 = harness(text, programs, multitasking_mode=2)
    mode1.cycle()
    mode2.cycle()
    assert mode1.value("Long.k") == 4  # its own slice only
    assert mode2.value("Long.k") == 10  # plus the 8 us Quick left unused (it used none)


def test_mode_3_makes_every_cycle_as_long_as_the_slices() -> None:
    text = """
    PROGRAM Quick VAR n : DINT; END_VAR n := n + 1; END_PROGRAM
    PROGRAM Other VAR n : DINT; END_VAR n := n + 1; END_PROGRAM
    """
    programs = [
        {"name": "Quick", "max_duration_us": 300},
        {"name": "Other", "max_duration_us": 200},
    ]
    mode1 = harness(text, programs, multitasking_mode=1)
    mode3 = harness(text, programs, multitasking_mode=3)
    mode1.cycle(3)
    mode3.cycle(3)
    assert mode1.resource.stats.max_ns == 0  # no loop passes: no virtual time used
    assert mode3.resource.stats.min_ns == mode3.resource.stats.max_ns == 500_000


def test_globals_seen_at_the_start_of_the_program_cycle() -> None:
    # Writer counts every CPU cycle; Reader reads it twice in one program cycle that
    # spans two CPU cycles: both reads give the value of its cycle's start
    text = """
    VAR_GLOBAL count : DINT; END_VAR
    PROGRAM Writer VAR_EXTERNAL count : DINT; END_VAR count := count + 1; END_PROGRAM
    PROGRAM Reader
    VAR_EXTERNAL count : DINT; END_VAR
    VAR first, second, i, k : DINT; END_VAR
    first := count;
    FOR i := 1 TO 6 DO k := k + 1; END_FOR;
    second := count;
    END_PROGRAM
    """
    h = harness(
        text,
        [
            {"name": "Writer"},
            {"name": "Reader", "priority": 1, "max_duration_us": 4, "max_cycles": 2},
        ],
    )
    h.cycle(4)
    assert h.value("count") == 4
    assert h.value("Reader.first") == h.value("Reader.second") == 2


def test_an_olt_write_to_a_global_reaches_every_program() -> None:
    text = """
    VAR_GLOBAL limit : INT := 5; END_VAR
    PROGRAM P1 VAR_EXTERNAL limit : INT; END_VAR VAR seen : INT; END_VAR seen := limit; END_PROGRAM
    PROGRAM P2 VAR_EXTERNAL limit : INT; END_VAR VAR seen : INT; END_VAR seen := limit; END_PROGRAM
    """
    h = harness(text, [{"name": "P1"}, {"name": "P2"}])
    h.cycle()
    h.ok("write", variable="limit", value=9)
    h.cycle()
    assert (h.value("P1.seen"), h.value("P2.seen")) == (9, 9)
