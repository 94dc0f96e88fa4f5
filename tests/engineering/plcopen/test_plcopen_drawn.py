"""FBD and LD bodies of PLCopen XML: imported into their text form, compiled and run, written
back to TC6 XML with everything they had, and a broken drawing refused at its place.

The round trip is checked against the XML itself, read here without the import's reader:
every element, attribute, pin, relative position and connection point of the original is
in the XML written back from the text form."""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from backend.compiler.graphics.model import GraphicBody
from backend.compiler.graphics.text_form import read_body, write_body
from backend.engineering.plcopen.graphic import graphic_body
from backend.engineering.plcopen.graphic_xml import body_xml
from backend.engineering.plcopen.importer import import_plcopen, read_plcopen
from backend.engineering.plcopen.issues import ImportFailed
from backend.engineering.plcopen.xml_tree import Element, parse_xml
from tests.conftest import padt
from tests.support.corpus_paths import corpus_dir

FIXTURES = Path(__file__).parent / "fixtures"
DRAWN = FIXTURES / "drawn.xml"


def imported(tmp_path: Path, xml: Path) -> tuple[Path, int, str]:
    folder = tmp_path / "project"
    run = padt("import", str(xml), "-o", str(folder))
    assert "Traceback" not in run.stderr
    return folder, run.returncode, run.stderr


def test_fbd_and_ld_bodies_are_imported_as_their_text_form_and_compile(tmp_path: Path) -> None:
    folder, code, stderr = imported(tmp_path, DRAWN)
    assert (code, stderr) == (0, "")
    counter = (folder / "Counter.st").read_text()
    body = counter[counter.index("\nFBD\n") + 1 : counter.index("END_FBD\n") + 8]
    assert counter.endswith("END_FBD\nEND_PROGRAM\n")
    for line in (
        # a comment's lines and quotes, escaped as in an ST string
        "  30: COMMENT 'Counts the pulses of t1 up to the limit;$Nthe count holds while "
        "$'hold$' is set.' {at 20 10 size 300 40}",
        # an FB instance with a negated input whose wire has points (one not whole)
        "  3: BLOCK TON t1 (IN := NOT 4, PT := 2) -> (Q, ET) {at 160 70 size 60 80 order 1 "
        "in 0 0 25 in 1 0 55 out 0 60 25 out 1 60 55 wire 0 0 160 95 140.5 95 140.5 40 600 40 "
        "wire 1 0 160 125 100 145}",
        "  5: CONNECTOR pulse := 3.Q {at 250 85 size 60 20 in 0 0 10 wire 0 0 250 95 220 95}",
        "  11: INOUT count := 10.OUT {at 460 190 size 60 30 order 4 in 0 0 15 out 0 60 15}",
        "  14: OUT[SET] done := 13.OUT {at 660 190 size 60 30 order 6 in 0 0 15}",
        "  15: OUT started := R_EDGE 1 {at 160 300 size 60 30 order 7 in 0 0 15}",
        "  16: BLOCK AND (IN1 := 1, IN2 := NOT 17) -> (NOT OUT) {at 160 360 size 60 60 order 8 "
        "in 0 0 15 in 1 0 45 out 0 60 15}",
        "  19: IN hold -> (NOT _) {at 20 460 size 60 30 out 0 60 15}",
        "  20: JUMP Finish := 19 {at 160 465 size 60 20 order 10 in 0 0 10}",
        "  23: LABEL Finish {at 20 580 size 80 20 order 12}",
        "  24: RETURN := 17 {at 160 620 size 60 20 order 13 in 0 0 10}",
    ):
        assert line + "\n" in body, line
    line = (folder / "Line.st").read_text()
    for rung in (
        "  1: LEFT_RAIL -> (_, _, _, _, _) {at 10 20 size 3 300 out 0 3 20 out 1 3 60 out 2 3 "
        "120 out 3 3 180 out 4 3 240}",
        # a parallel branch: two wires into one contact (a wired OR), each with its points
        "  4: CONTACT[NEGATED] stop := 2 | 3 {at 140 32 size 21 15 in 0 0 8 out 0 21 8 "
        "wire 0 0 140 40 81 40 wire 0 1 140 40 110 40 110 80 81 80}",
        "  6: CONTACT[RISING] start := 1 {at 60 132 size 21 15 in 0 0 8 out 0 21 8}",
        "  8: BLOCK TP tp1 (IN := 6, PT := 7) -> (Q, ET) {at 160 125 size 50 60 in 0 0 15 "
        "in 1 0 45 out 0 50 15 out 1 50 45}",
        "  10: CONTACT[FALLING] stop := 1 {",
        "  11: COIL[SET] alarm := 10 {",
        "  12: COIL[RESET] alarm := 2 {",
        "  14: COIL[NEGATED] lamp := 13 {",
        "  15: COIL[RISING] rose := 14 {",
        "  16: COIL[FALLING] fell := 15 {",
        # a rail's pin with nothing connected; a block drawn without outputs
        "  17: RIGHT_RAIL (5, 9, 11 | 12, 16, _) {at 420 20 size 3 300 in 0 0 20 in 1 0 120 "
        "in 2 0 180 in 3 0 240 in 4 0 280}",
        "  18: BLOCK Tally tally1 (hit := 13) -> () {at 140 290 size 60 40 in 0 0 20}",
    ):
        assert rung in line, rung
    compiled = padt("compile", str(folder))
    assert compiled.returncode == 0, compiled.stdout + compiled.stderr


