"""Artifact version 5 carries each unit's typed form, not its Python: what a runtime loads
prints the same Python, with the same ST lines, as the compiler printed from its own form,
and a form that is not one the compiler could have built refuses the whole artifact,
naming the unit and where in its form."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.contract.artifact import VERSION, Artifact, ArtifactError, load_artifact
from runtime.contract.code.statements import Evaluate
from runtime.contract.code.typed_form import Member, This
from runtime.contract.code.units import Class
from tests.support.crafted_units import first_in_body, with_form

PROGRAM = """
TYPE Pair : STRUCT a : INT; b : REAL := 1.5; END_STRUCT; END_TYPE
VAR_GLOBAL level : INT := 3; END_VAR
FUNCTION Twice : INT VAR_INPUT x : INT; END_VAR Twice := x * 2; END_FUNCTION
PROGRAM Main
VAR count : INT; p : Pair; t : TON; END_VAR
IF count > 10 THEN count := 0;
ELSIF count > 5 THEN count := count + 2;
ELSE count := Twice(x := count) + level;
END_IF
t(IN := count > 3, PT := T#1s);
END_PROGRAM
"""


def compiled() -> Artifact:
    result = compile_sources([SourceFile("main.st", PROGRAM)])
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


def test_a_loaded_artifact_prints_what_the_compiler_printed() -> None:
    artifact = compiled()
    loaded = load_artifact(artifact.to_json())
    assert loaded.version == VERSION == 5
    assert [u.name for u in loaded.units()] == [u.name for u in artifact.units()]
    kinds = {u.kind for u in loaded.units()}
    assert kinds == {"STRUCT", "FUNCTION", "FUNCTION_BLOCK", "PROGRAM", "GLOBALS"}
    for ours, theirs in zip(artifact.units(), loaded.units(), strict=True):
        assert theirs.unit == ours.unit
        assert (theirs.source, theirs.st_lines) == (ours.source, ours.st_lines)
    main = loaded.pou("Main")
    assert "source" not in json.loads(artifact.to_json())["pous"][0]
    assert isinstance(main.unit, Class) and main.unit.name == "POU_MAIN"
    lines = main.source.splitlines()
    branch = lines.index("        elif s.count > 5:") + 1
    assert lines[branch].strip().startswith("s.count = ") and main.st_lines[branch] == 8


def test_an_artifact_of_version_4_is_refused() -> None:
    data = json.loads(compiled().to_json())
    data["version"] = 4
    with pytest.raises(ArtifactError, match="artifact version 4 is not 5"):
        load_artifact(json.dumps(data))


def test_a_form_the_compiler_could_not_have_built_refuses_the_artifact() -> None:
    artifact = compiled()
    main = artifact.pous.index(artifact.pou("Main"))
    others = (*artifact.pous[:main], *artifact.pous[main + 1 :])
    first = replace(artifact, pous=(artifact.pous[main], *others))
    smuggling = first_in_body(first, Evaluate(Member(This(""), "x\nimport os", ""), 0))
    with pytest.raises(ArtifactError) as refused:
        load_artifact(smuggling.to_json())
    message = str(refused.value)
    assert message.startswith("the form of PROGRAM Main: Class.functions[0].body[0].value.name")
    assert "not an identifier" in message
    for form in ("[", '["Pass", 1]', json.dumps(["Class", "POU_MAIN", [], [], [], "extra"])):
        with pytest.raises(ArtifactError, match="the form of PROGRAM Main"):
            load_artifact(with_form(first, form).to_json())


def test_a_form_that_is_no_text_refuses_the_artifact() -> None:
    artifact = compiled()
    # as a crafted artifact's JSON may have it
    numbered = replace(artifact.pous[0], form=7)  # type: ignore[arg-type]
    crafted = replace(artifact, pous=(numbered, *artifact.pous[1:])).with_crc()
    with pytest.raises(ArtifactError, match="is int 7, not a text"):
        load_artifact(crafted.to_json())


def test_a_comment_above_a_pou_keeps_its_crc_and_changes_the_configurations() -> None:
    """The POU CRC is over its code (the printed Python), the configuration CRC over the
    forms, which carry the ST line of every statement."""
    before = compiled()
    result = compile_sources([SourceFile("main.st", "(* a comment *)\n" + PROGRAM)])
    after = result.artifact
    assert after is not None
    assert [p.crc for p in after.pous] == [p.crc for p in before.pous]
    assert after.pou("Main").form != before.pou("Main").form
    assert after.crc != before.crc
