"""The FileCheck matcher (`tests/support/filecheck.py`), on small inputs and on rusty-lit."""

from __future__ import annotations

from pathlib import Path

import pytest

from runtime.code.printf import format_printf
from tests.support.corpus_paths import CORPUS as CORPUS_ROOT
from tests.support.corpus_paths import corpus_dir
from tests.support.filecheck import Check, CheckKind, match_output, parse_checks, run_line

CORPUS = CORPUS_ROOT / "rusty-lit"


def rusty_lit() -> Path:
    return corpus_dir("rusty-lit")


def check(source: str, output: str, *, full: bool = True) -> tuple[bool, str]:
    result = match_output(parse_checks(source), output, match_full_lines=full)
    return result.ok, result.message


# --- parsing ---------------------------------------------------------------------------


def test_directives_are_found_behind_code_with_their_source_lines() -> None:
    source = (
        "// RUN: (%COMPILE %s && %RUN) | %CHECK %s\n"
        "FUNCTION main\n"
        "    printf('%d$N', x);   // CHECK: 10\n"
        "    // CHECK-NEXT:   a  b  \n"
        "    // CHECK-NOT: error\n"
        "    // CHECK-SAME: tail\n"
        "    // CHECK-EMPTY:\n"
        "END_FUNCTION\n"
    )
    assert parse_checks(source) == [
        Check(CheckKind.CHECK, "10", 3),
        Check(CheckKind.NEXT, "a  b", 4),
        Check(CheckKind.NOT, "error", 5),
        Check(CheckKind.SAME, "tail", 6),
        Check(CheckKind.EMPTY, "", 7),
    ]


def test_words_that_only_contain_check_are_not_directives() -> None:
    source = (
        "// XCHECK: disabled\n"
        "// MYCHECK: other prefix\n"
        "// PRE-CHECK: hyphenated word\n"
        "// CHECK-NEXT without a colon\n"
        "// RUN: %COMPILE %s | %CHECK %s\n"
        "// CHECK : space before the colon\n"
        "// CHECKS: plural\n"
    )
    assert parse_checks(source) == []


def test_comment_prefixes_hide_a_directive_but_only_when_they_come_first() -> None:
    source = "// COM: CHECK: commented out\n// RUN: echo CHECK: x\n// CHECK: kept COM: x\n"
    assert parse_checks(source) == [Check(CheckKind.CHECK, "kept COM: x", 3)]


def test_literal_modifier_unsupported_kinds_and_crlf() -> None:
    source = (
        "// CHECK{LITERAL}: {{x}}\r\n"
        "// CHECK-NEXT{LITERAL}: [[y]]\r\n"
        "// CHECK-DAG: d\r\n"
        "// CHECK-LABEL: l\r\n"
        "// CHECK-COUNT-3: c\r\n"
    )
    assert parse_checks(source) == [
        Check(CheckKind.CHECK, "{{x}}", 1, literal=True),
        Check(CheckKind.NEXT, "[[y]]", 2, literal=True),
        Check(CheckKind.DAG, "d", 3),
        Check(CheckKind.LABEL, "l", 4),
        Check(CheckKind.COUNT, "c", 5),
    ]


def test_run_line() -> None:
    assert run_line("FUNCTION main\nEND_FUNCTION\n") is None
    assert run_line("x\n// RUN: (%COMPILE %s && %RUN) | %CHECK %s\n") == (
        "(%COMPILE %s && %RUN) | %CHECK %s"
    )
    several = "// RUN: rm -f %t\n// RUN: not %COMPILE \\\n// RUN:   --flag %s\n"
    assert run_line(several) == "rm -f %t\nnot %COMPILE --flag %s"


# --- CHECK -----------------------------------------------------------------------------


def test_check_finds_lines_in_order_skipping_others() -> None:
    source = "// CHECK: 10\n// CHECK: 30\n"
    assert check(source, "10\n20\n30\n") == (True, "all 2 checks passed")
    ok, message = check(source, "30\n10\n")
    assert not ok
    assert "CHECK: 30 (source line 2)" in message
    assert "scanning from output line 2: '10'" in message


def test_check_reports_where_the_scan_started() -> None:
    ok, message = check("// CHECK: a\n// CHECK: b\n// CHECK: zzz\n", "a\nb\nc\n")
    assert not ok
    assert message == (
        "CHECK: zzz (source line 3): not found in the output; scanning from output line 2: 'b'"
    )


def test_check_matches_whole_lines_by_default_and_substrings_on_request() -> None:
    source = "// CHECK: 10\n"
    assert not check(source, "x = 10\n")[0]
    assert not check(source, "100\n")[0]
    assert check(source, "x = 10\n", full=False)[0]
    assert check(source, "100\n", full=False)[0]


