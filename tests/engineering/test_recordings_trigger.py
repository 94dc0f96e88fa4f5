"""A recording's trigger as an engineer types it (`padt record --trigger`, the REST body,
the Trends screen): an ST condition read into the protocol's Trigger, and a clear error
for anything else."""

from __future__ import annotations

import pytest

from backend.engineering.recordings import (
    RecordingSpec,
    TriggerError,
    parse_trigger,
)
from runtime.contract.protocol import RecordStart, Trigger, decode_request, encode_request


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("Main.level > 80", Trigger("Main.level", ">", 80)),
        ("Main.alarm", Trigger("Main.alarm", "=", True)),
        ("NOT Main.alarm", Trigger("Main.alarm", "=", False)),
        ("  not   Tank.full ", Trigger("Tank.full", "=", False)),
        ("Main.alarm = FALSE", Trigger("Main.alarm", "=", False)),
        ("Main.alarm<>BOOL#true", Trigger("Main.alarm", "<>", True)),
        ("Main.level>=-2.5", Trigger("Main.level", ">=", -2.5)),
        ("Main.level <= 1.5e3", Trigger("Main.level", "<=", 1500.0)),
        ("Main.count < 16#FF", Trigger("Main.count", "<", 255)),
        ("Main.count = INT#-7", Trigger("Main.count", "=", -7)),
        ("Main.count = 1", Trigger("Main.count", "=", 1)),  # a number, not TRUE
        ("Main.t >= T#1m5s", Trigger("Main.t", ">=", 65 * 10**9)),
        ("Main.t > TIME#20ms", Trigger("Main.t", ">", 20 * 10**6)),
        ("Main.state = 'open = shut'", Trigger("Main.state", "=", "open = shut")),
        ("Main.fb.Q", Trigger("Main.fb.Q", "=", True)),
        ("Main.bits[3] <> 0", Trigger("Main.bits[3]", "<>", 0)),
    ],
)
def test_conditions_an_engineer_writes(text: str, expected: Trigger) -> None:
    assert parse_trigger(text) == expected
    # and the resource's decoder takes it as the engineer meant it
    command = RecordStart(["Main.level"], trigger=parse_trigger(text))
    assert decode_request(encode_request(command, None)).command == command


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("", "is not a trigger"),
        ("NOT", "is not a trigger"),
        ("TRUE", "is not a trigger"),
        ("Main.level >", "is not a trigger"),
        ("Main.level >> 80", "> 80 is not an ST literal"),
        ("Main.level == 80", "= 80 is not an ST literal"),
        ("Main.level > high", "high is not an ST literal"),
        ("Main.level > 80 AND Main.run", "80 AND Main.run is not an ST literal"),
        ("80 < Main.level", "is not a trigger"),
        ("Main.alarm OR Main.fault", "is not a trigger"),
        ("NOT Main.alarm = TRUE", "is not a trigger"),
        ("Main.state = 'open", "'open is not an ST literal"),
        ("Main.t > T#5parsecs", "is not an ST literal"),
    ],
)
def test_anything_else_is_refused_with_what_a_trigger_looks_like(text: str, says: str) -> None:
    with pytest.raises(TriggerError) as refused:
        parse_trigger(text)
    message = str(refused.value)
    assert says in message
    assert "OP one of = <> < <= > >=" in message


def test_a_spec_becomes_the_command_and_a_bad_trigger_stops_it_before_it_is_sent() -> None:
    spec = RecordingSpec(("Main*",), trigger="Main.level > 80", pre_cycles=10, cycles=50)
    command = spec.command()
    assert command.trigger == Trigger("Main.level", ">", 80)
    assert (command.variables, command.pre_cycles, command.cycles) == (["Main*"], 10, 50)
    with pytest.raises(TriggerError):
        RecordingSpec(("Main*",), trigger="Main.level >>> 3").command()
