"""The Online change dialog's pure parts: every value's fate as the engineer reads it, the
source diff, the parameter resets, why not online, and a compile that failed."""

from __future__ import annotations

from backend.engineering.online_change import (
    FileDiff,
    OnlineChangePreview,
    ParameterReset,
)
from backend.engineering.reload import risks
from frontend.dialogs import online_change as dialog
from frontend.dialogs.deployment import Failure, failure_html
from runtime.contract import protocol as p


def change(path: str, action: str, source: str | None = None, reason: str = "") -> p.VariableChange:
    return p.VariableChange(path, action, "INT", "INT", source, reason)


def preview(
    changes: list[p.VariableChange],
    refusals: tuple[str, ...] = (),
    why_not: tuple[str, ...] = (),
    resets: tuple[ParameterReset, ...] = (),
    diff: tuple[FileDiff, ...] = (),
    running_from: str = "backup demo_AAAAAAAA_20261202T000000Z.zip",
) -> OnlineChangePreview:
    summary = {fate: sum(c.action == fate for c in changes) for fate in dialog.FATES}
    plan = p.ReloadPlanInfo(
        "AAAAAAAA", "BBBBBBBB", not refusals, list(refusals), [],
        p.ProgramChanges([], [], ["P"]), summary, changes, 12.0,
    )  # fmt: skip
    return OnlineChangePreview(
        "Tank1", "demo", {}, plan, ("BBBBBBBB", "BBBBBBBB"), tuple(risks(plan)), why_not,
        resets, diff, running_from,
    )  # fmt: skip


def test_every_value_has_its_fate_lost_and_initialised_first() -> None:
    shown = dialog.preview_html(
        preview(
            [
                change("P.a", "kept", "P.a"),
                change("P.new", "kept", "P.old", "renamed from P.old"),
                change("P.n", "new"),
                change("P.gone", "deleted"),
                change("P.i", "initialised", "P.i", "INT -> SINT does not convert every value"),
            ]
        )
    )
    order = [shown.index(f'data-fate="{path}"') for path in ("P.gone", "P.i", "P.new", "P.n")]
    assert order == sorted(order) and order[-1] < shown.index('data-fate="P.a"')
    assert 'data-fate="P.gone">lost<' in shown and 'data-fate="P.new">renamed<' in shown
    assert "the value of P.old" in shown and "none: the value is lost" in shown
    assert "its initial value (INT -&gt; SINT does not convert every value)" in shown
    assert 'data-count="deleted"' in shown and "BBBBBBBB" in shown and "AAAAAAAA" in shown


def test_the_source_diff_the_resets_and_why_not_online_are_shown() -> None:
    diff = FileDiff("tank.st", "changed", ("@@ -1,2 +1,2 @@", " x", "-y", "+z"))
    reset = ParameterReset("target_cycle_ms", 50, 100, "")
    shown = dialog.preview_html(
        preview(
            [change("P.a", "kept")],
            refusals=("no user program would remain",),
            why_not=("No program would remain: ...",),
            resets=(reset,),
            diff=(diff,),
        )
    )
    assert '<div data-diff="removed" style="background:#fff5f5">-y</div>' in shown
    assert '<div data-diff="added" style="background:#ebfbee">+z</div>' in shown
    assert "tank.st (changed)" in shown and "against backup demo_AAAAAAAA" in shown
    assert "target_cycle_ms: 50 online, 100 in the project; the reload sets 100" in shown
    assert 'data-testid="why-not-online"' in shown and "No program would remain" in shown
    unknown = dialog.preview_html(preview([change("P.a", "kept")], running_from=""))
    assert "sources are not known here" in unknown


def test_a_compile_error_is_shown_with_file_line_col_and_code() -> None:
    shown = failure_html(
        Failure(
            "compile",
            "the project does not compile",
            ("tank.st:18:20: error: '<x>' is not declared [E0201]",),
        ),
        "Online change",
    )
    assert "Online change refused (compile): the project does not compile" in shown
    assert "tank.st:18:20: error: &#x27;&lt;x&gt;&#x27; is not declared [E0201]" in shown
