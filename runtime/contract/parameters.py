"""Resource and user-program parameters: defaults, ranges, and which ones change online.

One table per level drives everything that touches parameters: the project loader checks a
`padt.toml` against it, the runtime checks online changes against it, and docs/parameters.md
restates it. Values live in `ResourceConfig` / `ProgramConfig` (runtime/artifact.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

TARGET_CYCLE_MODES = ("fixed", "fixed-tolerant", "dynamic", "dynamic-tolerant")
AUTOSTART_MODES = ("off", "cold", "warm")
GLOBAL_FORCE_REACTIONS = ("stop-forcing", "stop-resource")
LOCAL_FORCE_REACTIONS = ("stop-forcing", "stop-program")


class ParameterError(ValueError):
    """A parameter value outside its range, of the wrong type, or not changeable online."""


@dataclass(frozen=True)
class ParameterSpec:
    name: str  # as in padt.toml and the artifact
    kind: type  # int, bool or str
    low: int | None = None
    high: int | None = None
    choices: tuple[str, ...] = ()
    online: bool = False  # changeable while the resource runs (Allow Online Settings ON)
    administrator: bool = False  # only an Administrator changes it

    def check(self, value: Any) -> Any:
        """The value if it is valid for this parameter, else ParameterError saying why."""
        if self.kind is bool:
            if not isinstance(value, bool):
                raise ParameterError(f"{self.name} must be true or false, not {value!r}")
            return value
        if self.kind is int:
            if isinstance(value, bool) or not isinstance(value, int):
                raise ParameterError(f"{self.name} must be an integer, not {value!r}")
            if (self.low is not None and value < self.low) or (
                self.high is not None and value > self.high
            ):
                raise ParameterError(f"{self.name} must be from {self.low} to {self.high}")
            return value
        if value not in self.choices:
            raise ParameterError(f"{self.name} must be one of {', '.join(self.choices)}")
        return value


RESOURCE_PARAMETERS: tuple[ParameterSpec, ...] = (
    ParameterSpec("safety_time_ms", int, 20, 22_500),
    ParameterSpec("watchdog_ms", int, 6, 7_500, online=True),
    ParameterSpec("target_cycle_ms", int, 0, 7_500, online=True),
    ParameterSpec("target_cycle_mode", str, choices=TARGET_CYCLE_MODES, online=True),
    ParameterSpec("multitasking_mode", int, 1, 3),
    ParameterSpec("com_slice_ms", int, 1, 5_000, online=True),
    ParameterSpec("allow_online_settings", bool, online=True, administrator=True),
    ParameterSpec("autostart", str, choices=AUTOSTART_MODES),
    ParameterSpec("start_allowed", bool),
    ParameterSpec("load_allowed", bool),
    ParameterSpec("reload_allowed", bool),
    ParameterSpec("global_forcing_allowed", bool),
    ParameterSpec("global_force_timeout_reaction", str, choices=GLOBAL_FORCE_REACTIONS),
    ParameterSpec("safety_operation", bool),
)

PROGRAM_PARAMETERS: tuple[ParameterSpec, ...] = (
    ParameterSpec("program_id", int, 1, 32),
    ParameterSpec("priority", int, 0, 31),
    ParameterSpec("max_duration_us", int, 0, 7_500_000),
    ParameterSpec("max_cycles", int, 1, 1_000_000),
    ParameterSpec("start_allowed", bool),
    ParameterSpec("freeze_allowed", bool),
    ParameterSpec("reload_allowed", bool),
    ParameterSpec("local_forcing_allowed", bool),
    ParameterSpec("local_force_timeout_reaction", str, choices=LOCAL_FORCE_REACTIONS),
    ParameterSpec("safety_related", bool),
)

RESOURCE_BY_NAME = {spec.name: spec for spec in RESOURCE_PARAMETERS}
PROGRAM_BY_NAME = {spec.name: spec for spec in PROGRAM_PARAMETERS}


def resource_consistency(values: dict[str, Any]) -> list[str]:
    """Rules between resource parameters (each problem as one sentence)."""
    problems = []
    if values["watchdog_ms"] * 2 > values["safety_time_ms"]:
        problems.append(
            f"watchdog_ms {values['watchdog_ms']} is more than half the safety time "
            f"({values['safety_time_ms']} ms)"
        )
    target, watchdog = values["target_cycle_ms"], values["watchdog_ms"]
    if target and target > watchdog:
        problems.append(
            f"target_cycle_ms {target} is longer than the watchdog time ({watchdog} ms)"
        )
    return problems
