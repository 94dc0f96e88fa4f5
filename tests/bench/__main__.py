"""`make bench`: print the benchmark figures (no assertions; machines are shared and noisy)."""

from __future__ import annotations

from tests.bench import (
    bench_compiler,
    bench_context,
    bench_debugging,
    bench_documentation,
    bench_editor,
    bench_event_log,
    bench_exchange,
    bench_hostile,
    bench_jitter_loaded,
    bench_language,
    bench_language_services,
    bench_logic_view,
    bench_lsp,
    bench_modbus,
    bench_opcua,
    bench_peers,
    bench_projects,
    bench_recording,
    bench_reload,
    bench_rest,
    bench_runtime,
    bench_scale,
    bench_trends,
    bench_ui,
    bench_unit_tests,
    bench_watch,
    bench_workspace,
)


def main() -> None:
    bench_compiler.main()
    bench_language.main()
    bench_peers.main()
    bench_language_services.main()
    bench_lsp.main()
    bench_projects.main()
    bench_context.main()
    bench_runtime.main()
    bench_reload.main()
    bench_debugging.main()
    bench_event_log.main()
    bench_scale.main()
    bench_watch.main()
    bench_recording.main()
    bench_modbus.main()
    bench_opcua.main()
    bench_exchange.main()
    bench_jitter_loaded.main()
    bench_rest.main()
    bench_hostile.main()
    bench_ui.main()
    bench_editor.main()
    bench_documentation.main()
    bench_trends.main()
    bench_logic_view.main()
    bench_workspace.main()
    bench_unit_tests.main()


if __name__ == "__main__":
    main()
