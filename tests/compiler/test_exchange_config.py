"""The `[exchange]` settings of padt.toml: checked with the line of the setting and a code,
carried in the artifact as the runtime needs them (backend/compiler/checks/exchange.py,
docs/exchange.md)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from backend.compiler.pipeline import CompileResult
from backend.engineering.project import compile_project, load_project
from runtime.contract.artifact import ArtifactError, load_artifact
from runtime.contract.exchange import ExchangeConfig, ExchangePoint, Publication, Published
from runtime.reload_plan import plan_reload

SOURCE = """
TYPE Pair : STRUCT a : INT; b : INT; END_STRUCT; END_TYPE
VAR_GLOBAL
    level : REAL;
    running : BOOL;
    label : STRING[12];
    pair : Pair;
    remoteLevel : REAL;
    remoteLabel : STRING[12];
    remoteCount : UDINT;
    written : INT;
    sensor AT %IW3 : INT;
END_VAR
VAR_GLOBAL CONSTANT limit : INT := 3; END_VAR
PROGRAM Main
VAR_EXTERNAL written : INT; level : REAL; END_VAR
written := 1;
level := level + 0.5;
END_PROGRAM
"""
HEAD = '[project]\nname = "p"\n[resource]\nname = "Tank2"\n'


def _compile(tmp_path: Path, settings: str) -> CompileResult:
    folder = tmp_path / "project"
    folder.mkdir(exist_ok=True)
    (folder / "padt.toml").write_text(HEAD + settings)
    (folder / "main.st").write_text(SOURCE)
    return compile_project(load_project([folder]))


def test_publications_and_subscriptions_in_the_artifact(tmp_path: Path) -> None:
    result = _compile(
        tmp_path,
        """
[[exchange.publish]]
name = "state"
variables = ["RUNNING", "level", "label"]
[[exchange.publish]]
name = "fast"
variables = ["level"]
period_ms = 10

[[exchange.subscribe]]
resource = "Tank1"
publication = "levels"
timeout_ms = 250
[[exchange.subscribe.variable]]
variable = "remotelevel"
from = "level"
safe_value = -1.0
[[exchange.subscribe.variable]]
variable = "remoteLabel"
from = "label"
[[exchange.subscribe.variable]]
variable = "remoteCount"
""",
    )
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    exchange = result.artifact.exchange
    assert exchange == ExchangeConfig(
        publications=(
            Publication("fast", (Published("level", "REAL"),), 10),
            Publication(
                "state",
                (
                    Published("label", "STRING[12]"),
                    Published("level", "REAL"),
                    Published("running", "BOOL"),
                ),
                100,
            ),
        ),
        subscriptions=(exchange.subscriptions[0],) if exchange else (),
    )
    assert exchange is not None
    subscription = exchange.subscriptions[0]
    assert (subscription.resource, subscription.publication, subscription.timeout_ms) == (
        "Tank1", "levels", 250,
    )  # fmt: skip
    # as declared, sorted; the source defaults to the variable's name; safe values default
    # to 0 / empty of the type
    assert subscription.points == (
        ExchangePoint("remoteCount", "UDINT", "remoteCount", 0),
        ExchangePoint("remoteLabel", "STRING[12]", "label", ""),
        ExchangePoint("remoteLevel", "REAL", "level", -1.0),
    )
    again = load_artifact(result.artifact.to_json())
    assert again.exchange == exchange and again.crc == result.artifact.crc


def test_no_exchange_keeps_the_crc(tmp_path: Path) -> None:
    without = _compile(tmp_path, "")
    empty = _compile(tmp_path, "[exchange]\n")
    assert without.artifact is not None and empty.artifact is not None
    assert without.artifact.exchange is None and empty.artifact.exchange is None
    assert '"exchange"' not in without.artifact.body_json()
    assert without.artifact.crc == empty.artifact.crc


def test_every_problem_at_its_line(tmp_path: Path) -> None:
    settings = """
[exchange]
publsh = []
[[exchange.publish]]
name = "a/b"
variables = ["level"]
[[exchange.publish]]
name = "ok"
variables = ["nothing", "pair", "level"]
period_ms = 5

[[exchange.subscribe]]
resource = "Tank2"
publication = "x"
[[exchange.subscribe.variable]]
variable = "remoteLevel"

[[exchange.subscribe]]
resource = "Tank1"
publication = "levels"
[[exchange.subscribe.variable]]
variable = "written"
[[exchange.subscribe.variable]]
variable = "limit"
[[exchange.subscribe.variable]]
variable = "remoteLevel"
safe_value = "high"
[[exchange.subscribe.variable]]
variable = "remoteCount"
safe_value = -1
[[exchange.subscribe.variable]]
variable = "sensor"