def test_whitespace_is_canonical_and_blank_ends_are_ignored() -> None:
    assert check("// CHECK: Col1\tCol2\n", "Col1 Col2\n")[0]
    assert check("// CHECK: a b\n", "  a \t  b  \n")[0]
    assert not check("// CHECK: ab\n", "a b\n")[0]


def test_regex_blocks() -> None:
    source = "// CHECK: value={{[0-9]+}} ok\n"
    assert check(source, "value=123 ok\n")[0]
    assert not check(source, "value=x ok\n")[0]
    # An alternation stays inside its block.
    assert check("// CHECK: a{{b|c}}d\n", "acd\n")[0]
    assert not check("// CHECK: a{{b|c}}d\n", "c\n")[0]
    # Outside {{ }} regex characters are literal.
    assert check("// CHECK: arr[0].x=1 (a+b)*\n", "arr[0].x=1 (a+b)*\n")[0]
    assert not check("// CHECK: a.c\n", "abc\n")[0]
    assert check("// CHECK{LITERAL}: {{x}}\n", "{{x}}\n")[0]


def test_expect_error_style_patterns_reach_the_line_ends_with_regexes() -> None:
    source = "// CHECK: {{.*}}error[E032]{{.*}}takes 2 arguments{{.*}}\n"
    assert check(source, "file.st:3:1: error[E032]: this POU takes 2 arguments but 1\n")[0]


def test_positive_check_can_continue_on_the_same_line_in_substring_mode() -> None:
    assert check("// CHECK: a\n// CHECK: b\n", "a b\n", full=False)[0]
    assert not check("// CHECK: b\n// CHECK: a\n", "a b\n", full=False)[0]


# --- CHECK-NEXT ------------------------------------------------------------------------


def test_check_next_on_the_next_line() -> None:
    source = "// CHECK: 1\n// CHECK-NEXT: 2\n// CHECK-NEXT: 3\n"
    assert check(source, "1\n2\n3\n")[0]


def test_check_next_not_on_the_next_line() -> None:
    source = "// CHECK: 1\n// CHECK-NEXT: 3\n"
    ok, message = check(source, "1\n2\n3\n")
    assert not ok
    assert message == (
        "CHECK-NEXT: 3 (source line 2): first match is on output line 3: '3', not the line "
        "after the previous match on output line 1: '1'"
    )


def test_check_next_on_the_same_line_fails() -> None:
    ok, message = check("// CHECK: a\n// CHECK-NEXT: b\n", "a b\nb\n", full=False)
    assert not ok
    assert "the same line as the previous match" in message


def test_check_next_missing_altogether() -> None:
    ok, message = check("// CHECK: 1\n// CHECK-NEXT: 2\n", "1\n")
    assert not ok
    assert "not found" in message


def test_check_next_without_a_previous_match_is_an_error() -> None:
    ok, message = check("// CHECK-NOT: x\n// CHECK-NEXT: 1\n", "1\n")
    assert not ok
    assert "no previous CHECK match" in message


# --- CHECK-SAME ------------------------------------------------------------------------


def test_check_same() -> None:
    source = "// CHECK: ret=\n// CHECK-SAME: ok\n"
    assert check(source, "ret= ok\n", full=False)[0]
    ok, message = check(source, "ret=\nok\n", full=False)
    assert not ok
    assert "not on the line of the previous match" in message
    # The text must come after the previous match, not before it.
    assert not check("// CHECK: b\n// CHECK-SAME: a\n", "a b\n", full=False)[0]


def test_check_same_after_a_full_line_match_finds_nothing_left_on_the_line() -> None:
    # With --match-full-lines the previous match took the whole line, as in FileCheck.
    assert not check("// CHECK: a b\n// CHECK-SAME: b\n", "a b\n")[0]


# --- CHECK-NOT -------------------------------------------------------------------------


def test_check_not_between_matches() -> None:
    source = "// CHECK: start\n// CHECK-NOT: error\n// CHECK: end\n"
    assert check(source, "start\nfine\nend\nerror after the end\n")[0]
    ok, message = check(source, "start\nan error here\nend\n")
    assert not ok
    assert message == (
        "CHECK-NOT: error (source line 2): excluded text found on output line 2: 'an error here'"
    )


def test_check_not_at_the_end_runs_to_the_end_of_the_output() -> None:
    source = "// CHECK: start\n// CHECK-NOT: error\n"
    assert check(source, "error\nstart\nok\n")[0]
    ok, message = check(source, "start\nok\nerror\n")
    assert not ok
    assert "output line 3" in message


def test_check_not_before_the_first_match_and_only_nots() -> None:
    assert not check("// CHECK-NOT: bad\n// CHECK: good\n", "bad\ngood\n")[0]
    assert check("// CHECK-NOT: bad\n", "good\n")[0]
    assert not check("// CHECK-NOT: bad\n", "so bad\n")[0]


def test_check_not_is_a_substring_match_even_for_whole_lines() -> None:
    assert not check("// CHECK: a\n// CHECK-NOT: rr\n", "a\nerror\n")[0]


