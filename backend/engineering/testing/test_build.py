"""A project compiled with its tests: the test files of its `test/` folder and the libraries
asked for join its sources; the suites and tests are read from the parse."""

from __future__ import annotations

import fnmatch
from dataclasses import dataclass, replace
from pathlib import Path

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.diagnostics import Diagnostic
from backend.compiler.generate import method_attr
from backend.compiler.limits import MAX_PROJECT_FILES
from backend.compiler.pipeline import parse_project
from backend.compiler.source import SourceFile, read_sources
from backend.compiler.test_functions import TEST_FOLDER, is_test_file
from backend.engineering.project import (
    PROJECT_FILE,
    Project,
    ProjectError,
    compile_project,
    load_project,
)
from runtime.contract.artifact import Artifact, VarInfo
from runtime.contract.values import array_shape

LIBRARY_FOLDER = "library/"  # how library files are named among the sources


@dataclass(frozen=True)
class UnitTest:
    suite: str  # the function block, as declared
    name: str  # the method, as declared
    file: str  # the test file, by its path in the project
    line: int
    setup: str | None  # the generated method names of SetUp and TearDown, if the suite has them
    teardown: str | None
    # a parameterised test: its cases' array (the suite's variable `<Test>_Cases`) and the
    # index of this case in it, as ST counts (`TestAdd[2]`)
    cases: str | None = None
    case: int | None = None
    first: int = 0  # the array's lower bound
    problem: str = ""  # why it cannot run (a parameterised test without its cases)

    @property
    def full_name(self) -> str:
        index = f"[{self.case}]" if self.case is not None else ""
        return f"{self.suite}.{self.name}{index}"

    @property
    def method(self) -> str:
        return method_attr(self.name)


@dataclass(frozen=True)
class UnitTestBuild:
    project: Project
    folder: Path
    artifact: Artifact | None  # None: it does not compile
    diagnostics: tuple[Diagnostic, ...]
    cases: tuple[UnitTest, ...]  # by suite, then test, names in upper case
    syntax: tuple[ast.SourceUnit, ...] = ()  # the parse of the sources (coverage reads it)


def sources_of_tests(folder: Path) -> list[SourceFile]:
    """The test files of a project folder, named by their path in it (`test/...`)."""
    tests = folder / TEST_FOLDER.rstrip("/")
    if not tests.is_dir():
        return []
    files = sorted(tests.rglob("*.st"))[: MAX_PROJECT_FILES + 1]
    return read_sources([(p, p.relative_to(folder).as_posix()) for p in files])


def library_sources(paths: list[Path]) -> list[SourceFile]:
    """`--library`: .st files, or the .st files of folders, named `library/<file name>`."""
    files: list[Path] = []
    for path in paths:
        if path.is_dir():
            files += sorted(path.rglob("*.st"))
        elif path.is_file():
            files.append(path)
        else:
            raise ProjectError(f"--library {path}: no such file or folder")
    names = [f"{LIBRARY_FOLDER}{p.name}" for p in files]
    if len(set(names)) < len(names):
        raise ProjectError("--library: two files of the same name")
    return read_sources(list(zip(files, names, strict=True)))


def project_of(path: Path) -> tuple[Path, list[str]]:
    """The project folder a PATH of `padt test` belongs to, and the test files it selects
    (empty: all). A folder with padt.toml is a project; a test file or a folder below a
    project's test/ selects those tests."""
    path = path.resolve()
    if path.is_dir() and (path / PROJECT_FILE).is_file():
        return path, []
    for folder in path.parents:
        if (folder / PROJECT_FILE).is_file():
            inside = path.relative_to(folder).as_posix() + ("/" if path.is_dir() else "")
            if not is_test_file(inside):
                raise ProjectError(f"{path}: not below the test/ folder of {folder}")
            return folder, [inside]
    if path.is_dir():
        return path, []  # a folder of .st files without padt.toml: a default resource
    raise ProjectError(f"{path}: no project (no {PROJECT_FILE} above it)")


