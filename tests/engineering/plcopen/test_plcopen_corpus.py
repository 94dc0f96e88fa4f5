"""PLCopen XML nobody here wrote, imported with `padt import` and compiled: OSCAT BASIC and
BUILDING as PLCopen projects, and matiec's PLCopen test projects. Each must import, and its
project compile with no error, or be listed with its reason in
tests/compiler/corpus/plcopen_known_failures.tsv (where a listed file must still fail)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from backend.compiler.diagnostics import Diagnostic
from backend.compiler.pipeline import compile_sources
from backend.compiler.source import read_source
from backend.engineering.plcopen.importer import import_plcopen
from backend.engineering.project import compile_project, load_project
from tests.conftest import padt
from tests.support.corpus_paths import CORPUS, corpus_dir, known_failures

KNOWN = known_failures("plcopen_known_failures.tsv")
FOLDERS = ("oscat/plcopen", "matiec/tests")
# what each folder's files may hold that padt does not compile: OSCAT's test program0
# is FBD; matiec's test projects are in FBD and LD on purpose
LEFT_OUT = {"oscat/plcopen": {"FBD"}, "matiec/tests": {"FBD", "LD"}}


def xml_files(folder: str) -> list[str]:
    return sorted(str(p.relative_to(CORPUS)) for p in corpus_dir(folder).glob("*.xml"))


def imported_errors(name: str, tmp_path: Path) -> list[Diagnostic]:
    """Import the file, check what was left out, compile: the compile errors."""
    folder = tmp_path / "project"
    result = import_plcopen(CORPUS / name, folder)
    reasons = {missing.reason for missing in result.not_imported}
    assert reasons <= LEFT_OUT[str(Path(name).parent)], result.not_imported
    compiled = compile_project(load_project([folder]))
    return [d for d in compiled.diagnostics if d.severity == "error"]


@pytest.mark.parametrize("folder", FOLDERS)
def test_corpus_xml_imports_and_compiles(folder: str, tmp_path: Path) -> None:
    failing = {}
    for number, name in enumerate(xml_files(folder)):
        if name in KNOWN:
            continue
        found = imported_errors(name, tmp_path / str(number))
        if found:
            failing[name] = found[0]
    assert not failing, "\n".join(f"{name}: {error}" for name, error in failing.items())


@pytest.mark.parametrize("name", sorted(KNOWN))
def test_known_failure_still_fails(name: str, tmp_path: Path) -> None:
    corpus_dir(str(Path(name).parent))
    assert imported_errors(name, tmp_path), f"{name} compiles now: remove it from the list"


def test_oscat_xml_compiles_as_well_as_the_oscat_st() -> None:
    """A chapter whose ST compiles fails as XML only for a fault of the XML itself."""
    iec = known_failures("iec_known_failures.tsv")
    st_chapters = {p.stem for p in corpus_dir("oscat/st").glob("*.st")}
    for name, reason in KNOWN.items():
        stem = Path(name).stem
        if name.startswith("oscat/") and stem in st_chapters:
            st_fails = f"oscat/st/{stem}.st" in iec
            assert st_fails or "of the XML only" in reason, name
    assert len(xml_files("oscat/plcopen")) == 24


def test_matiecs_sfc_test_runs_after_import(tmp_path: Path) -> None:
    """matiec's SFC test project (selection and simultaneous branches, jumps, named and
    inline actions, TC6 1.0) imported, then run by `padt sim` on its own resource."""
    source = corpus_dir("matiec/tests") / "SFC_TEST.xml"
    folder = tmp_path / "sfc"
    assert import_plcopen(source, folder).complete
    steps = ["GO", "STEP1", "STEP2", "A1"]
    names = [f"MAIN_INSTANCE.{step}.X" for step in steps]
    run = padt(
        "sim", str(folder), "--cycles", "4", "--trace", ",".join(names),
        "--set", "MAIN_INSTANCE.IX2=TRUE@3",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    rows = [json.loads(line)["values"] for line in run.stdout.splitlines()]
    active = [[step for step, name in zip(steps, names, strict=True) if row[name]] for row in rows]
    # GO -> STEP1 at once (IX1 is FALSE); STEP1 -> STEP2 when IX2; then the first branch
    # whose condition holds (QX1 and QX2 both FALSE after STEP2's P action: A1)
    assert active == [["STEP1"], ["STEP1"], ["STEP2"], ["A1"]]


def test_oscat_building_through_the_command_line(tmp_path: Path) -> None:
    """As a user does it: `padt import` (exit 1: the FBD test program is named and left
    out), then `padt compile` on the folder it wrote."""
    source = corpus_dir("oscat/plcopen") / "BUILDING_1.0.xml"
    folder = tmp_path / "building"
    run = padt("import", str(source), "-o", str(folder))
    assert run.returncode == 1, run.stderr
    assert "1 POU not imported, padt compiles ST and SFC only: program0 (FBD) [P0006]" in (
        run.stderr
    )
    imported = "105 POUs, 4 data types, 0 global variables, 0 programs"
    assert run.stdout == f"padt import: {imported} written to {folder}\n"
    compiled = padt("compile", str(folder))
    assert compiled.returncode == 0, compiled.stdout
    assert "configuration CRC" in compiled.stdout


# POUs whose XML and ST in the corpus differ in their text, not in the import
SOURCES_DIFFER = {
    "BASIC_3.33-5_Mathematics/SQRTN": "oscat/st declares X and N as VAR, the XML as inputs",
}


def test_oscat_xml_compiles_to_the_same_code_as_the_oscat_st(tmp_path: Path) -> None:
    """The strongest check of the import: each POU of a chapter, imported from the XML,
    has the CRC (the same generated code) it has when the chapter's ST file is compiled."""
    compared, differing = 0, []
    for st in sorted(corpus_dir("oscat/st").glob("*.st")):
        xml = CORPUS / "oscat" / "plcopen" / f"{st.stem}.xml"
        if f"oscat/st/{st.name}" in known_failures("iec_known_failures.tsv"):
            continue
        folder = tmp_path / st.stem
        import_plcopen(xml, folder)
        from_xml = compile_project(load_project([folder])).artifact
        from_st = compile_sources([read_source(st, st.name)], programs=[]).artifact
        if from_xml is None:  # listed in plcopen_known_failures.tsv
            assert f"oscat/plcopen/{xml.name}" in KNOWN
            continue
        assert from_st is not None
        st_crcs = {pou.name: pou.crc for pou in from_st.pous}
        for pou in from_xml.pous:
            compared += 1
            if st_crcs.get(pou.name) != pou.crc:
                differing.append(f"{st.stem}/{pou.name}")
    assert sorted(differing) == sorted(SOURCES_DIFFER)
    assert compared >= 650  # 690, with the standard blocks they use
