"""PLCopen XML nobody here wrote, imported with `padt import` and compiled with `padt
compile`, as a user runs them: OSCAT BASIC and BUILDING as PLCopen projects (each with an
FBD program), and matiec's PLCopen test projects (in ST, SFC, FBD and LD). Each must import
whole, and its project compile with no error, or be listed with its reason in
tests/compiler/corpus/plcopen_known_failures.tsv (where a listed file must still fail)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import read_source
from backend.engineering.plcopen.importer import import_plcopen
from backend.engineering.project import compile_project, load_project
from tests.conftest import padt
from tests.support.corpus_paths import CORPUS, corpus_dir, known_failures

KNOWN = known_failures("plcopen_known_failures.tsv")
FOLDERS = ("oscat/plcopen", "matiec/tests")


def xml_files(folder: str) -> list[str]:
    return sorted(str(p.relative_to(CORPUS)) for p in corpus_dir(folder).glob("*.xml"))


def imported_errors(name: str, tmp_path: Path) -> list[str]:
    """`padt import` the file (it must import whole: exit 0), `padt compile` the folder:
    the compile's error lines."""
    folder = tmp_path / "project"
    run = padt("import", str(CORPUS / name), "-o", str(folder))
    assert (run.returncode, run.stderr) == (0, ""), name
    compiled = padt("compile", str(folder))
    output = compiled.stdout + compiled.stderr
    errors = [line for line in output.splitlines() if ": error: " in line]
    assert (compiled.returncode == 0) == (not errors), output
    return errors


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
    """As a user does it: `padt import` (exit 0: the FBD test program is imported too),
    `padt compile` on the folder it wrote, and `padt sim` runs the drawn program (an ADD
    of two variables into a third)."""
    source = corpus_dir("oscat/plcopen") / "BUILDING_1.0.xml"
    folder = tmp_path / "building"
    run = padt("import", str(source), "-o", str(folder))
    assert (run.returncode, run.stderr) == (0, "")
    imported = "106 POUs, 4 data types, 0 global variables, 1 program"
    assert run.stdout == f"padt import: {imported} written to {folder}\n"
    assert "\nFBD\n  1: BLOCK ADD (IN1 := 2, IN2 := 3) -> (OUT) {at 600 140" in (
        (folder / "program0.st").read_text()
    )
    compiled = padt("compile", str(folder))
    assert compiled.returncode == 0, compiled.stdout
    assert "configuration CRC" in compiled.stdout
    names = [f"instance0.LocalVar{k}" for k in range(3)]
    ran = padt(
        "sim", str(folder), "--cycles", "2", "--trace", ",".join(names),
        "--set", "instance0.LocalVar0=40", "--set", "instance0.LocalVar1=2@2",
    )  # fmt: skip
    assert ran.returncode == 0, ran.stderr
    rows = [json.loads(line)["values"] for line in ran.stdout.splitlines()]
    assert [[row[name] for name in names] for row in rows] == [[40, 0, 40], [40, 2, 42]]


# POUs whose XML and ST in the corpus differ in their text, not in the import
SOURCES_DIFFER = {
    "BASIC_3.33-5_Mathematics/SQRTN": "oscat/st declares X and N as VAR, the XML as inputs",
}
# the FBD program0 of each chapter is in oscat/st as Beremiz translated it, with a variable
# ADD1_OUT where padt's lowering has its hidden _TMP_ADD1_OUT: other code, the same sum
# (test_oscat_building_through_the_command_line runs it)
DRAWN = "PROGRAM0"


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
            if pou.name.upper() == DRAWN:
                continue
            compared += 1
            if st_crcs.get(pou.name) != pou.crc:
                differing.append(f"{st.stem}/{pou.name}")
    assert sorted(differing) == sorted(SOURCES_DIFFER)
    assert compared >= 650  # 690, with the standard blocks they use
