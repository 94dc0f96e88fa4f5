"""The one table of what generated code may name (runtime/contract/intrinsic_table.py)
holds for everything that uses it: the Python tier's namespace binds exactly its names,
each function takes the arguments its entry declares and raises the faults it names,
and docs/artifact.md tells each one."""

from __future__ import annotations

import inspect

import pytest

from runtime.code import intrinsics
from runtime.code.intrinsics import ProgramFault, SystemView, namespace
from runtime.contract.code.names import CALLED_INTRINSICS, INTRINSICS
from runtime.contract.intrinsic_table import INTRINSICS as TABLE
from runtime.contract.intrinsic_table import Intrinsic
from tests.conftest import REPO

CALLED = [entry for entry in TABLE if entry.called]


def test_the_namespace_binds_the_names_of_the_table_and_no_other() -> None:
    names = [entry.name for entry in TABLE]
    assert len(names) == len(set(names))
    bound = namespace(SystemView()).keys() - {"__builtins__", "__name__"}
    assert bound == set(names) == INTRINSICS
    assert {entry.name for entry in CALLED} == CALLED_INTRINSICS


@pytest.mark.parametrize("entry", CALLED, ids=lambda entry: entry.name)
def test_each_function_takes_the_arguments_its_entry_declares(entry: Intrinsic) -> None:
    function = namespace(SystemView())[entry.name]
    signature = inspect.signature(function)
    fixed = len(entry.params) - 1 if entry.variadic else len(entry.params)
    signature.bind(*[None] * fixed)  # as few as the entry allows
    signature.bind(*[None] * len(entry.params))  # and a variadic one with one more


@pytest.mark.parametrize("entry", [e for e in CALLED if e.faults], ids=lambda e: e.name)
def test_the_faults_an_entry_names_are_program_faults(entry: Intrinsic) -> None:
    for fault in entry.faults:
        assert issubclass(getattr(intrinsics, fault), ProgramFault), fault


def test_docs_artifact_tells_every_name() -> None:
    text = (REPO / "docs" / "artifact.md").read_text()
    untold = [entry.name for entry in TABLE if f"`{entry.name}" not in text]
    assert not untold, untold
