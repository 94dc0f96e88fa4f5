"""The text form of drawn bodies (docs/project-format.md, "Graphical bodies"): what it
writes it reads back unchanged, a line it cannot read is refused at that line and column
with the others kept, and every diagnostic of a drawing points at the element's line."""

from __future__ import annotations

from backend.compiler.graphics.model import Element, Pin, Point, Wire
from backend.compiler.graphics.text_form import read_body, write_body
from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile

EVERY_KIND = "\n".join(
    [
        "FBD",
        "  1: IN a {at 10 20 size 40 20 out 0 40 10}",
        "  2: IN NOT b -> (NOT _)",
        "  3: BLOCK TON t1 (EN := 1, IN := NOT 1 | 2, PT := 4, R) -> (ENO, Q, NOT ET)"
        " {at 100 20 size 60 80 order 3 in 1 0 30 wire 1 0 60 30 80 30.5 wire 1 1 70 40}",
        "  4: IN T#5s",
        "  5: OUT[SET] x := 3.Q",
        "  6: INOUT y := R_EDGE 3.ENO",
        "  7: CONNECTOR c := 1",
        "  8: CONTINUATION c",
        "  9: JUMP done := F_EDGE 8",
        "  10: LABEL done",
        "  11: RETURN := 1",
        "  12: COMMENT 'it$'s $'quoted$' and $$ costs$Nmore'",
        "  13: OUT z",
        "END_FBD",
    ]
)

LADDER = """LD
  1: LEFT_RAIL -> (_, _) {at 0 0 size 3 80 out 0 3 20 out 1 3 60}
  2: CONTACT[RISING] start := 1
  3: CONTACT[NEGATED] stop := 2 | 1.x
  4: COIL[SET] motor := 3
  5: RIGHT_RAIL (4, 2)
END_LD"""


def test_what_the_form_writes_it_reads_back_unchanged() -> None:
    for text in (EVERY_KIND, LADDER):
        body, problems = read_body(text, "t.st", 10, 1)
        assert problems == []
        assert write_body(body) == text


def test_a_body_reads_into_the_elements_and_wires_of_the_drawing() -> None:
    body, _ = read_body(EVERY_KIND, "t.st", 10, 1)
    block = body.element(3)
    assert block is not None
    assert (block.kind, block.text, block.instance, block.order) == ("BLOCK", "TON", "t1", 3)
    assert (block.at, block.size, block.line, block.col) == (Point(100, 20), Point(60, 80), 13, 3)
    assert block.inputs[1] == Pin(
        "IN",
        (Wire(1, "", (Point(60, 30), Point(80, 30.5))), Wire(2, "", (Point(70, 40),))),
        "NOT",
        Point(0, 30),
    )
    assert block.inputs[3] == Pin("R")
    assert [(p.name, p.flag) for p in block.outputs] == [("ENO", ""), ("Q", ""), ("ET", "NOT")]
    comment = body.element(12)
    assert comment is not None and comment.text == "it's 'quoted' and $ costs\nmore"
    assert body.element(13) == Element(13, "OUT", "z", inputs=(Pin(),), line=23, col=3)
    ladder, _ = read_body(LADDER, "t.st", 1, 1)
    contact = ladder.element(3)
    assert contact is not None and contact.modifiers == ("NEGATED",)
    assert contact.inputs[0].wires == (Wire(2), Wire(1, "x"))


def test_a_line_that_does_not_read_is_refused_there_and_the_others_are_kept() -> None:
    text = "\n".join(
        [
            "FBD",
            "  1: IN a",
            "  2: WIRE b := 1",
            "  3: OUT b := one",
            "  4: CONTACT[SHINY] c := 1",
            "  1: IN again",
            "  5: OUT c := 1 {at 1}",
            "  7: OUT d := 1 {at inf nan}",
            "  6: OUT d := 1",
            "END_FBD",
        ]
    )
    body, problems = read_body(text, "t.st", 5, 1)
    assert [e.id for e in body.elements] == [1, 6]
    assert [str(p) for p in problems] == [
        "t.st:7:6: error: unknown element kind 'WIRE' [E0901]",
        "t.st:8:15: error: expected a wire `ID` or `ID.PIN`, not 'one' [E0901]",
        "t.st:9:14: error: CONTACT takes no modifier SHINY (it takes: NEGATED, RISING, "
        "FALLING) [E0901]",
        "t.st:10:3: error: element 1 is written twice (first on line 6) [E0901]",
        "t.st:11:18: error: wrong count of numbers after 'at' [E0901]",
        "t.st:12:18: error: a place or size is a number within ±1,000,000, not 'inf' [E0901]",
    ]


def _diagnostics(text: str) -> list[str]:
    result = compile_sources([SourceFile("main.st", text)])
    return [str(d) for d in result.diagnostics]


def test_every_diagnostic_of_a_drawing_points_at_its_element() -> None:
    program = """PROGRAM Main
VAR a : BOOL; n : INT; END_VAR
FBD
  1: IN a
  2: IN n +
  3: OUT n := 2
END_FBD
END_PROGRAM
"""
    # a syntax error in an element's expression, at the element the value goes into
    assert _diagnostics(program)[0].startswith("main.st:6:3: error: ")
    # a type error: a BOOL into an INT, at the OUT element
    typed = program.replace("  2: IN n +\n", "").replace("OUT n := 2", "OUT n := 1")
    found = _diagnostics(typed)
    assert found and all(d.startswith("main.st:5:3: error: ") for d in found), found
    # an unknown variable, named, at the element its value goes into
    unknown = typed.replace("IN a", "IN nothing")
    assert _diagnostics(unknown) == ["main.st:5:3: error: 'nothing' is not declared [E0201]"]
    # a wire from nowhere, at the element it goes into
    nowhere = typed.replace("OUT n := 1", "OUT n := 9")
    assert _diagnostics(nowhere) == [
        "main.st:5:3: error: a wire comes from element 9, which is not in the drawing [E0902]"
    ]


def _chain(blocks: int, first: str) -> str:
    """A drawing of `blocks` ADDs in a chain, each taking the one before twice."""
    lines = [f"  1: IN {first}"]
    for n in range(2, blocks + 2):
        lines.append(f"  {n}: BLOCK ADD (IN1 := {n - 1}, IN2 := {n - 1}) -> (OUT)")
    lines.append(f"  {blocks + 2}: OUT n := {blocks + 1}")
    body = "\n".join(lines)
    return f"PROGRAM Main\nVAR n : DINT; END_VAR\nFBD\n{body}\nEND_FBD\nEND_PROGRAM\n"


def test_a_crafted_drawing_is_refused_with_a_reason_not_a_hang_or_a_crash() -> None:
    # a chain whose type the drawing cannot tell would double its text at every block
    assert _diagnostics(_chain(40, "1"))[0].endswith("[E0706]")
    # continuations that feed their own connector
    looped = """PROGRAM Main
VAR n : DINT; END_VAR
FBD
  1: CONTINUATION a
  2: CONNECTOR b := 1
  3: CONTINUATION b
  4: CONNECTOR a := 3
  5: OUT n := 3
END_FBD
END_PROGRAM
"""
    assert _diagnostics(looped)[0].endswith("[E0706]")
    # a long chain the drawing can type is kept in variables: it compiles
    assert _diagnostics(_chain(3000, "n")) == []
