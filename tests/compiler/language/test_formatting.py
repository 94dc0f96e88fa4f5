"""Formatting: an engineer's messy file comes back indented by its blocks with keywords in
upper case, meaning exactly what it meant; a file that does not parse is left alone with
the reason; OSCAT's files format and format again to the same text."""

from __future__ import annotations

from pathlib import Path

from backend.compiler.language.analysis import analyse
from backend.compiler.language.formatting import format_file, format_text
from backend.engineering.project import demo_project_path
from tests.support.corpus_paths import corpus_dir

TANK = (demo_project_path() / "tank.st").read_text(encoding="utf-8")


def test_a_messy_demo_formats_back_to_the_demo() -> None:
    # the program messed up, the comments as they are (their lines are theirs)
    start, end = TANK.index("PROGRAM"), TANK.index("END_PROGRAM")
    body = TANK[start:end].splitlines()
    messy_lines = [("\t  " if n % 2 else "") + line.strip() + "   " for n, line in enumerate(body)]
    messy = TANK[:start] + "\n".join(messy_lines) + "\n" + TANK[end:]
    messy = messy.replace("IF ", "if ").replace(" THEN", " then").replace("END_IF", "End_If")
    formatted = format_file(analyse({"tank.st": messy}), "tank.st")
    assert formatted.ok, formatted.refusal
    assert formatted.text == TANK


def test_case_labels_and_nested_blocks_are_indented_under_their_block() -> None:
    text = """PROGRAM P
VAR
x : INT;
s : ARRAY[1..3] OF INT;
END_VAR
case x of
1:
x := 2;
2, 3:
for x := 1 to 3 do
s[x] := LIMIT(0,
x, 10);
end_for;
else
while x > 0 do x := x - 1; end_while;
end_case;
repeat
x := x + 1;
until x > 5
end_repeat;
END_PROGRAM
"""
    expected = """PROGRAM P
VAR
  x : INT;
  s : ARRAY[1..3] OF INT;
END_VAR
CASE x OF
  1:
    x := 2;
  2, 3:
    FOR x := 1 TO 3 DO
      s[x] := LIMIT(0,
          x, 10);
    END_FOR;
ELSE
  WHILE x > 0 DO x := x - 1; END_WHILE;
END_CASE;
REPEAT
  x := x + 1;
UNTIL x > 5
END_REPEAT;
END_PROGRAM
"""
    formatted = format_text("p.st", text)
    assert formatted.ok, formatted.refusal
    assert formatted.text == expected


def test_comments_names_and_strings_keep_their_text() -> None:
    text = (
        "PROGRAM P\nVAR\n   myVar : STRING := 'if then';  (* if   x *)\nEND_VAR\n(* a\n      b *)\n"
        "myVar := 'else';\nEND_PROGRAM\n"
    )
    formatted = format_text("p.st", text)
    assert formatted.text == (
        "PROGRAM P\nVAR\n  myVar : STRING := 'if then';  (* if   x *)\nEND_VAR\n(* a\n      b *)\n"
        "myVar := 'else';\nEND_PROGRAM\n"
    )


def test_a_file_that_does_not_parse_is_left_as_it_is() -> None:
    text = "PROGRAM P\nVAR x : INT; END_VAR\n  IF x THEN\nEND_PROGRAM\n"
    formatted = format_text("p.st", text)
    assert not formatted.ok
    assert formatted.text == text
    assert "does not parse" in formatted.refusal


def test_oscat_formats_to_the_same_meaning_and_again_to_the_same_text() -> None:
    files = sorted(corpus_dir("oscat/st").glob("*.st"))[::5]
    for path in files:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
        formatted = format_text(path.name, text)
        assert formatted.ok, f"{path.name}: {formatted.refusal}"
        assert format_text(path.name, formatted.text).text == formatted.text, path.name
