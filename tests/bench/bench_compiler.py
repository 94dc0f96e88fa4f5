"""Compiler and generated-code speed on the demo project."""

from __future__ import annotations

import time

from backend.engineering.project import compile_project, demo_project_path, load_project
from runtime.clock import VirtualClock
from runtime.resource import Resource


def main() -> None:
    project = load_project([demo_project_path()])
    lines = sum(s.text.count("\n") for s in project.sources)
    rounds = 50
    started = time.perf_counter()
    for _ in range(rounds):
        result = compile_project(project)
    elapsed = time.perf_counter() - started
    print(f"compile demo project: {elapsed / rounds * 1e3:.2f} ms ({lines} lines)")

    assert result.artifact is not None
    clock = VirtualClock()
    resource = Resource("bench", clock)
    resource.load(result.artifact)
    resource.start()
    cycles = 20_000
    started = time.perf_counter()
    for _ in range(cycles):
        resource.cycle()
        clock.advance(100_000_000)
    elapsed = time.perf_counter() - started
    print(f"demo cycle incl. engine: {elapsed / cycles * 1e6:.2f} us per cycle")


if __name__ == "__main__":
    main()