[[exchange.subscribe]]
resource = "Tank3"
publication = "levels"
[[exchange.subscribe.variable]]
variable = "remoteLabel"
[[exchange.subscribe.variable]]
variable = "remoteLabel"
"""
    result = _compile(tmp_path, settings)
    assert result.artifact is None
    found = [(d.code, d.line, d.message) for d in result.diagnostics]
    text = (HEAD + settings).splitlines()

    def line(fragment: str, after: int = 0) -> int:
        return next(i + 1 for i, t in enumerate(text) if i >= after and fragment in t)

    expected = {
        ("E0628", line("publsh")),  # an unknown key
        ("E0628", line('name = "a/b"')),  # no plain chunk of a key
        ("E0629", line('variables = ["nothing"')),  # no global; a structure
        ("E0628", line("period_ms = 5")),
        ("E0628", line('resource = "Tank2"')),  # this resource itself
        ("E0629", line('variable = "written"')),  # a program writes it
        ("E0629", line('variable = "limit"')),  # a CONSTANT
        ("E0628", line('safe_value = "high"')),
        ("E0628", line("safe_value = -1")),  # no UDINT
        ("E0629", line('variable = "sensor"')),  # located: the field delivers it
        ("E0629", line('variable = "remoteLabel"', line('variable = "remoteLabel"'))),
    }
    assert {(code, at) for code, at, _ in found} == expected, found
    messages = " | ".join(message for *_, message in found)
    assert "'nothing' is no global variable" in messages
    assert "only elementary variables are exchanged" in messages
    assert "'Tank2' is this resource" in messages
    assert "written by a user program" in messages
    assert "already takes the values of Tank3/levels" in messages


def test_the_reload_plan_says_what_a_changed_exchange_does(tmp_path: Path) -> None:
    before = """
[[exchange.publish]]
name = "state"
variables = ["running", "level"]
[[exchange.subscribe]]
resource = "Tank1"
publication = "levels"
[[exchange.subscribe.variable]]
variable = "remoteLevel"
"""
    after = """
[[exchange.publish]]
name = "state"
variables = ["running"]
[[exchange.subscribe]]
resource = "Tank3"
publication = "labels"
[[exchange.subscribe.variable]]
variable = "remoteLabel"
"""
    old, new = _compile(tmp_path, before).artifact, _compile(tmp_path, after).artifact
    assert old is not None and new is not None
    hazards = {(h.kind, h.instance): h.message for h in plan_reload(old, new).hazards}
    assert hazards == {
        ("exchange-subscribed", "Tank3/labels"): (
            "remoteLabel: safe values until the next message of Tank3/labels "
            "(within its publisher's period)"
        ),
        ("exchange-unsubscribed", "Tank1/levels"): (
            "remoteLevel: the last values stay, no longer updated from Tank1/levels"
        ),
        ("exchange-publication-changed", "state"): (
            "loses variables: a subscriber that takes one of them refuses its messages and "
            "takes its safe values"
        ),
    }
    assert plan_reload(old, old).hazards == ()


@pytest.mark.parametrize(
    "crafted",
    [
        {"resource": "Tank1/**"},  # a wildcard that would reach every resource's keys
        {"publication": "a/b"},
        {"timeout_ms": 0},
        {"points": (ExchangePoint("remoteLevel", "REAL", "level", "high"),)},
        {"points": (ExchangePoint("remoteLevel", "REF_TO INT", "level", 0),)},
    ],
    ids=["wildcard", "key chunk", "timeout", "safe value", "reference"],
)
def test_a_crafted_exchange_in_an_artifact_is_refused(
    tmp_path: Path, crafted: dict[str, Any]
) -> None:
    """A CRC is no signature: the runtime checks what an artifact's exchange says before it
    uses any of it (a download of a crafted artifact is refused whole)."""
    result = _compile(
        tmp_path,
        '[[exchange.subscribe]]\nresource = "Tank1"\npublication = "levels"\n'
        '[[exchange.subscribe.variable]]\nvariable = "remoteLevel"\n',
    )
    assert result.artifact is not None and result.artifact.exchange is not None
    subscription = replace(result.artifact.exchange.subscriptions[0], **crafted)
    exchange = replace(result.artifact.exchange, subscriptions=(subscription,))
    crafted_artifact = replace(result.artifact, exchange=exchange).with_crc()
    with pytest.raises(ArtifactError):
        load_artifact(crafted_artifact.to_json())
