"""Positions between LSP (lines from 0, UTF-16 code units unless agreed otherwise) and the
language services (lines and columns from 1, in characters): a comment of wide characters
before the cursor moves nothing, and an incremental change lands where the editor put it."""

from __future__ import annotations

from lsprotocol import types

from padt.lsp_positions import UTF8, UTF16, UTF32, Lines, edited

WIDE = "(* Füllstand ≥ 5 m³ 😀 *) level := 1;"
TEXT = f"PROGRAM P\r\n{WIDE}\nEND_PROGRAM"


def test_a_name_after_wide_characters_in_each_encoding() -> None:
    lines = Lines.of(TEXT)
    col = WIDE.index("level") + 1  # the services' column: characters
    before = WIDE[: col - 1]
    for encoding, units in (
        (UTF16, len(before.encode("utf-16-le")) // 2),
        (UTF8, len(before.encode("utf-8"))),
        (UTF32, len(before)),
    ):
        position = types.Position(1, units)
        assert lines.place(position, encoding) == (2, col)
        assert lines.position(2, col, encoding) == position
    assert lines.position(2, col, UTF16).character == col  # the emoji is two units, ü one


def test_places_past_the_end_and_inside_a_surrogate_pair() -> None:
    lines = Lines.of(TEXT)
    assert lines.place(types.Position(1, 10_000), UTF16) == (2, len(WIDE) + 1)
    assert lines.place(types.Position(99, 3), UTF16) == (3, len("END_PROGRAM") + 1)
    assert lines.position(99, 1, UTF16) == types.Position(2, len("END_PROGRAM"))
    emoji = WIDE.index("😀")
    inside = types.Position(1, emoji + 1)  # between the two halves of the pair
    assert lines.place(inside, UTF16) == (2, emoji + 2)  # the character after it
    # "\r\n": the "\r" is the line's last character, as the compiler counts columns
    assert lines.line(0) == "PROGRAM P\r"


def test_incremental_changes_and_a_whole_text() -> None:
    at = WIDE.index("1;")
    start = types.Position(1, len(WIDE[:at].encode("utf-16-le")) // 2)
    end = types.Position(1, start.character + 1)
    change = types.TextDocumentContentChangePartial(range=types.Range(start, end), text="2 + 3")
    assert edited(TEXT, change, UTF16) == TEXT.replace("level := 1;", "level := 2 + 3;")
    across = types.TextDocumentContentChangePartial(
        range=types.Range(types.Position(0, 7), types.Position(2, 3)), text=" Q\n"
    )
    assert edited(TEXT, across, UTF16) == "PROGRAM Q\n_PROGRAM"
    whole = types.TextDocumentContentChangeWholeDocument(text="x")
    assert edited(TEXT, whole, UTF16) == "x"
