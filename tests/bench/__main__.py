"""`make bench`: print the benchmark figures (no assertions; machines are shared and noisy)."""

from __future__ import annotations

from tests.bench import bench_compiler, bench_language


def main() -> None:
    bench_compiler.main()
    bench_language.main()


if __name__ == "__main__":
    main()