def test_an_imported_ladder_runs(tmp_path: Path) -> None:
    """The LD program after import, cycle by cycle under `padt sim`: a latched motor that
    stop breaks, an alarm set on stop's falling edge and reset by start, a negated coil and
    coils on the rising and falling power flow."""
    folder, code, _ = imported(tmp_path, DRAWN)
    assert code == 0
    names = ["motor", "alarm", "lamp", "rose", "fell"]
    run = padt(
        "sim", str(folder), "--cycles", "9", "--trace", ",".join(f"line.{n}" for n in names),
        "--set", "line.start=TRUE@2", "--set", "line.start=FALSE@3",
        "--set", "line.stop=TRUE@4", "--set", "line.stop=FALSE@5",
        "--set", "line.jog=TRUE@6", "--set", "line.jog=FALSE@8",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    rows = [json.loads(row)["values"] for row in run.stdout.splitlines()]
    seen = {name: [row[f"line.{name}"] for row in rows] for name in names}
    assert seen == {
        "motor": [False, True, True, False, False, False, False, False, False],
        "alarm": [False, False, False, False, True, True, True, True, True],
        "lamp": [True, True, True, True, True, False, False, True, True],
        "rose": [False, False, False, False, False, True, False, False, False],
        "fell": [False, False, False, False, False, False, False, True, False],
    }


def test_a_codesys_ladder_is_imported_and_runs(tmp_path: Path) -> None:
    """LD as CODESYS exports it (network titles as vendor elements, `???` on an output
    nothing is connected to, no places, local ids from 10^10): imported, and it runs."""
    folder, code, stderr = imported(tmp_path, FIXTURES / "codesys_ld.xml")
    assert (code, stderr) == (0, "")
    body = (folder / "PLC_PRG.st").read_text()
    for line in (
        "  10000000002: CONTACT start := 0\n",
        "  10000000004: BLOCK TON delay (IN := 10000000002, PT := 10000000003) -> (Q, ET)\n",
        "  20000000001: CONTACT[NEGATED] stop := 20000000000\n",
    ):
        assert line in body
    assert "10000000000:" not in body  # the network title, a vendor's element, left out
    names = ["PLC_PRG.ready", "PLC_PRG.motor"]
    run = padt(
        "sim", str(folder), "--cycles", "5", "--cycle-ms", "20", "--trace", ",".join(names),
        "--set", "PLC_PRG.start=TRUE",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    rows = [json.loads(row)["values"] for row in run.stdout.splitlines()]
    # TON 50 ms on 20 ms cycles: Q at 60 ms, the fourth cycle; the motor's rung reads it
    assert [row["PLC_PRG.ready"] for row in rows] == [False, False, False, True, True]
    assert [row["PLC_PRG.motor"] for row in rows][::4] == [False, True]


def test_il_stays_refused_by_name_with_the_reason(tmp_path: Path) -> None:
    folder, code, stderr = imported(tmp_path, FIXTURES / "graphical.xml")
    assert code == 1
    assert [line for line in stderr.splitlines() if ": error: " in line] == [
        f"{FIXTURES / 'graphical.xml'}:61:7: error: 1 POU not imported: Lister (IL); IL is "
        "deprecated in IEC 61131-3 edition 3, and padt does not compile it [P0006]"
    ]
    assert sorted(p.name for p in folder.iterdir()) == [
        "Adder.st", "Ladder.st", "Main.st", "Twice.st", "padt.toml",
    ]  # fmt: skip
    assert "1: LEFT_RAIL {at 10 10 size 3 40 out 0 3 20}" in ((folder / "Ladder.st").read_text())
    toml = (folder / "padt.toml").read_text()
    assert "#   Lister: IL\n" in toml and 'name = "AdderInstance"' in toml


# ---- a drawing that breaks the schema ----------------------------------------------------

BROKEN = [
    # (what, the text replaced in drawn.xml, its replacement, the message)
    (
        "a missing localId",
        '<inVariable localId="8" height="30" width="30">',
        '<inVariable height="30" width="30">',
        "FBD: <inVariable> without its localId",
    ),
    (
        "a localId used twice",
        '<inVariable localId="8" height="30" width="30">',
        '<inVariable localId="7" height="30" width="30">',
        "FBD: localId 7 is used twice (also at line 91)",
    ),
    (
        "a connection to no element",
        '<connection refLocalId="8"/>',
        '<connection refLocalId="99"/>',
        "FBD: element 9 is connected to localId 99, which is no element of the body",
    ),
    (
        "a position that is no number",
        '<position x="160" y="240"/>',
        '<position x="160" y="twelve"/>',
        "FBD: <position> y 'twelve' is no coordinate",
    ),
    (
        "a position that is not a number at all",
        '<position x="160" y="240"/>',
        '<position x="NaN" y="240"/>',
        "FBD: <position> x 'NaN' is no coordinate",
    ),
    (
        "a block output that is not there",
        '<connection refLocalId="9" formalParameter="OUT"/>',
        '<connection refLocalId="9" formalParameter="Q"/>',
        "FBD: element 10 is connected to output Q of block 9 (ADD), which has no such output",
    ),
    (
        "a pin both negated and edge-triggered",
        '<outVariable localId="15" executionOrderId="7" height="30" width="60" negated="false"',
        '<outVariable localId="15" executionOrderId="7" height="30" width="60" negated="true"',
        "FBD: <outVariable> both negated and R_EDGE (a pin takes one of them)",
    ),
    (
        "an element of a vendor with a pin",
        "<label label=",
        '<vendorElement localId="40"><position x="0" y="0"/><connectionPointOut/>'
        "</vendorElement><label label=",
        "FBD: a <vendorElement> in an <FBD> body, which padt does not draw",
    ),
]


@pytest.mark.parametrize(("what", "old", "new", "message"), BROKEN, ids=[b[0] for b in BROKEN])
def test_a_broken_drawing_leaves_its_pou_out_and_names_the_place(
    tmp_path: Path, what: str, old: str, new: str, message: str
) -> None:
    text = DRAWN.read_text()
    assert text.count(old) == 1, what
    xml = tmp_path / "broken.xml"
    xml.write_text(text.replace(old, new))
    result = import_plcopen(xml, tmp_path / "out")
    line = text[: text.index(old)].count("\n") + 1
    errors = [(d.line, d.code, d.message) for d in result.diagnostics if d.severity == "error"]
    assert errors == [(line, "P0011", f"Counter not imported: {message}")]
    assert [m.name for m in result.not_imported] == ["Counter"]
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "Line.st",
        "Tally.st",
        "padt.toml",
    ]


def test_a_broken_drawing_through_the_command_line(tmp_path: Path) -> None:
    xml = tmp_path / "broken.xml"
    xml.write_text(DRAWN.read_text().replace('<connection refLocalId="8"/>', "<connection/>"))
    folder, code, stderr = imported(tmp_path, xml)
    assert code == 1
    assert stderr.splitlines() == [
        f"{xml}:108:65: error: Counter not imported: FBD: <connection> without its "
        "refLocalId [P0011]",
        f"{xml}:402:13: warning: program instance counter left out: its POU Counter is not "
        "imported (FBD: <connection> without its refLocalId) [P0103]",
    ]
    assert padt("compile", str(folder)).returncode == 0


# what a hostile drawing puts into attributes and texts (numbers that are none, names that
# are none, ST comments, pragmas and arrows that the text form gives a meaning)
VALUES = ["", "7", "99", "-1", "NaN", "1e9", "1.5", "true", "rising", "set", "bogus", "Q", "a b"]
TEXTS = ["a -> (b)", "x // c", "x (* c *)", "{at 1 2}", "a | b", "x}", "3: IN y", "", "a\nb"]
ATTRIBUTE = re.compile(r'(\w+)="([^"]*)"')
TEXT = re.compile(r"<(expression|variable)>([^<]*)</\1>")


def damaged(text: str, edits: list[tuple[int, float, int]]) -> str:
    """drawn.xml with attribute values, texts and whole lines changed, still well-formed
    mostly: the drawing's reader, not the XML parser, meets the damage."""
    for kind, place, pick in edits:
        if kind == 0:
            found = list(ATTRIBUTE.finditer(text))
            match = found[int(place * (len(found) - 1))]
            text = text[: match.start(2)] + VALUES[pick % len(VALUES)] + text[match.end(2) :]
        elif kind == 1:
            found = list(TEXT.finditer(text))
            match = found[int(place * (len(found) - 1))]
            text = text[: match.start(2)] + TEXTS[pick % len(TEXTS)] + text[match.end(2) :]
        else:
            lines = text.split("\n")
            at = int(place * (len(lines) - 1))
            lines[at : at + 1] = [] if kind == 2 else [lines[at]] * 2
            text = "\n".join(lines)
    return text


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    edits=st.lists(
        st.tuples(st.integers(0, 3), st.floats(0, 1), st.integers(0, 20)), min_size=1, max_size=3
    )
)
def test_a_damaged_drawing_is_refused_at_a_place_or_read_whole(
    tmp_path: Path, edits: list[tuple[int, float, int]]
) -> None:
    """Attribute values, expressions and lines of drawn.xml changed, removed or doubled: the
    file is refused at a place, or a POU is left out with the place of the fault, or each
    drawing goes through its text form unchanged; never another failure."""
    xml = tmp_path / "damaged.xml"
    xml.write_text(damaged(DRAWN.read_text(), edits))
    try:
        project = read_plcopen(xml)
    except ImportFailed as refused:
        assert refused.where.line >= 1 and refused.code.id.startswith("P")
        return
    for missing in project.not_imported:
        assert missing.problem is None or missing.problem.line >= 1
    for pou in project.pous:
        if pou.graphic is not None:
            read, problems = read_body(write_body(pou.graphic), "x.st", 1, 1)
            assert problems == [] and without_places(read) == pou.graphic, pou.name


