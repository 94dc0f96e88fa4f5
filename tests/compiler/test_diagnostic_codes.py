"""docs/diagnostics.md explains every diagnostic code, each with a failing and a passing
example (the page says how it is laid out). This runs every example: the failing one must
get its code, the passing one no error and not that code; and the page and the registry in
`backend.compiler.codes` must list the same codes, with the same titles, in code order."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import pytest

from backend.compiler.codes import Code
from backend.compiler.pipeline import CompileResult, compile_sources
from backend.compiler.source import SourceFile
from backend.engineering.project import PROJECT_FILE, compile_project, load_project

PAGE = Path(__file__).resolve().parents[2] / "docs" / "diagnostics.md"
CODE = re.compile(r"[EWN]\d{4}")
HEADING = re.compile(r"## (?P<code>\S+): (?P<title>.+)")
MARKERS = ("Fails:", "Passes:")


@dataclass(frozen=True)
class Example:
    st: str
    toml: str | None  # the project's padt.toml, for an example that needs settings


@dataclass(frozen=True)
class Section:
    code: str
    title: str
    fails: Example
    passes: Example


def parse_page(text: str) -> list[Section]:
    """The code sections, in page order; what comes before the first one is the
    introduction."""
    sections: list[Section] = []
    lines = iter(text.splitlines())
    heading: re.Match[str] | None = None
    blocks: dict[str, list[tuple[str, str]]] = {}
    marker: str | None = None

    def close() -> None:
        if heading is not None:
            examples = [_example(heading["code"], m, blocks.get(m, [])) for m in MARKERS]
            sections.append(Section(heading["code"], heading["title"], *examples))

    for line in lines:
        if line.startswith("## "):
            found = HEADING.fullmatch(line)
            assert found is not None or heading is None, f"not a code section: {line!r}"
            close()
            heading, blocks, marker = found, {}, None
        elif heading is not None and line in MARKERS:
            assert line not in blocks, f"{heading['code']}: {line} twice"
            marker = line
            blocks[marker] = []
        elif line.startswith("```") and heading is not None:
            assert marker is not None, f"{heading['code']}: a block before {MARKERS[0]}"
            body = []
            for inner in lines:
                if inner == "```":
                    break
                body.append(inner)
            blocks[marker].append((line[3:], "\n".join(body) + "\n"))
    close()
    return sections


def _example(code: str, marker: str, blocks: list[tuple[str, str]]) -> Example:
    kinds = [kind for kind, _ in blocks]
    assert kinds in (["st"], ["toml", "st"]), f"{code} {marker} has blocks {kinds}"
    found = dict(blocks)
    return Example(expand(found["st"]), found.get("toml"))


REPEATED = re.compile(r"(?P<line>.*) \(\* (?P<count>[0-9]+) times \*\)")


def expand(st: str) -> str:
    """A line that ends in `(* N times *)` stands for N copies of the line before the comment
    (the examples of limits need long sources)."""
    lines = []
    for line in st.splitlines():
        repeated = REPEATED.fullmatch(line)
        if repeated is None:
            lines.append(line)
        else:
            lines.extend([repeated["line"]] * int(repeated["count"]))
    return "\n".join(lines) + "\n"


SECTIONS = parse_page(PAGE.read_text(encoding="utf-8"))


def compile_example(example: Example, folder: Path, code: str = "") -> CompileResult:
    """As `padt compile` does: a lone file, or a project folder with its padt.toml; the
    examples of the unit tests' codes (E10xx) as a test file, as `padt test` compiles it."""
    if example.toml is None:
        name = "test/main_test.st" if code.startswith("E10") else "main.st"
        return compile_sources([SourceFile(name, example.st)])
    folder.mkdir()
    (folder / PROJECT_FILE).write_text(example.toml, encoding="utf-8")
    (folder / "main.st").write_text(example.st, encoding="utf-8")
    return compile_project(load_project([folder]))


def test_codes_are_well_formed_and_unique() -> None:
    ids = [code.id for code in Code]
    assert len(ids) == len(set(ids))
    for code in Code:
        assert CODE.fullmatch(code.id), code
        assert code.severity == {"E": "error", "W": "warning", "N": "note"}[code.id[0]], code
        assert code.title and code.title == code.title.strip(), code


def test_the_page_and_the_registry_list_the_same_codes_in_code_order() -> None:
    on_page = [(section.code, section.title) for section in SECTIONS]
    assert on_page == sorted((code.id, code.title) for code in Code)


@pytest.mark.parametrize("section", SECTIONS, ids=[section.code for section in SECTIONS])
def test_the_failing_example_gets_its_code_and_the_passing_one_compiles(
    section: Section, tmp_path: Path
) -> None:
    failing = compile_example(section.fails, tmp_path / "fails", section.code)
    assert section.code in [d.code for d in failing.diagnostics], [
        str(d) for d in failing.diagnostics
    ]
    passing = compile_example(section.passes, tmp_path / "passes", section.code)
    problems = [d for d in passing.diagnostics if d.severity == "error" or d.code == section.code]
    assert passing.ok and not problems, [str(d) for d in problems]