def test_check_not_covers_the_rest_of_the_previous_line() -> None:
    source = "// CHECK: a\n// CHECK-NOT: x\n// CHECK: b\n"
    assert not check(source, "a x\nb\n", full=False)[0]
    assert check(source, "x a\nb x\n", full=False)[0]


# --- CHECK-EMPTY -----------------------------------------------------------------------


def test_check_empty() -> None:
    source = "// CHECK: Line1\n// CHECK-EMPTY:\n// CHECK-NEXT: Line3\n"
    assert check(source, "Line1\n\nLine3\n")[0]
    ok, message = check(source, "Line1\nLine2\n\nLine3\n")
    assert not ok
    assert "CHECK-EMPTY:" in message and "output line 3" in message
    assert not check(source, "Line1\n \nLine3\n")[0]


# --- malformed checks ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("", "no CHECK directives"),
        ("// CHECK:\n", "empty pattern"),
        ("// CHECK: a\n// CHECK-EMPTY: b\n", "must have an empty pattern"),
        ("// CHECK-DAG: a\n", "CHECK-DAG is not supported"),
        ("// CHECK-LABEL: a\n", "CHECK-LABEL is not supported"),
        ("// CHECK: [[x:.*]]\n", "substitution blocks are not supported"),
        ("// CHECK: {{[}}\n", "invalid regular expression"),
        ("// CHECK: {{abc\n", "without a closing"),
        ("// CHECK-SAME: a\n", "no previous CHECK match"),
    ],
)
def test_malformed_checks_fail_with_a_reason(source: str, expected: str) -> None:
    ok, message = check(source, "a\n")
    assert not ok
    assert expected in message


# --- the corpus ------------------------------------------------------------------------


def corpus_files() -> list[Path]:
    return sorted(rusty_lit().rglob("*.st"))


def is_expect_error(path: Path) -> bool:
    return path.relative_to(CORPUS).parts[0] == "expect-error"


def test_every_runnable_corpus_file_has_checks() -> None:
    files = corpus_files()
    assert files, f"no .st files under {CORPUS}"
    runnable = [path for path in files if not is_expect_error(path)]
    assert runnable
    for path in files:
        source = path.read_text(encoding="utf-8")
        checks = parse_checks(source)
        assert run_line(source) is not None, path
        if not is_expect_error(path):
            assert checks, f"{path.relative_to(CORPUS)} yields no checks"
            # Only the directives rusty's runnable tests use; nothing left unsupported.
            assert {c.kind for c in checks} <= {CheckKind.CHECK, CheckKind.NEXT}, path


def test_each_runnable_corpus_file_accepts_its_own_expected_lines() -> None:
    # An output made of the patterns, one a line, must pass; this runs the parser and the
    # whole-line matcher over the corpus's real patterns (tabs, brackets, unicode, ...).
    for path in corpus_files():
        if is_expect_error(path):
            continue
        checks = parse_checks(path.read_text(encoding="utf-8"))
        output = "".join(c.pattern + "\n" for c in checks)
        result = match_output(checks, output)
        assert result.ok, f"{path.relative_to(CORPUS)}: {result.message}"


def test_disabled_xcheck_in_string_escapes_is_not_a_check() -> None:
    source = (rusty_lit() / "string_escapes" / "string_escapes.st").read_text(encoding="utf-8")
    patterns = [c.pattern for c in parse_checks(source)]
    assert "Price: $100" not in patterns
    assert "Col1\tCol2" in patterns


def test_integer_overflow_output_from_format_printf() -> None:
    # arithmetic/integer_overflow.st, with its printf calls replayed by hand: the values
    # before and after each type wraps.
    source = (rusty_lit() / "arithmetic" / "integer_overflow.st").read_text(encoding="utf-8")
    calls = [
        ("%d\n", 127),
        ("%d\n", 32767),
        ("%d\n", 2147483647),
        ("%lld\n", 9223372036854775807),
        ("%u\n", 255),
        ("%u\n", 65535),
        ("%u\n", 4294967295),
        ("%llu\n", 18446744073709551615),
        ("%d\n", -128),
        ("%d\n", -32768),
        ("%d\n", -2147483648),
        ("%lld\n", -9223372036854775808),
        ("%u\n", 0),
        ("%u\n", 0),
        ("%u\n", 0),
        ("%llu\n", 0),
    ]
    checks = parse_checks(source)
    output = "".join(format_printf(fmt, [value]) for fmt, value in calls)
    assert match_output(checks, output).ok

    # A SINT that did not wrap (prints 128) must be caught, at the right source line.
    broken = output.replace("-128\n", "128\n")
    result = match_output(checks, broken)
    assert not result.ok
    line = next(c.line for c in checks if c.pattern == "-128")
    assert f"CHECK: -128 (source line {line})" in result.message
