"""`padt import FILE.xml -o DIR` as a user runs it, on PLCopen files written for these tests
(fixtures/): what is written, that it compiles and runs, and how bad files are refused."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from backend.engineering.plcopen.importer import import_plcopen
from backend.engineering.plcopen.issues import ImportCode, ImportFailed
from backend.engineering.project import load_project
from tests.conftest import REPO, padt

FIXTURES = Path(__file__).parent / "fixtures"


def imported(tmp_path: Path, name: str, *options: str) -> tuple[Path, int, str]:
    folder = tmp_path / name
    run = padt("import", str(FIXTURES / f"{name}.xml"), "-o", str(folder), *options)
    assert "Traceback" not in run.stderr
    if run.returncode < 2:
        assert run.stdout.endswith(f" written to {folder}\n")
    return folder, run.returncode, run.stderr


def test_every_part_of_a_project_is_imported(tmp_path: Path) -> None:
    folder = tmp_path / "plant"
    run = padt("import", str(FIXTURES / "plant.xml"), "-o", str(folder))
    assert run.returncode == 0, run.stderr
    assert run.stdout == (
        f"padt import: 4 POUs, 6 data types, 4 global variables, 2 programs written to {folder}\n"
    )
    assert run.stderr == ""
    assert sorted(p.name for p in folder.iterdir()) == [
        "Dosing.st", "Scale.st", "Sequence.st", "Totaliser.st",
        "data-types.st", "global-variables.st", "padt.toml",
    ]  # fmt: skip
    types = (folder / "data-types.st").read_text()
    for declaration in (
        "Mode : (Idle, Filling, Mixing) := Idle;",
        "Alarm : INT (NoAlarm := 0, High := 10);",
        "Percent : INT (0..100) := 50;",
        "Litres : REAL := 1.5;",
        "name : STRING[16] := 'water';",
        "steps : ARRAY [1..3] OF INT := [1, 2(7)];",
        "Levels : ARRAY [0..3] OF Percent := [4(10)];",
    ):
        assert declaration in types
    dosing = (folder / "Dosing.st").read_text()
    for line in (
        "raw AT %IW0 : INT;",
        "valve AT %QX0.0 : BOOL;",
        "VAR CONSTANT\n    LIMIT : REAL := 4.0;",
        "VAR_EXTERNAL\n    gSetpoint : REAL;",
        "label : STRING := 'dosing line';",  # an unquoted string value gets its quotes
        "batches : ARRAY [1..2, 0..1] OF Recipe := [(volume := 1.0), "
        "3((name := 'oil', steps := [3(2)]))];",
        "counter : Totaliser; (* the dosed volume ( * ) *)",  # a comment that stays one
    ):
        assert line in dosing
    totaliser = (folder / "Totaliser.st").read_text()
    assert "VAR RETAIN\n    kept : Recipe := (volume := 2.5);\nEND_VAR" in totaliser
    assert "VAR_IN_OUT\n    count : DINT;" in totaliser
    assert "VAR_TEMP\n    step : REAL;" in totaliser
    assert (
        (folder / "Scale.st")
        .read_text()
        .startswith(
            "(* Raw counts to engineering units ( * ) ends no comment. *)\nFUNCTION Scale : REAL\n"
        )
    )
    globals_ = (folder / "global-variables.st").read_text()
    assert "VAR_GLOBAL RETAIN\n    gRuns : UDINT;" in globals_
    assert "VAR_GLOBAL CONSTANT\n    gMax : INT := 100;" in globals_
    toml = (folder / "padt.toml").read_text()
    assert 'name = "Mixing plant"\nversion = "2.1"' in toml
    assert 'name = "Mixer"\ntarget_cycle_ms = 50' in toml  # the shortest task interval
    assert 'name = "Dose"\npou = "Dosing"\nid = 1\npriority = 1  # task Fast' in toml
    assert 'name = "Seq"\npou = "Sequence"\nid = 2\npriority = 5  # task Slow' in toml
    compiled = padt("compile", str(folder))
    assert compiled.returncode == 0, compiled.stdout + compiled.stderr
    assert "program Dose: CRC" in compiled.stdout and "program Seq: CRC" in compiled.stdout


def test_the_same_file_gives_the_same_bytes(tmp_path: Path) -> None:
    first = tmp_path / "first"
    second = tmp_path / "elsewhere" / "second"
    import_plcopen(FIXTURES / "plant.xml", first)
    shutil.copy(FIXTURES / "plant.xml", tmp_path / "plant.xml")
    import_plcopen(tmp_path / "plant.xml", second)
    names = sorted(p.name for p in first.iterdir())
    assert names == sorted(p.name for p in second.iterdir())
    for name in names:
        assert (first / name).read_bytes() == (second / name).read_bytes(), name


def trace(folder: Path, cycles: int, names: list[str], *sets: str) -> dict[str, list[object]]:
    args = ["sim", str(folder), "--cycles", str(cycles), "--trace", ",".join(names)]
    for setting in sets:
        args += ["--set", setting]
    run = padt(*args)
    assert run.returncode == 0, run.stderr
    rows = [json.loads(line) for line in run.stdout.splitlines()]
    return {name: [row["values"][name] for row in rows] for name in names}


def test_the_sfc_runs_as_drawn(tmp_path: Path) -> None:
    """Wait -> Filling (its action Fill, a named transition Full) -> Mixing and Heating
    together (inline N and P actions) -> Wait when both are done."""
    folder, code, stderr = imported(tmp_path, "plant")
    assert code == 0, stderr
    chart = (folder / "Sequence.st").read_text()
    assert "TRANSITION FROM Filling TO (Mixing, Heating) := filled >= 2;" in chart
    assert "TRANSITION FROM (Mixing, Heating) TO Wait := mixed >= 2;" in chart
    steps = ["Seq.Wait.X", "Seq.Filling.X", "Seq.Mixing.X", "Seq.Heating.X"]
    values = trace(folder, 7, [*steps, "Seq.filled", "Seq.mixed", "Seq.heated"], "Seq.start=TRUE@2")
    active = [[name.split(".")[1] for name in steps if values[name][cycle]] for cycle in range(7)]
    assert active == [
        ["Wait"], ["Filling"], ["Filling"], ["Mixing", "Heating"], ["Mixing", "Heating"],
        ["Wait"], ["Filling"],
    ]  # fmt: skip
    # Fill runs while Filling is active, once more as its final scan (docs/language.md)
    assert values["Seq.filled"] == [0, 0, 1, 2, 3, 3, 3]
    assert values["Seq.mixed"] == [0, 0, 0, 0, 1, 2, 3]
    assert values["Seq.heated"] == [0, 0, 0, 0, 1, 1, 1]  # P: once per activation


def test_the_st_programs_run_with_their_function_and_block(tmp_path: Path) -> None:
    folder, _, _ = imported(tmp_path, "plant")
    names = ["Dose.flow", "Dose.calls", "Dose.counter.total", "Dose.valve", "gSetpoint"]
    values = trace(folder, 3, names, "Dose.raw=4")
    assert values["Dose.flow"] == [2.0, 2.0, 2.0]  # Scale: 4 * 0.5
    assert values["Dose.calls"] == [1, 2, 3]  # the in-out of Totaliser
    assert values["Dose.counter.total"] == [2.0, 4.0, 6.0]
    assert values["Dose.valve"] == [True, False, False]  # below LIMIT (a constant) first
    assert values["gSetpoint"] == [2.0, 4.0, 6.0]  # the global of the configuration


def test_initial_values_of_types_and_variables_meet(tmp_path: Path) -> None:
    """The initial values of the XML's data types (Recipe's name and steps, the alias
    Litres) under those of a variable (an array of structures, with repetitions)."""
    folder, _, _ = imported(tmp_path, "plant")
    run = padt("sim", str(folder), "--cycles", "1", "--trace", "Dose.batches,Dose.label")
    assert run.returncode == 0, run.stderr
    values = json.loads(run.stdout)["values"]
    first, last = "Dose.batches[1,0]", "Dose.batches[2,1]"
    assert [values[f"{first}.{member}"] for member in ("name", "volume", "steps")] == [
        "water", 1.0, [1, 7, 7],
    ]  # fmt: skip
    assert [values[f"{last}.{member}"] for member in ("name", "volume", "steps")] == [
        "oil", 1.5, [2, 2, 2],
    ]  # fmt: skip
    assert values["Dose.label"] == "dosing line"


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("malformed", ":6:7: error: not well-formed XML: mismatched tag [P0001]"),
        ("entity_bomb", ":2:19: error: refused: a DOCTYPE (PLCopen files have none) [P0002]"),
        ("external_entity", ":2:19: error: refused: a DOCTYPE (PLCopen files have none) [P0002]"),
    ],
)
def test_a_bad_file_is_refused_at_its_place_and_nothing_written(
    tmp_path: Path, name: str, message: str
) -> None:
    folder, code, stderr = imported(tmp_path, name)
    assert code == 2
    assert stderr.splitlines() == [
        f"{FIXTURES / name}.xml{message}",
        "padt import: nothing written",
    ]
    assert not folder.exists()


def test_an_encoding_python_does_not_know_is_refused(tmp_path: Path) -> None:
    xml = tmp_path / "odd.xml"
    xml.write_text('<?xml version="1.0" encoding="falling"?>\n<project/>\n')
    with pytest.raises(ImportFailed) as refused:
        import_plcopen(xml, tmp_path / "out")
    assert (refused.value.where.line, refused.value.code.id) == (1, "P0001")
    assert refused.value.message == "not readable XML: unknown encoding: falling"


def test_a_file_of_another_kind_is_no_plcopen_project(tmp_path: Path) -> None:
    xml = tmp_path / "other.xml"
    xml.write_text('<?xml version="1.0"?>\n<svg xmlns="http://www.w3.org/2000/svg"/>\n')
    run = padt("import", str(xml), "-o", str(tmp_path / "out"))
    assert run.returncode == 2
    assert f"{xml}:2:1: error: the root element is <svg>" in run.stderr
    assert "[P0003]" in run.stderr


def test_names_that_are_no_identifiers_are_refused(tmp_path: Path) -> None:
    """A POU name becomes a file name: `../x` must never leave DIR."""
    text = (FIXTURES / "graphical.xml").read_text().replace('"Twice"', '"../../Twice"')
    xml = tmp_path / "escape.xml"
    xml.write_text(text)
    with pytest.raises(ImportFailed) as refused:
        import_plcopen(xml, tmp_path / "out")
    assert refused.value.code.id == "P0005"
    assert refused.value.where.line == 15
    assert not (tmp_path / "out").exists() and not (tmp_path / "Twice.st").exists()


def test_a_folder_that_is_not_empty_needs_force(tmp_path: Path) -> None:
    folder = tmp_path / "project"
    (folder / "old").mkdir(parents=True)
    (folder / "old" / "Stale.st").write_text("PROGRAM Stale END_PROGRAM\n")
    (folder / "notes.txt").write_text("keep me\n")
    run = padt("import", str(FIXTURES / "plant.xml"), "-o", str(folder))
    assert run.returncode == 2
    assert "is not empty" in run.stderr and "--force" in run.stderr
    # no padt.toml: not a project folder, so not even --force empties it
    run = padt("import", str(FIXTURES / "plant.xml"), "-o", str(folder), "--force")
    assert run.returncode == 2
    assert "holds no padt.toml: --force replaces only a project folder" in run.stderr
    assert (folder / "old" / "Stale.st").exists() and not (folder / "Sequence.st").exists()
    (folder / "padt.toml").write_text('[resource]\nname = "Old"\n')
    run = padt("import", str(FIXTURES / "plant.xml"), "-o", str(folder), "--force")
    assert run.returncode == 0, run.stderr
    assert not (folder / "old" / "Stale.st").exists()  # it would be compiled with the project
    assert (folder / "notes.txt").read_text() == "keep me\n"
    assert 'name = "Mixer"' in (folder / "padt.toml").read_text()
    assert (folder / "Sequence.st").exists()


@pytest.mark.parametrize("source", ["plant", "oop"])
def test_every_cut_of_a_file_is_refused_or_imported_never_a_crash(
    tmp_path: Path, source: str
) -> None:
    data = (FIXTURES / f"{source}.xml").read_bytes()
    for number, end in enumerate(range(0, len(data), max(1, len(data) // 60))):
        xml = tmp_path / f"cut{number}.xml"
        xml.write_bytes(data[:end])
        try:
            import_plcopen(xml, tmp_path / f"out{number}")
        except ImportFailed as refused:
            assert refused.where.line >= 1 and refused.code.id.startswith("P")


def test_every_code_is_documented() -> None:
    page = (REPO / "docs" / "plcopen-import.md").read_text()
    rows = {line.split("|")[1].strip(): line.split("|")[2].strip() for line in page.splitlines()
            if line.startswith("| P0")}  # fmt: skip
    assert rows == {code.id: code.severity for code in ImportCode}


def test_a_codesys_export_with_its_global_variable_list(tmp_path: Path) -> None:
    """CODESYS keeps GVLs in the project's <addData> (imported), methods in the block's
    (imported, test_plcopen_oop.py) and a structure's EXTENDS in the type's (padt has no
    ST for it: named in an error, the structure written without it)."""
    folder, code, stderr = imported(tmp_path, "codesys")
    assert code == 1
    assert stderr.splitlines() == [
        f"{FIXTURES / 'codesys.xml'}:22:11: error: ST_Belt is imported without its CODESYS "
        "EXTENDS ST_Base (a structure extends no other in padt) [P0010]"
    ]
    assert "#   ST_Belt: its CODESYS EXTENDS ST_Base\n" in (folder / "padt.toml").read_text()
    assert (folder / "global-variables.st").read_text() == (
        "VAR_GLOBAL\n    GVL_Start : BOOL := TRUE;\n    GVL_Count : DINT;\nEND_VAR\n"
    )
    values = trace(folder, 5, ["GVL_Count"])  # no configuration: every PROGRAM runs
    assert values["GVL_Count"] == [1, 2, 3, 1, 2]  # belt.Reset() at 3


def test_task_settings_padt_cannot_keep_are_reported(tmp_path: Path) -> None:
    folder, code, stderr = imported(tmp_path, "tasks")
    assert code == 1
    lines = [line.removeprefix(f"{FIXTURES / 'tasks.xml'}:") for line in stderr.splitlines()]
    assert lines == [
        "19:7: error: 1 POU not imported: Drawn (SFC: the transition at line 25 has its "
        "condition in FBD or LD) [P0006]",
        "42:13: warning: program instance SlowOne: task priority 40 is lower than padt's "
        "lowest, 31, which it gets [P0102]",
        "44:11: warning: task Alarm has no interval (an event task): its programs run in every "
        "CPU cycle [P0102]",
        "48:13: warning: program instance DrawnOne left out: its POU Drawn is not imported "
        "(SFC: the transition at line 25 has its condition in FBD or LD) [P0103]",
        "51:9: warning: VAR_CONFIG of configuration left out [P0104]",
        "54:9: warning: resource Cpu2 ignored, with its tasks, programs and global variables: "
        "a padt project has one resource [P0101]",
    ]
    toml = (folder / "padt.toml").read_text()
    # 00:00:01.5 (TC6 1.0's xsd:time) is the shortest interval; the watchdog allows it
    assert "target_cycle_ms = 1500" in toml
    assert "watchdog_ms = 3000\nsafety_time_ms = 6000\n" in toml
    assert 'name = "SlowOne"\npou = "Slow"\nid = 1\npriority = 31' in toml
    assert 'name = "EventOne"\npou = "OnEvent"\nid = 2\npriority = 2' in toml
    compiled = padt("compile", str(folder))
    assert compiled.returncode == 0, compiled.stdout + compiled.stderr


def test_a_pou_declared_twice_is_refused(tmp_path: Path) -> None:
    text = (FIXTURES / "graphical.xml").read_text().replace('"Main"', '"TWICE"')
    xml = tmp_path / "twice.xml"
    xml.write_text(text)
    with pytest.raises(ImportFailed) as refused:
        import_plcopen(xml, tmp_path / "out")
    assert refused.value.code.id == "P0007"
    assert refused.value.message == "TWICE is declared twice (also line 15)"


PIECES = [
    *(b"<", b">", b'"', b"/>", b"</step>", b'localId="1"', b'refLocalId="9"', b"&amp;", b"\xff"),
    *(b'<step localId="77"/>', b'<connection refLocalId="3"/>', b'<transition localId="78"/>'),
    *(b"</Method>", b"<Extends>Nope</Extends>", b'<AccessModifiers Private="true"/>'),
    *(b"<GetAccessor><interface/></GetAccessor>", b'<Interface name="I_X">'),
]


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    source=st.sampled_from(
        ["plant", "tasks", "codesys", "graphical", "oop", "graphical_method", "drawn"]
    ),
    edits=st.lists(
        st.tuples(st.floats(0, 1), st.integers(0, 40), st.sampled_from(PIECES)),
        min_size=1,
        max_size=4,
    ),
)
def test_a_damaged_file_is_refused_or_imported_never_a_crash(
    tmp_path: Path, source: str, edits: list[tuple[float, int, bytes]]
) -> None:
    """Bytes cut out and pieces of markup put in anywhere: the import refuses the file at a
    place, or imports it into a project that loads; it never fails in another way."""
    data = bytearray((FIXTURES / f"{source}.xml").read_bytes())
    for where, cut, piece in edits:
        at = int(where * (len(data) - 1))
        data[at : at + cut] = piece
    xml = tmp_path / "damaged.xml"
    xml.write_bytes(bytes(data))
    out = tmp_path / "out"
    shutil.rmtree(out, ignore_errors=True)
    try:
        import_plcopen(xml, out)
    except ImportFailed as refused:
        assert refused.where.line >= 1 and refused.code.id.startswith("P")
    else:
        load_project([out])  # what an import writes always loads


def test_a_file_name_with_a_line_break_stays_in_its_comment(tmp_path: Path) -> None:
    xml = tmp_path / 'x\n[resource]\nname = "Evil".xml'
    shutil.copy(FIXTURES / "plant.xml", xml)
    import_plcopen(xml, tmp_path / "out")
    toml = (tmp_path / "out" / "padt.toml").read_text()
    assert toml.startswith('# Imported from x [resource] name = "Evil".xml by padt import.\n')
    assert 'name = "Mixer"' in toml


def test_an_anonymous_type_where_st_has_no_place_for_one(tmp_path: Path) -> None:
    """PLCopen can nest an enum inside an array; ST cannot: refused at its place."""
    enum = "<enum><values><value name='Red'/></values></enum>"
    text = (FIXTURES / "plant.xml").read_text()
    text = text.replace(
        '<dimension lower="0" upper="3"/>\n            <baseType><derived name="Percent"/>',
        f'<dimension lower="0" upper="3"/>\n            <baseType>{enum}',
    )
    xml = tmp_path / "anonymous.xml"
    xml.write_text(text)
    with pytest.raises(ImportFailed) as refused:
        import_plcopen(xml, tmp_path / "out")
    assert (refused.value.where.line, refused.value.code.id) == (83, "P0004")
    assert refused.value.message == (
        "an <enum> without a name inside <baseType> has no ST form: declare it as a data type "
        "and use its name"
    )


def test_program_instances_beyond_32_are_left_out(tmp_path: Path) -> None:
    instances = "".join(f'<pouInstance name="Run{k}" typeName="Main"/>' for k in range(1, 34))
    text = (FIXTURES / "graphical.xml").read_text()
    text = text.replace('<pouInstance name="MainInstance" typeName="Main"/>', instances)
    text = text.replace('<pouInstance name="AdderInstance" typeName="Adder"/>', "")
    xml = tmp_path / "many.xml"
    xml.write_text(text)
    result = import_plcopen(xml, tmp_path / "out")
    assert [d.message for d in result.diagnostics if d.code == "P0105"] == [
        "program instance Run33 left out: a resource runs at most 32 programs"
    ]
    project = load_project([tmp_path / "out"])
    assert project.programs is not None
    assert [p.name for p in project.programs][-1] == "Run32"


def test_elements_nested_too_deep_are_refused(tmp_path: Path) -> None:
    xml = tmp_path / "deep.xml"
    xml.write_text(
        '<project xmlns="http://www.plcopen.org/xml/tc6_0201">' + "<a>" * 300 + "</a>" * 300
        + "</project>"
    )  # fmt: skip
    with pytest.raises(ImportFailed) as refused:
        import_plcopen(xml, tmp_path / "out")
    assert refused.value.message == "refused: elements nested deeper than 200"
    assert refused.value.code.id == "P0004"


def test_a_project_name_of_any_characters_reads_back(tmp_path: Path) -> None:
    name = 'Größe "A"\\B\x7f\ttab'
    text = (FIXTURES / "plant.xml").read_text().replace("Mixing plant", "NAME")
    xml = tmp_path / "named.xml"
    xml.write_bytes(
        text.encode().replace(b"NAME", b"Gr\xc3\xb6\xc3\x9fe &quot;A&quot;\\B&#127;&#9;tab")
    )
    import_plcopen(xml, tmp_path / "out")
    assert load_project([tmp_path / "out"]).name == name
    assert 'name = "Größe' in (tmp_path / "out" / "padt.toml").read_text()


def test_a_second_configuration_is_reported_with_its_globals(tmp_path: Path) -> None:
    spare = (
        '<configuration name="Spare"><globalVars><variable name="gSpare"><type><INT/></type>'
        "</variable></globalVars></configuration>"
    )
    text = (
        (FIXTURES / "plant.xml")
        .read_text()
        .replace("</configurations>", spare + "\n</configurations>")
    )
    xml = tmp_path / "two.xml"
    xml.write_text(text)
    result = import_plcopen(xml, tmp_path / "out")
    assert [(d.code, d.message) for d in result.diagnostics] == [
        ("P0101", "configuration Spare ignored, with its global variables: a padt project has "
         "one resource"),
    ]  # fmt: skip
    assert "gSpare" not in (tmp_path / "out" / "global-variables.st").read_text()


def test_a_folder_that_cannot_be_made_is_an_error_not_a_traceback(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("")
    for target, said in (("file", "is a file, not a folder"), ("file/sub", "Not a directory")):
        run = padt("import", str(FIXTURES / "plant.xml"), "-o", str(tmp_path / target))
        assert run.returncode == 2
        assert said in run.stderr and "Traceback" not in run.stderr
