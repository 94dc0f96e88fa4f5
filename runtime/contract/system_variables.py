"""The system variables: what ST reads (and partly writes) as `SYS.<NAME>`.

This table is the one definition both sides use: the compiler (which types `SYS.NAME` and
refuses writes to the read-only ones) and the runtime (which keeps the values in
`runtime.code.intrinsics.SystemView`, one attribute per entry, named as here). Generated code
reads and writes them as `_SYS.<NAME>`. Types are ST type names; the values have the
run-time representation of the artifact (BOOL as bool, TIME and DT as int nanoseconds, DT
counted from 1970-01-01, integers as int). `docs/language.md` documents the table.
"""

from __future__ import annotations

from dataclasses import dataclass

NAMESPACE = "SYS"


@dataclass(frozen=True)
class SystemVariable:
    name: str  # upper case: the ST name after `SYS.` and the attribute of SystemView
    type: str  # an elementary ST type name
    writable: bool  # by logic (and I/O); the others only the runtime sets
    meaning: str


SYSTEM_VARIABLES: tuple[SystemVariable, ...] = (
    SystemVariable("COLDSTART", "BOOL", False, "TRUE in the first cycle after a cold start"),
    SystemVariable("WARMSTART", "BOOL", False, "TRUE in the first cycle after a warm start"),
    SystemVariable("START_CYCLE", "BOOL", False, "TRUE in the first CPU cycle after any start"),
    SystemVariable("CYCLE_TIME_LAST", "TIME", False, "duration of the last CPU cycle"),
    SystemVariable("CYCLE_TIME_MIN", "TIME", False, "shortest CPU cycle since the start"),
    SystemVariable("CYCLE_TIME_MAX", "TIME", False, "longest CPU cycle since the start"),
    SystemVariable("CYCLE_TIME_MEAN", "TIME", False, "mean CPU cycle since the start"),
    SystemVariable("WATCHDOG_TIME", "TIME", False, "the resource's watchdog time"),
    SystemVariable(
        "SYSTEM_TICK", "UDINT", False, "milliseconds since the runtime started, wrapping at 2^32"
    ),
    SystemVariable("FORCE_TIME_REMAINING", "TIME", False, "remaining time of global forcing"),
    SystemVariable("CONFIGURATION_CRC", "DWORD", False, "CRC of the loaded configuration"),
    SystemVariable("DATE_AND_TIME", "DT", False, "date and time of the controller"),
    SystemVariable(
        "FORCE_DEACTIVATION", "BOOL", True, "FALSE -> TRUE ends all forcing and blocks new forcing"
    ),
    SystemVariable("RELOAD_DEACTIVATION", "BOOL", True, "TRUE blocks reload"),
    SystemVariable("READ_ONLY_IN_RUN", "BOOL", True, "TRUE blocks stop, start, load and reload"),
    SystemVariable("EMERGENCY_STOP_1", "BOOL", True, "TRUE puts the resource in ERROR STOP"),
    SystemVariable("EMERGENCY_STOP_2", "BOOL", True, "TRUE puts the resource in ERROR STOP"),
    SystemVariable("EMERGENCY_STOP_3", "BOOL", True, "TRUE puts the resource in ERROR STOP"),
    SystemVariable("EMERGENCY_STOP_4", "BOOL", True, "TRUE puts the resource in ERROR STOP"),
)

BY_NAME: dict[str, SystemVariable] = {v.name: v for v in SYSTEM_VARIABLES}


def initial_value(variable: SystemVariable) -> bool | int:
    """The value before the runtime sets one: FALSE or 0."""
    return False if variable.type == "BOOL" else 0
