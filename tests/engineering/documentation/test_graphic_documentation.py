"""FBD and LD bodies printed as drawings in the documentation: `padt docs` on a project with
an FBD program, an LD program and an FBD body too tall for a page, read back from the PDF
(pdftotext, page by page) and from the pages drawn (pdftoppm); and a body laid out as a
PLCopen import lays it out, drawn where TC6 put its parts."""

from __future__ import annotations

import math
import re
import shutil
import subprocess
from dataclasses import replace
from pathlib import Path

import pytest

from backend.compiler.graphics.model import Element, GraphicBody, Pin, Point, Wire
from backend.compiler.parse import parse_source
from backend.engineering.documentation.graphic_chart import WIDTH, graphic_charts
from padt.cli import main
from tests.conftest import REPO
from tests.engineering.documentation.test_document import pages

PADT_TOML = """\
[project]
name = "Drawn logic"
version = "1.0"
date = "2026-12-02"

[resource]
name = "Cell"

[[resource.program]]
name = "Mix"
pou = "Mixer"
id = 1

[[resource.program]]
name = "Motor"
pou = "MotorRung"
id = 2

[[resource.program]]
name = "Many"
pou = "Tall"
id = 3

[[resource.program]]
name = "Lights"
pou = "Sequence"
id = 4
"""

MIXER_ST = """\
PROGRAM Mixer
VAR
  speed, offset, setpoint : DINT;
  run_request : BOOL;
  running : BOOL;
  start_delay : TON;
END_VAR
FBD
  2: IN speed
  3: IN offset
  1: BLOCK ADD (IN1 := 2, IN2 := 3) -> (OUT)
  4: OUT setpoint := 1.OUT
  6: IN run_request
  7: IN T#2s
  5: BLOCK TON start_delay (IN := NOT 6, PT := 7) -> (Q, ET)
  9: OUT running := 5.Q
  8: COMMENT 'Mixer start </svg><script>alert(1)</script> & delay'
END_FBD
END_PROGRAM
"""

MOTOR_ST = """\
PROGRAM MotorRung
VAR
  start_button, stop_button, motor_on, lamp_test, alarm_latched : BOOL;
END_VAR
LD
  1: LEFT_RAIL -> (_, _, _)
  2: CONTACT start_button := 1
  3: CONTACT[NEGATED] stop_button := 2
  4: COIL motor_on := 3
  5: CONTACT motor_on := 1
  6: CONTACT[RISING] lamp_test := 1
  7: COIL[SET] alarm_latched := 5 | 6
  9: RIGHT_RAIL (4, 7)
END_LD
END_PROGRAM
"""

SEQUENCE_ST = """\
PROGRAM Sequence
VAR go, lamp, beacon : BOOL; END_VAR
INITIAL_STEP Idle : END_STEP
STEP Flashing : Flash(N); END_STEP
TRANSITION FROM Idle TO Flashing := go; END_TRANSITION
TRANSITION FROM Flashing TO Idle := NOT go; END_TRANSITION
ACTION Flash :
LD
  1: LEFT_RAIL
  2: CONTACT[NEGATED] lamp := 1
  3: COIL beacon := 2
END_LD
END_ACTION
END_PROGRAM
"""

TALL_ROWS = 60


def tall_st() -> str:
    """An FBD body of 60 copies, one under the other: taller than two pages."""
    names = [f"copy_in_{n:02d}, copy_out_{n:02d}" for n in range(TALL_ROWS)]
    lines = ["PROGRAM Tall", "VAR", f"  {', '.join(names)} : INT;", "END_VAR", "FBD"]
    for n in range(TALL_ROWS):
        lines += [
            f"  {2 * n + 1}: IN copy_in_{n:02d}",
            f"  {2 * n + 2}: OUT copy_out_{n:02d} := {2 * n + 1}",
        ]
    return "\n".join([*lines, "END_FBD", "END_PROGRAM", ""])


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, Path]:
    project = tmp_path_factory.mktemp("drawn") / "drawn-logic"
    project.mkdir()
    (project / "padt.toml").write_text(PADT_TOML)
    (project / "mixer.st").write_text(MIXER_ST)
    (project / "motor.st").write_text(MOTOR_ST)
    (project / "tall.st").write_text(tall_st())
    (project / "sequence.st").write_text(SEQUENCE_ST)
    out = tmp_path_factory.mktemp("out")
    assert main(["docs", str(project), "-o", str(out)]) == 0
    return (out / "Drawn_logic.html").read_text(), out / "Drawn_logic.pdf"


