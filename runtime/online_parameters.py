"""Online changes of resource parameters (spec section 6): only those the parameter table
marks online, only with Allow Online Settings ON (except that setting itself, which the
protocol reserves to an Administrator), each checked against its range and against the
others, each an event."""

from __future__ import annotations

import dataclasses

from runtime.contract.parameters import RESOURCE_BY_NAME, ParameterError, resource_consistency
from runtime.contract.refusal import Refusal
from runtime.resource import Resource


def set_parameter(resource: Resource, name: str, value: bool | int | str) -> None:
    spec = RESOURCE_BY_NAME.get(name)
    if spec is None:
        raise Refusal("unknown_parameter", f"no resource parameter '{name}'")
    if not spec.online:
        raise Refusal("not_online", f"{name} changes only with a download")
    if name != "allow_online_settings" and not resource.params.allow_online_settings:
        raise Refusal("not_allowed", "Allow Online Settings is OFF")
    try:
        checked = spec.check(value)
    except ParameterError as exc:
        raise Refusal("bad_value", str(exc)) from None
    changed = dataclasses.replace(resource.params, **{name: checked})
    problems = resource_consistency(changed.__dict__)
    if problems:
        raise Refusal("bad_value", problems[0])
    sliced = sum(p.config.max_duration_us for p in resource.programs)
    if sliced > changed.watchdog_ms * 1000:
        raise Refusal("bad_value", f"the programs' time slices ({sliced} us) exceed that watchdog")
    old = getattr(resource.params, name)
    resource.params = changed
    resource.system.WATCHDOG_TIME = resource.scheduler.watchdog_ns
    resource.recorder.record(
        "parameter", f"{name} changed from {old} to {checked}", name=name, old=old
    )
