"""The language services on OSCAT (third-party ST, all chapters analysed as one project):
every name an engineer can go to lands on a declaration of that name, whose references
lead back to where they started; every POU hovers with its interface; completion after an
instance's dot offers that block's inputs and outputs."""

from __future__ import annotations

import pytest

from backend.compiler.ast import key
from backend.compiler.language.analysis import Analysis, analyse
from backend.compiler.language.completion import complete
from backend.compiler.language.hover import hover
from backend.compiler.language.navigation import definition, references
from backend.compiler.language.position import token_symbol
from backend.compiler.language.tokens import lex
from backend.compiler.types import FbType
from tests.support.corpus_paths import corpus_dir

CHAPTER = "BASIC_3.33-16_Logic_Modules.st"


@pytest.fixture(scope="module")
def oscat() -> Analysis:
    folder = corpus_dir("oscat/st")
    return analyse(
        {
            p.name: p.read_text(encoding="utf-8", errors="replace")
            for p in sorted(folder.glob("*.st"))
        }
    )


def test_definition_and_references_agree_on_every_name_of_a_chapter(oscat: Analysis) -> None:
    lexed = lex(oscat.texts[CHAPTER])
    checked = 0
    for index, token in enumerate(lexed.tokens):
        if not token.is_name() or index % 7:  # a sample: references scan every file
            continue
        target = definition(oscat, CHAPTER, token.line, token.col)
        if target is None:
            continue
        declared = oscat.texts[target.file].splitlines()[target.range.line - 1]
        assert key(declared[target.range.col - 1 : target.range.end_col - 1]) == token.upper
        found = references(oscat, target.file, target.range.line, target.range.col)
        assert target in found
        assert any(
            place.file == CHAPTER and (place.range.line, place.range.col) == (token.line, token.col)
            for place in found
        ), f"{CHAPTER}:{token.line}:{token.col} {token.text} not among its references"
        checked += 1
    assert checked > 100


def test_every_pou_hovers_with_its_interface(oscat: Analysis) -> None:
    for name in sorted(oscat.user_pous):
        pou = oscat.resolved.pous[name]
        pos = pou.pou.pos
        text = oscat.texts[pos.file]
        lexed = lex(text)
        index = lexed.index_at(pos.line, pos.col) + 1
        shown = hover(oscat, pos.file, lexed.tokens[index].line, lexed.tokens[index].col)
        assert shown is not None, f"no hover on {pou.name} at {pos}"
        assert shown.signature.splitlines()[0].startswith(f"{pou.kind} {pou.name}")
        assert len(shown.signature.splitlines()) == 1 + len(pou.parameters)


def test_completion_after_every_instance_offers_its_blocks_interface(oscat: Analysis) -> None:
    lexed = lex(oscat.texts[CHAPTER])
    offered = 0
    for index, token in enumerate(lexed.tokens[:-1]):
        if not token.is_name() or lexed.tokens[index + 1].text != ".":
            continue
        symbol = token_symbol(oscat, CHAPTER, lexed, index)
        if symbol is None or not isinstance(symbol.type, FbType):
            continue
        block = oscat.resolved.pous[key(symbol.type.name)]
        dot = lexed.tokens[index + 1]
        labels = {item.label for item in complete(oscat, CHAPTER, dot.line, dot.end_col)}
        outside = {v.name for v in block.variables if v.kind in ("VAR_INPUT", "VAR_OUTPUT")}
        assert outside <= labels
        offered += 1
    assert offered > 0
