"""Whether a C compiler lays the structs of layouts out as layout.py says: one gcc run over
the declarations of many artifacts' layouts (each artifact's structs renamed apart, as
every artifact has its `POU_MAIN`), whose static assertions fail on any other offset."""

from __future__ import annotations

import os
import subprocess

import pytest

from runtime.code.native.build import find_toolchain
from runtime.code.native.layout_c import PRELUDE, declarations
from runtime.contract.layout import Layouts, runtime_layouts


def struct_source(many: list[Layouts]) -> str:
    parts = [PRELUDE]
    for n, layouts in enumerate(many):
        parts.append(declarations({**runtime_layouts(), **layouts}).replace("L_", f"L{n}_"))
    return "\n".join(parts)


def compile_errors(source: str) -> str:
    """gcc's complaints about `source` ("" when it compiles); skips where no C compiler is,
    but in CI."""
    toolchain = find_toolchain()
    if toolchain is None:
        if os.environ.get("CI") == "true":
            pytest.fail("CI must have a C compiler")
        pytest.skip("no C compiler here")
    done = subprocess.run(
        [toolchain.compiler, "-std=c11", "-fsyntax-only", "-Werror", "-x", "c", "-"],
        input=source,
        text=True,
        capture_output=True,
        check=False,
    )
    return done.stderr if done.returncode else ""