def build_tests(paths: list[Path], libraries: tuple[Path, ...] = ()) -> UnitTestBuild:
    """The project of PATH... compiled with its tests; raises ProjectError when PATHs name
    more than one project or cannot be read."""
    found = [project_of(path) for path in paths]
    folders = {folder for folder, _ in found}
    if len(folders) != 1:
        raise ProjectError("padt test: give test paths of one project")
    folder = folders.pop()
    selected = [s for _, chosen in found for s in chosen]
    if any(not chosen for _, chosen in found):
        selected = []
    project = load_project([folder])
    sources = [*project.sources, *library_sources(list(libraries)), *sources_of_tests(folder)]
    project = replace(project, sources=sources)
    parsed = parse_project(sources)
    result = compile_project(project, parsed=parsed)
    cases = tuple(
        case
        for case in unit_tests_of(parsed[0], result.artifact)
        if not selected or any(_selects(choice, case.file) for choice in selected)
    )
    return UnitTestBuild(
        project, folder, result.artifact, result.diagnostics, cases, tuple(parsed[0])
    )


def _selects(choice: str, file: str) -> bool:
    return file == choice or (choice.endswith("/") and file.startswith(choice))


def unit_tests_of(units: list[ast.SourceUnit], artifact: Artifact | None) -> list[UnitTest]:
    """Every test of the test files: the methods named Test... of their function blocks,
    by suite and test name; a method with an input is a test per element of its cases."""
    cases = []
    compiled = {key(p.name): p for p in artifact.pous} if artifact is not None else {}
    for unit in units:
        for pou in unit.pous:
            if pou.kind != "FUNCTION_BLOCK" or not is_test_file(pou.pos.file):
                continue
            methods = {key(m.name): m for m in pou.methods}
            setup = method_attr(methods["SETUP"].name) if "SETUP" in methods else None
            teardown = method_attr(methods["TEARDOWN"].name) if "TEARDOWN" in methods else None
            code = compiled.get(key(pou.name))
            variables = {key(v.name): v for v in code.variables} if code is not None else {}
            for method in pou.methods:
                if not key(method.name).startswith("TEST"):
                    continue
                test = UnitTest(
                    pou.name, method.name, pou.pos.file, method.pos.line, setup, teardown
                )
                if _inputs(method):
                    cases += _parameterised(test, variables, len(_inputs(method)))
                else:
                    cases.append(test)
    return sorted(cases, key=lambda c: (key(c.suite), key(c.name), c.case or 0))


def _inputs(method: ast.Method) -> list[str]:
    return [
        decl.name
        for block in method.var_blocks
        if block.kind == "VAR_INPUT"
        for decl in block.decls
    ]


def _parameterised(test: UnitTest, variables: dict[str, VarInfo], inputs: int) -> list[UnitTest]:
    """A test per element of the suite's array `<Test>_Cases`, whose elements are what the
    test method's one input takes (docs/testing.md, "Parameterised tests")."""
    wanted = f"{test.name}_Cases"
    found = variables.get(key(wanted))
    shape = array_shape(found.type) if found is not None else None
    problem = ""
    if inputs != 1:
        problem = f"{test.name} takes {inputs} inputs: a parameterised test takes one, its case"
    elif found is None or shape is None or len(shape.dims) != 1:
        problem = (
            f"{test.name} takes an input: declare {wanted}, an array of its cases, in the suite"
        )
    if problem:
        return [replace(test, problem=problem)]
    assert found is not None and shape is not None
    low, high = shape.dims[0]
    return [
        replace(test, cases=found.attr, case=index, first=low) for index in range(low, high + 1)
    ]


def matching(cases: tuple[UnitTest, ...], pattern: str | None) -> tuple[UnitTest, ...]:
    """`-k PATTERN`: the tests whose `Suite.Test` (`Suite.Test[2]`, a case of a
    parameterised one) contains PATTERN, any case; `*` and `?` as in a shell."""
    if not pattern:
        return cases
    wanted = pattern.upper().replace("[", "[[]")  # `TestAdd[2]` names a case, no set
    if not any(ch in pattern for ch in "*?"):
        wanted = f"*{wanted}*"
    return tuple(c for c in cases if fnmatch.fnmatchcase(c.full_name.upper(), wanted))