def svgs_after(html: str, caption: str) -> list[str]:
    """The drawings under the captions that start with `caption`."""
    found = re.findall(
        rf'<p class="caption">{re.escape(caption)}[^<]*</p>(<svg[^>]*class="graphic".*?</svg>)',
        html,
        re.S,
    )
    assert found, f"no drawing captioned {caption!r}"
    return found


def test_an_fbd_body_is_drawn_with_its_blocks_pins_and_variables(written) -> None:
    html, pdf = written
    (svg,) = svgs_after(html, "FBD body of Mixer")
    for shown in ("ADD", ">IN1<", ">IN2<", ">OUT<", "TON", "start_delay", ">PT<", "speed"):
        assert shown in svg
    assert "<circle" in svg, "the negated input is drawn as a circle"
    # the comment stays text: nothing of it closes the drawing or runs
    assert "&lt;/svg&gt;&lt;script&gt;" in svg and "<script" not in html
    page = next(text for text in pages(pdf) if "FBD body of Mixer" in text)
    for shown in ("ADD", "IN1", "TON", "start_delay", "setpoint", "running", "Mixer start"):
        assert shown in page, shown


def test_an_ld_body_is_drawn_with_rails_contacts_and_coils(written) -> None:
    html, pdf = written
    (svg,) = svgs_after(html, "LD body of MotorRung")
    assert svg.count('fill="#222222" stroke="none"') == 2, "a left and a right power rail"
    for mark in (">/<", ">P<", ">S<"):  # negated and rising contact, set coil
        assert mark in svg, mark
    page = next(text for text in pages(pdf) if "LD body of MotorRung" in text)
    for shown in ("start_button", "stop_button", "motor_on", "lamp_test", "alarm_latched"):
        assert shown in page, shown


def test_an_action_drawn_in_ld_is_drawn_under_its_chart(written) -> None:
    html, pdf = written
    (svg,) = svgs_after(html, "LD body of action Flash of Sequence")
    assert ">lamp<" in svg and ">beacon<" in svg and ">/<" in svg
    assert html.index("SFC chart of Sequence") < html.index("LD body of action Flash")
    page = next(text for text in pages(pdf) if "LD body of action Flash of Sequence" in text)
    assert "lamp" in page and "beacon" in page


def test_a_body_taller_than_a_page_is_split_over_pages(written) -> None:
    html, pdf = written
    parts = svgs_after(html, "FBD body of Tall")
    assert len(parts) >= 3
    for svg in parts:
        width, height = (float(v) for v in re.findall(r'(?:width|height)="([\d.]+)"', svg)[:2])
        assert width <= WIDTH and height <= 960, "a part fits a page"
    texts = pages(pdf)
    drawn = [i for i, text in enumerate(texts) if "FBD body of Tall, part" in text]
    assert len(drawn) == len(parts), "each part on a page of its own"
    seen = "".join(texts[i] for i in drawn)
    for n in range(TALL_ROWS):  # every copy drawn in some part, none lost at a cut
        assert f"copy_in_{n:02d}" in seen and f"copy_out_{n:02d}" in seen, n


def test_the_drawn_pages_show_ink_where_the_drawing_is(written, tmp_path: Path) -> None:
    """The SVG reaches the page as drawn lines, not as an empty box: the rendered page of
    the LD body has dark pixels in the rails' columns all along the rungs."""
    assert shutil.which("pdftoppm"), "poppler-utils missing: run scripts/install-document-tools.sh"
    _, pdf = written
    number = next(i for i, t in enumerate(pages(pdf), 1) if "LD body of MotorRung" in t)
    subprocess.run(
        [
            "pdftoppm",
            "-r",
            "50",
            "-gray",
            "-f",
            str(number),
            "-l",
            str(number),
            str(pdf),
            str(tmp_path / "page"),
        ],
        check=True,
    )
    (image,) = tmp_path.glob("page*.pgm")
    width, height, pixels = read_pgm(image.read_bytes())
    dark_columns = [
        x for x in range(width) if sum(pixels[y * width + x] < 100 for y in range(height)) > 40
    ]
    assert len(dark_columns) >= 2, "two power rails drawn as tall dark lines"


def read_pgm(data: bytes) -> tuple[int, int, bytes]:
    """A binary PGM (P5) as width, height and its 8-bit pixels."""
    fields = data.split(maxsplit=4)
    assert fields[0] == b"P5" and fields[3] == b"255"
    width, height = int(fields[1]), int(fields[2])
    return width, height, fields[4][: width * height]


