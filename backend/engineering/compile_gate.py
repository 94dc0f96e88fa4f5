"""The compile-twice gate before a load or reload (spec section 3): two compiles in two
processes must agree on every CRC, and the compile in this process, whose artifact is
sent, must give the configuration CRC they agreed on."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from backend.engineering.check_twice import check_twice
from backend.engineering.project import (
    PROJECT_FILE,
    Project,
    compile_project,
    for_resource,
    load_project,
)
from backend.engineering.testing.test_build import sources_of_tests
from runtime.contract.artifact import Artifact
from runtime.contract.refusal import Refusal


@dataclass(frozen=True)
class CheckedCompile:
    """A project compiled in this process, with the same CRCs as two separate compiles."""

    project: Project
    artifact: Artifact
    diagnostics: tuple[str, ...]  # warnings of the in-process compile
    config_text: str | None  # the project's padt.toml as read for this compile, if any
    # the configuration CRCs of the two check compiles (equal, and equal to the artifact's)
    check_crcs: tuple[str, str]
    # the project's tests (docs/testing.md) by name, read with its sources: not compiled into
    # the configuration, kept in its backup, which they travel with
    tests: dict[str, str] = field(default_factory=dict)


def compile_failed(message: str, diagnostics: Sequence[str]) -> Refusal:
    """The refusal of a project that does not compile: code `compile`, with every
    rendered diagnostic."""
    return Refusal("compile", message, diagnostics=list(diagnostics))


def compile_checked(paths: Sequence[Path], resource: str | None = None) -> CheckedCompile:
    """Compile-twice gate, then the in-process compile whose artifact is sent; with
    `resource`, all three compile the project for that resource in place of its own
    (`for_resource`: a fleet load). Raises ProjectError when the project cannot be read,
    Refusal (`compile`, `check_twice`) otherwise."""
    # an unreadable project fails fast, before two
    project = for_resource(load_project(list(paths)), resource)
    # kept for the backup: the project model holds the sources but not padt.toml's text
    folder = Path(paths[0]) if len(paths) == 1 and Path(paths[0]).is_dir() else None
    config = folder / PROJECT_FILE if folder is not None else None
    config_text = config.read_text(encoding="utf-8") if config and config.is_file() else None
    tests = {t.name: t.text for t in sources_of_tests(folder)} if folder is not None else {}
    check = check_twice(paths, resource=resource)
    if not check.compiled:
        failures = [run.failure for run in (check.first, check.second) if run.failure]
        first = check.first if check.first.failure is None else check.second
        if failures and not first.diagnostics:
            raise compile_failed(f"the check compile failed: {failures[0]}", ())
        raise compile_failed("the project does not compile", first.diagnostics)
    if check.mismatches:
        raise Refusal("check_twice", "the two compiles differ: " + "; ".join(check.mismatches))
    result = compile_project(project)
    diagnostics = tuple(str(d) for d in result.diagnostics)
    if result.artifact is None:
        raise compile_failed("the project does not compile", diagnostics)
    agreed = check.first.configuration
    if result.artifact.crc != agreed:
        raise Refusal(
            "check_twice",
            f"this compile gives configuration CRC {result.artifact.crc}, the two check "
            f"compiles gave {agreed} (was a source changed meanwhile?)",
        )
    crcs = (agreed or "", check.second.configuration or "")
    return CheckedCompile(project, result.artifact, diagnostics, config_text, crcs, tests)
