"""Write OSCAT BASIC 3.33 as one library file for `padt test --library`.

The corpus holds OSCAT BASIC as one file per chapter, each complete in itself: every
chapter repeats the POUs it needs from the others (FLOOR2, BIT_OF_DWORD, T_PLC_MS, ...)
and brings its own `program0` and CONFIGURATION. No two chapters therefore compile together
(each shared POU would be declared twice). This script reads the chapters and writes each
declaration once (the first chapter's, in chapter order), without the chapters' programs
and configurations, to a file outside the repository: OSCAT's licence keeps its sources out
of this repository (README.md).

Where chapters repeat a POU with different texts, the first is kept, except that a
repeat with inputs replaces a first text without any: the conversion of some chapters
declares the input of SINH, SQRTN and FRMP_B as a plain VAR, so those cannot be called
with an argument.

    python3 oscat_library.py [CORPUS_FOLDER] [OUTPUT_FILE]

CORPUS_FOLDER defaults to ../shared/corpus/oscat/st beside the repository, OUTPUT_FILE to
oscat_basic_3.33.st in the system's temporary folder. A declaration that a later chapter
repeats with a different text is listed on stderr (the first one is kept).
"""

from __future__ import annotations

import re
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

REPOSITORY = Path(__file__).resolve().parents[3]
DEFAULT_CORPUS = REPOSITORY.parent / "shared" / "corpus" / "oscat" / "st"
DEFAULT_OUTPUT = Path(tempfile.gettempdir()) / "oscat_basic_3.33.st"
# the String_Functions chapter is no valid IEC 61131-3: it calls BYTE_TO_STRING with two
# arguments (tests/compiler/corpus/iec_known_failures.tsv)
LEFT_OUT = {"BASIC_3.33-13_String_Functions.st"}
KINDS = ("TYPE", "FUNCTION_BLOCK", "FUNCTION", "PROGRAM", "CONFIGURATION")
DROPPED = ("PROGRAM", "CONFIGURATION")  # the chapters' demo program and its configuration
# comments, strings and words: enough of ST's lexis to find the declarations' keywords
# outside comments (an unterminated `(*` comment runs on to the next `*)`, as IEC says)
TOKEN = re.compile(
    r"\(\*.*?\*\)|/\*.*?\*/|//[^\n]*|'(?:\$.|[^'$])*'|\"(?:\$.|[^\"$])*\"|[A-Za-z_]\w*",
    re.DOTALL,
)


@dataclass(frozen=True)
class Declaration:
    kind: str
    name: str
    text: str
    chapter: str


def chapter_order(path: Path) -> tuple[int, str]:
    """BASIC_3.33-5_... before BASIC_3.33-10_...: the manual's chapter number."""
    number = re.match(r"BASIC_3\.33-(\d+)", path.name)
    return (int(number.group(1)) if number else 999, path.name)


def declarations(text: str, chapter: str) -> list[Declaration]:
    """The top-level declarations of a chapter, each with its text."""
    found: list[Declaration] = []
    start: int | None = None
    kind = name = ""
    expect_name = False
    for match in TOKEN.finditer(text):
        word = match.group(0)
        if not (word[0].isalpha() or word[0] == "_"):
            continue  # a comment or a string
        upper = word.upper()
        if expect_name:
            name, expect_name = upper, False
        if start is None and upper in KINDS:
            start, kind, expect_name = match.start(), upper, True
        elif start is not None and upper == "END_" + kind:
            found.append(Declaration(kind, name, text[start : match.end()], chapter))
            start = None
    return found


def normalised(text: str) -> str:
    """A declaration's text without comments and with single spaces, to compare repeats."""
    words = (m.group(0) for m in TOKEN.finditer(text) if not m.group(0).startswith(("(*", "/")))
    return " ".join(words).upper()


def has_inputs(item: Declaration) -> bool:
    return "VAR_INPUT" in normalised(item.text).split()


def merged(corpus: Path) -> tuple[list[Declaration], list[str]]:
    """Each declaration once, and a line for every repeat whose text differs."""
    kept: dict[tuple[str, str], Declaration] = {}
    differences: list[str] = []
    chapters = sorted(
        (p for p in corpus.glob("BASIC_3.33-*.st") if p.name not in LEFT_OUT), key=chapter_order
    )
    for path in chapters:
        text = path.read_text(encoding="utf-8").replace("\r\n", "\n")
        for item in declarations(text, path.name):
            if item.kind in DROPPED:
                continue
            key = ("TYPE" if item.kind == "TYPE" else "POU", item.name)
            first = kept.get(key)
            if first is None:
                kept[key] = item
            elif normalised(first.text) != normalised(item.text):
                if has_inputs(item) and not has_inputs(first):
                    kept[key] = item
                chosen = kept[key].chapter
                differences.append(f"{item.name}: {first.chapter}, {item.chapter}: {chosen} kept")
    return list(kept.values()), differences


def main() -> None:
    corpus = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_CORPUS
    output = Path(sys.argv[2]) if len(sys.argv) > 2 else DEFAULT_OUTPUT
    kept, differences = merged(corpus)
    if not kept:
        sys.exit(f"{corpus}: no OSCAT BASIC chapter (BASIC_3.33-*.st) found")
    for line in differences:
        print(f"repeated with another text: {line}", file=sys.stderr)
    header = (
        "(* OSCAT BASIC 3.33 (www.oscat.de), its chapters merged by oscat_library.py from "
        f"{corpus}. *)\n\n"
    )
    output.write_text(header + "\n\n".join(item.text for item in kept) + "\n", encoding="utf-8")
    print(f"{output}: {len(kept)} declarations")


if __name__ == "__main__":
    main()