def test_an_imported_layout_is_drawn_where_tc6_put_it() -> None:
    """A body with places, as `padt import` makes them: the boxes at their places, the wire
    through its points, and a sheet wider than a page scaled to the page's width."""
    body = GraphicBody(
        "FBD",
        (
            Element(
                2,
                "IN",
                "LocalVar0",
                outputs=(Pin(at=Point(90, 15)),),
                at=Point(430, 70),
                size=Point(90, 30),
            ),
            Element(
                1,
                "BLOCK",
                "ADD",
                inputs=(
                    Pin(
                        "IN1",
                        (
                            Wire(
                                2,
                                "",
                                (Point(560, 90), Point(540, 90), Point(540, 85), Point(520, 85)),
                            ),
                        ),
                        at=Point(0, 30),
                    ),
                    Pin("IN2", at=Point(0, 50)),
                ),
                outputs=(Pin("OUT", at=Point(70, 30)),),
                order=1,
                at=Point(560, 60),
                size=Point(70, 60),
            ),
            Element(
                4,
                "OUT",
                "LocalVar2",
                inputs=(Pin(wires=(Wire(1, "OUT"),), at=Point(0, 15)),),
                at=Point(1500, 75),
                size=Point(90, 30),
            ),
        ),
    )
    (svg,) = graphic_charts(body)
    assert '<rect x="430" y="70" width="90" height="30"' in svg
    assert '<rect x="560" y="60" width="70" height="60"' in svg
    assert 'd="M560,90 L540,90 L540,85 L520,85"' in svg, "the wire through TC6's points"
    width = float(re.search(r'width="([\d.]+)"', svg).group(1))  # type: ignore[union-attr]
    assert width == WIDTH, "the sheet is scaled to the page width"


def test_an_imported_plcopen_drawing_is_printed_as_its_author_laid_it_out(
    tmp_path: Path,
) -> None:
    """`padt import` of a PLCopen file drawn in FBD and LD, then `padt docs`: the TON block
    at the place TC6 gives it, its IN wire through TC6's points, the LD contact where the
    file puts it, both bodies on the PDF's pages."""
    xml = REPO / "tests" / "engineering" / "plcopen" / "fixtures" / "drawn.xml"
    assert main(["import", str(xml), "-o", str(tmp_path / "project")]) == 0
    assert main(["docs", str(tmp_path / "project"), "-o", str(tmp_path / "out")]) == 0
    (html_file,) = (tmp_path / "out").glob("*.html")
    html = html_file.read_text()
    (counter,) = svgs_after(html, "FBD body of Counter")
    assert '<rect x="160" y="70" width="60" height="80"' in counter, "TON t1 at 160,70"
    assert 'd="M160,95 L140.5,95 L140.5,40 L600,40"' in counter, "t1.IN's wire"
    (line,) = svgs_after(html, "LD body of Line")
    assert 'd="M60,80 L13,80"' in line, "the contact motor's wire from the left rail"
    (pdf,) = (tmp_path / "out").glob("*.pdf")
    texts = pages(pdf)
    assert any("FBD body of Counter" in t and "TON" in t and "t1" in t for t in texts)
    assert any("LD body of Line" in t and "motor" in t for t in texts)


def test_an_empty_body_draws_nothing() -> None:
    assert graphic_charts(GraphicBody("LD", ())) == []


@pytest.mark.parametrize(
    "place",
    [(math.inf, 0.0), (1e308, 0.0), (math.nan, 5.0), (0.0, -40_000_000.0), (0.0, -900_000.0)],
)
def test_a_place_no_page_can_hold_is_laid_out_anew(place: tuple[float, float]) -> None:
    """A drawing may come with any number as a place (the text form refuses those beyond
    ±1,000,000, E0901; the drawing does not count on it): it is laid out as if it gave
    none (one chart of finite numbers), not cut into millions of parts."""
    text = (
        "PROGRAM p\nVAR a : BOOL; END_VAR\nFBD\n"
        "  1: IN a {at 0 0 size 40 20}\n  2: OUT a := 1 {at 100 0 size 40 20}\n"
        "END_FBD\nEND_PROGRAM\n"
    )
    body = parse_source("p.st", text).pous[0].graphic
    first, *others = body.elements
    body = replace(body, elements=(replace(first, at=Point(*place)), *others))
    (svg,) = graphic_charts(body)
    assert not re.search(r"inf|nan|e\+", svg), svg
