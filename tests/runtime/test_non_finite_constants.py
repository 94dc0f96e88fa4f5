"""rusty's INF_REAL, NAN_REAL, INF_LREAL, NAN_LREAL (W0808, docs/language.md) in the
runtime's world: the artifact stays strict JSON, the online values and a watch set show them
as the text `inf`, `-inf`, `nan`, a saved context is strict JSON (their bits) and a warm
start gives them back."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.context import ContextInvalid, load_context, save_context
from runtime.contract.values import format_for_display, format_value
from runtime.resource import Resource
from runtime.restart import take_context, warm_start
from tests.support.resource_harness import compiled, harness

PLANT = """
VAR_GLOBAL CONSTANT
  ceiling : LREAL := INF_LREAL;
END_VAR
PROGRAM Main
VAR
  top : REAL := INF_REAL;
  bottom : LREAL;
  unknown : REAL;
  samples : ARRAY[1..2] OF REAL := [NAN_REAL, 1.5];
  is_nan, is_top : BOOL;
END_VAR
bottom := -ceiling;
unknown := NAN_REAL;
is_nan := unknown <> unknown;
is_top := top = INF_REAL;
END_PROGRAM
"""


def strict(text: str) -> Any:
    """JSON as any other parser reads it: NaN and Infinity are no JSON."""

    def refuse(constant: str) -> None:
        raise AssertionError(f"{constant} in JSON")

    return json.loads(text, parse_constant=refuse)


def test_the_constants_compile_with_a_warning_and_a_strict_json_artifact() -> None:
    result = compile_sources([SourceFile("t.st", PLANT)])
    warned = [str(d) for d in result.diagnostics]
    assert warned[0] == (
        "t.st:3:22: warning: 'INF_LREAL', the LREAL infinity, is a constant of rusty; "
        "IEC 61131-3 has no way to write it [W0808]"
    )
    assert {d.code for d in result.diagnostics} == {"W0808"} and len(warned) == 5
    assert result.artifact is not None
    strict(result.artifact.to_json())


def test_the_online_values_and_a_watch_set_show_them_as_text() -> None:
    h = harness(PLANT)
    h.cycle()
    values = h.ok("values")["values"]
    assert (values["Main.top"], values["Main.bottom"], values["Main.unknown"]) == (
        "inf",
        "-inf",
        "nan",
    )
    assert values["Main.samples"] == ["nan", 1.5] and values["ceiling"] == "inf"
    assert values["Main.is_nan"] is True and values["Main.is_top"] is True
    assert format_value(h.value("Main.bottom"), "LREAL") == "-inf"
    # what the OLT shows, from the values as they arrived: a number, not a quoted text
    shown = [format_for_display(values[name], "REAL") for name in ("Main.top", "Main.unknown")]
    assert shown == ["inf", "nan"]

    h.ok("watch", id="w", variables=["Main.top", "Main.unknown", "Main.samples"])
    watch_set = h.resource.online.watches.get("w")
    assert watch_set is not None
    snapshot = h.resource.online.snapshot(watch_set, 1, True, h.resource.forcing.table)
    assert strict(snapshot.message().decode())["values"] == ["inf", "nan", ["nan", 1.5]]


def test_a_saved_context_is_strict_json_and_a_warm_start_gives_them_back(
    tmp_path: Path,
) -> None:
    h = harness(PLANT)
    h.cycle(2)
    context = take_context(h.resource)
    assert context is not None
    save_context(tmp_path / "context.json", context)
    header, body = (tmp_path / "context.json").read_text().splitlines()  # two documents
    strict(header)
    assert strict(body)["programs"]["Main"]["values"]["v"]["top"] == {"ieee": "7ff0000000000000"}

    artifact = compiled(PLANT)
    again = Resource("R", h.clock)
    again.load(artifact)
    saved = load_context(tmp_path / "context.json", artifact.crc)
    assert not isinstance(saved, ContextInvalid), saved
    warm_start(again, saved)
    assert again.variables.value("Main.top") == math.inf
    assert again.variables.value("Main.bottom") == -math.inf
    assert math.isnan(again.variables.value("Main.unknown"))