def test_a_text_the_text_form_would_change_is_refused(tmp_path: Path) -> None:
    """An expression holding an ST comment (or a pragma, an arrow) would mean something
    else on its line: the POU is left out, at the element."""
    xml = tmp_path / "comment.xml"
    xml.write_text(DRAWN.read_text().replace("<expression>limit<", "<expression>limit // 3<"))
    result = import_plcopen(xml, tmp_path / "out")
    assert [(d.line, d.code, d.message) for d in result.diagnostics if d.code == "P0011"] == [
        (
            143,
            "P0011",
            "Counter not imported: FBD: the IN 'limit // 3' (localId 12) does not fit a line "
            "of the text form: `12: IN limit // 3 {at 460 240 size 60 30 out 0 60 15}` reads "
            "back as another element",
        )
    ]


# ---- the round trip: XML -> model -> text form -> model -> XML ----------------------------

NUMERIC = {"x", "y", "width", "height", "localId", "refLocalId", "executionOrderId"}
# an attribute at its default says nothing (TC6's defaults; 0 for no execution order, size)
DEFAULTS: dict[str, object] = {
    **{f"negated{s}": "false" for s in ("", "In", "Out")},
    **{f"edge{s}": "none" for s in ("", "In", "Out")},
    **{f"storage{s}": "none" for s in ("", "In", "Out")},
    **{name: 0.0 for name in ("executionOrderId", "width", "height")},
}
GROUPS = ("inputVariables", "inOutVariables", "outputVariables")


