"""The cause before its consequences: a syntax error in tank.st leaves the demo without its
PROGRAM and its globals, which padt.toml names; `padt compile` says the syntax error first,
then that the errors after it may follow from it, then those errors. The analysis of the
language services orders them the same way."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from backend.compiler.language.analysis import analyse
from backend.engineering.project import demo_project_path
from tests.conftest import padt


def broken_demo(tmp_path: Path) -> Path:
    folder = tmp_path / "demo"
    shutil.copytree(demo_project_path(), folder)
    tank = folder / "tank.st"
    lines = tank.read_text(encoding="utf-8").splitlines(keepends=True)
    assert lines[24].rstrip().endswith(";")
    lines[24] = lines[24].rstrip()[:-1] + " +;\n"  # an operand missing on line 25
    tank.write_text("".join(lines), encoding="utf-8")
    return folder


def test_padt_compile_says_the_syntax_error_before_what_follows_from_it(tmp_path: Path) -> None:
    result = padt("compile", str(broken_demo(tmp_path)))
    assert result.returncode == 1
    lines = result.stderr.splitlines() or result.stdout.splitlines()
    assert lines[0].startswith("tank.st:25:") and lines[0].endswith("[E0001]"), lines
    assert lines[1].startswith("tank.st:25:") and lines[1].endswith("[N0001]"), lines
    assert "tank.st did not parse" in lines[1]
    consequences = lines[2:]
    assert consequences and all(line.startswith("padt.toml:") for line in consequences)
    assert any("no PROGRAM 'TankControl'" in line for line in consequences)


def test_padt_compile_json_has_the_same_order(tmp_path: Path) -> None:
    result = padt("compile", "--json", str(broken_demo(tmp_path)))
    report = json.loads(result.stdout)
    codes = [d["code"] for d in report["diagnostics"]]
    assert codes[:2] == ["E0001", "N0001"]
    assert [d["file"] for d in report["diagnostics"][2:]] == ["padt.toml"] * (len(codes) - 2)


def test_the_analysis_puts_a_file_that_did_not_parse_first() -> None:
    texts = {
        "a_uses.st": "PROGRAM Main\nVAR b : Helper; END_VAR\nb();\nEND_PROGRAM\n",
        "z_helper.st": "FUNCTION_BLOCK Helper\nVAR x : INT; END_VAR\nx := ;\nEND_FUNCTION_BLOCK\n",
    }
    diagnostics = analyse(texts).diagnostics
    assert [(d.file, d.code) for d in diagnostics][:2] == [
        ("z_helper.st", "E0001"),
        ("z_helper.st", "N0001"),
    ]
    assert all(d.file == "a_uses.st" for d in diagnostics[2:]) and diagnostics[2:]
