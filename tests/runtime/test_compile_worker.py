"""Generated code compiled by the compile worker's child process (runtime/code/compile_worker.py),
as a reload prepared while cycles run has it compiled: the same code as compiled here, a
unit that does not compile raising its own error, and a child that died replaced."""

from __future__ import annotations

import os
import signal
from types import CodeType

import pytest

from runtime.code.compile_worker import COMPILE_WORKER, CompileWorker, compile_here
from runtime.contract.generated_code import GeneratedCodeError
from tests.support.resource_harness import compiled, harness

UNITS = [
    ("def FN_TWICE(x=0):\n    return 2 * x\n", "<pou TWICE>"),
    (
        "class POU_P:\n    __slots__ = ()\n    def __call__(s):\n        return FN_TWICE(x=21)\n",
        "<pou P>",
    ),
]


def _run(codes: list[CodeType]) -> object:
    namespace: dict[str, object] = {}
    for code in codes:
        exec(code, namespace)
    return namespace["POU_P"]()()  # type: ignore[operator]


def test_the_child_compiles_what_compiling_here_gives() -> None:
    worker = CompileWorker()
    try:
        codes = worker.compile(UNITS)
        assert [c.co_filename for c in codes] == ["<pou TWICE>", "<pou P>"]
        assert _run(codes) == _run(compile_here(UNITS)) == 42
    finally:
        worker.close()


def test_a_unit_that_does_not_compile_raises_its_error_naming_its_unit() -> None:
    worker = CompileWorker()
    try:
        with pytest.raises(GeneratedCodeError, match="pou BROKEN, line 1"):
            worker.compile([*UNITS, ("x = (", "<pou BROKEN>")])
        assert _run(worker.compile(UNITS)) == 42  # and it goes on serving
    finally:
        worker.close()


def test_a_child_that_died_is_replaced() -> None:
    worker = CompileWorker()
    try:
        worker.compile(UNITS)
        child = worker._child
        assert child is not None
        os.kill(child.pid, signal.SIGKILL)
        child.wait()
        assert _run(worker.compile(UNITS)) == 42  # by a new child
        assert worker._child is not None and worker._child.pid != child.pid
    finally:
        worker.close()


def test_a_reload_has_its_code_compiled_by_the_child() -> None:
    text = "PROGRAM P\nVAR n : DINT; END_VAR\nn := n + 1;\nEND_PROGRAM\n"
    h = harness(text, [{"name": "P"}])
    h.cycle(3)
    COMPILE_WORKER.close()
    h.send(compiled(text.replace("n + 1", "n + 10"), [{"name": "P"}]))
    assert h.cmd("reload")["ok"]
    assert COMPILE_WORKER._child is not None  # started for it
    h.cycle()
    assert h.value("P.n") == 13  # the value carried, the new code running


def test_a_reload_compiles_only_the_units_it_changed_and_copies_the_running_code_of_the_rest(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    text = (
        "FUNCTION_BLOCK Small\nVAR_INPUT x : DINT; END_VAR\nVAR_OUTPUT y : DINT; END_VAR\n"
        "y := x * 2;\nEND_FUNCTION_BLOCK\n"
        "PROGRAM P\nVAR n : DINT; s : Small; END_VAR\nn := n + 1; s(x := n);\nEND_PROGRAM\n"
    )
    h = harness(text, [{"name": "P"}])
    h.cycle(3)
    asked: list[str] = []

    def compile_and_note(units: list[tuple[str, str]]) -> list[CodeType]:
        asked.extend(filename for _, filename in units)
        return compile_here(units)

    monkeypatch.setattr(COMPILE_WORKER, "compile", compile_and_note)
    running = h.resource.programs[0].instance
    call_before = type(running).__call__.__code__
    h.send(compiled(text.replace("x * 2", "x * 5"), [{"name": "P"}]))
    assert h.cmd("reload")["ok"]
    assert asked == ["<FUNCTION_BLOCK Small>"]  # P's generated source did not change
    # a copy of the same code, in a class of the new image: none of the old code's
    # specializations for the classes the reload replaced (runtime/code/code_warmup.py)
    call_after = type(running).__call__.__code__
    assert call_after == call_before and call_after is not call_before
    h.cycle()
    assert h.value("P.n") == 4 and h.value("P.s.y") == 20