def canonical(element: Element) -> object:
    """What TC6 says in an element, numbers as numbers, without what says nothing (an empty
    attribute, one at its default, an empty group of pins): equal for two elements that
    say the same."""
    attrs: dict[str, object] = {}
    for key, value in element.attrs.items():
        number = float(value) if key in NUMERIC else value.strip()
        if number != "" and DEFAULTS.get(key) != number:
            attrs[key] = number
    textual = element.tag in ("expression", "content") or (
        element.tag == "variable" and "formalParameter" not in element.attrs
    )
    if textual:  # an expression, a comment's words, a contact's or coil's variable
        lines = [line.rstrip() for line in element.text().split("\n")]
        return (element.tag, sorted(attrs.items()), "\n".join(lines).strip())
    children = [canonical(c) for c in element.children if not (c.tag in GROUPS and not c.children)]
    return (element.tag, sorted(attrs.items()), children)


def bodies(root: Element) -> list[Element]:
    found = [root] if root.tag in ("FBD", "LD") else []
    for child in root.children:
        found += bodies(child)
    return found


def without_places(body: GraphicBody) -> GraphicBody:
    """The body without where it is written in a file (the text form adds that)."""
    elements = tuple(replace(e, line=0, col=0) for e in body.elements)
    return replace(body, elements=elements, line=0, col=0)


