"""The Reload screen's pure parts: the rename map as the user types it, the risks of a plan
to tick, and the plan and a failed preview as the user reads them."""

from __future__ import annotations

from frontend.screens import reload
from runtime.contract import protocol as p


def change(path: str, action: str, source: str | None = None, reason: str = "") -> p.VariableChange:
    return p.VariableChange(path, action, "INT", "INT", source, reason)


def plan(
    changes: list[p.VariableChange], hazards: list[p.Hazard] | None = None
) -> p.ReloadPlanInfo:
    summary = {fate: sum(c.action == fate for c in changes) for fate in reload.FATES}
    return p.ReloadPlanInfo(
        "AAAAAAAA", "BBBBBBBB", True, [], hazards or [], p.ProgramChanges([], [], ["P"]),
        summary, changes, 12.0,
    )  # fmt: skip


def test_the_rename_map_is_old_arrow_new_lines() -> None:
    text = "# carried over\nP.level -> P.tankLevel\n\n  P.fb->P.valve  \n"
    assert reload.parse_renames(text) == ({"P.tankLevel": "P.level", "P.valve": "P.fb"}, [])


def test_invalid_rename_lines_are_named_with_their_number() -> None:
    renames, errors = reload.parse_renames("P.a -> P.b\nP.a = P.c\nP.x -> p.X\nP.d -> P.B")
    assert errors == [
        "line 2: 'P.a = P.c' is not old -> new",
        "line 3: P.x is renamed to itself",
        "the rename map gives P.B twice",
    ]
    assert renames == {}


def test_each_loss_and_each_hazard_is_a_risk_of_its_own() -> None:
    hazard = p.Hazard("active-step-deleted", "P.chart", "step S2 of P.chart is active")
    risks = reload.risks(
        plan([change("P.a", "kept"), change("P.b", "deleted"), change("P.c", "deleted")], [hazard])
    )
    assert [risk.label for risk in risks] == [
        "Accept: 2 values deleted",
        "Accept hazard 1: active-step-deleted",
    ]
    assert risks[0].detail == "These are lost: P.b, P.c"
    assert risks[1].detail == "step S2 of P.chart is active"
    assert reload.risks(plan([change("P.a", "kept"), change("P.n", "new")])) == []


def test_the_table_filters_by_fate_and_says_where_each_value_comes_from() -> None:
    shown = plan(
        [
            change("P.a", "kept", "P.a"),
            change("P.new", "kept", "P.old", "renamed from P.old"),
            change("P.n", "new"),
            change("P.gone", "deleted"),
        ]
    )
    table = reload.render_table(shown, "all")
    # lost first, renamed before the plainly kept
    assert table.index("P.gone") < table.index("P.n") < table.index("P.new") < table.index("P.a<")
    assert "the value of P.old" in table and "its running value" in table
    assert "none: the value is lost" in table
    changed = reload.render_table(shown, "changed")
    assert 'data-fate="P.a"' not in changed and 'data-fate="P.gone"' in changed
    assert "No variable is converted" in reload.render_table(shown, "converted")


def test_a_compile_error_is_shown_as_file_line_col_code_message() -> None:
    shown = reload._failure(
        "compile",
        "the project does not compile",
        ["tank.st:18:20: error: '<x>' is not declared [E0201]"],
    )
    assert "tank.st:18:20</td>" in shown and ">E0201</td>" in shown
    assert "&#x27;&lt;x&gt;&#x27; is not declared" in shown


def test_the_summary_says_when_the_resource_moved_on_since_the_preview() -> None:
    preview = reload.Preview("Tank1", "demo", {}, plan([change("P.a", "kept")]), ())
    assert "crc-moved" not in reload.render_summary(preview, "AAAAAAAA", loaded=False)
    assert "it will refuse this reload" in reload.render_summary(preview, "CCCCCCCC", loaded=False)
    assert "preview again" in reload.render_summary(preview, "BBBBBBBB", loaded=True)