def round_trip(xml: Path) -> int:
    """Each FBD and LD body of the file through the text form and back to XML: the XML
    written says what the original says. The number of bodies."""
    originals = bodies(parse_xml(xml.read_bytes()))
    for original in originals:
        drawn = graphic_body(original)
        text = write_body(drawn)
        read, problems = read_body(text, "Body.st", 10, 1)
        assert problems == [], problems
        assert without_places(read) == drawn, f"{xml.name}:{original.where.line}"
        written = parse_xml(body_xml(read).encode())
        assert canonical(written) == canonical(original), f"{xml.name}:{original.where.line}"
        assert re.fullmatch(r"(FBD|LD)\n(  \d+: .*\n)*END_(FBD|LD)", text), text
    return len(originals)


def test_drawn_bodies_go_back_to_xml_with_everything_they_had() -> None:
    assert round_trip(DRAWN) == 2
    assert round_trip(FIXTURES / "graphical.xml") == 2


def test_corpus_bodies_go_back_to_xml_with_everything_they_had() -> None:
    """OSCAT's 24 files (an FBD program0 each, TC6 2.01 as OpenPLC writes it) and matiec's
    test projects (TC6 1.0 as Beremiz wrote it: four FBD bodies, 207 elements in all; its LD
    body is empty)."""
    oscat = sorted(corpus_dir("oscat/plcopen").glob("*.xml"))
    assert len(oscat) == 24
    assert sum(round_trip(xml) for xml in oscat) == 24
    matiec = corpus_dir("matiec/tests")
    assert round_trip(matiec / "STD_TEST.xml") == 4
    assert round_trip(matiec / "LD_TEST.xml") == 1


def test_an_action_drawn_in_ld_is_imported_as_a_drawing_and_runs(tmp_path: Path) -> None:
    folder, code, _ = imported(tmp_path, FIXTURES / "drawn_action.xml")
    assert code == 0
    text = (folder / "Belt.st").read_text()
    assert "ACTION Latch:\nLD\n" in text and "COIL[SET] motor := 2" in text
    run = padt(
        "sim", str(folder), "--cycles", "5", "--trace", "belt.motor",
        "--set", "belt.start=TRUE@2", "--set", "belt.start=FALSE@3", "--set", "belt.stop=TRUE@4",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    motor = [json.loads(row)["values"]["belt.motor"] for row in run.stdout.splitlines()]
    assert motor == [False, True, True, False, False]
