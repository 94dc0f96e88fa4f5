"""Generated code is checked before it is compiled (runtime/contract/generated_code.py): the
ways out of the restricted namespace are refused with the unit, the line and what, and every
unit the compiler makes passes.

Before, the runtime compiled whatever source an artifact carried: `_idiv.__globals__` led
from the first intrinsic to `__import__`, and a POU name put into the native tier's C went
into its text as it was."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from backend.compiler import builtins as compiler_builtins
from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile, read_source
from runtime.code.compile_worker import child_environment
from runtime.code.fault_location import code_filename
from runtime.code.intrinsics import ProgramFault, Reference, SystemView, namespace, reference_maker
from runtime.code.native.worker import ArtifactTranslation
from runtime.contract.artifact import Artifact, PouCode, VarInfo
from runtime.contract.code.names import BUILTINS, INTRINSICS, MATH_FUNCTIONS
from runtime.contract.code.statements import Evaluate
from runtime.contract.code.typed_form import Call, Const
from runtime.contract.generated_code import (
    GeneratedCodeError,
    check_artifact_names,
    check_source,
    compile_unit,
)
from tests.compiler.test_corpus_iec import FOLDERS, KNOWN, name_of, st_files
from tests.compiler.test_differential import programs
from tests.compiler.test_generated_names import KITCHEN_SINK
from tests.compiler.test_oop import DRIVES, MACHINES, MOTOR
from tests.compiler.test_sfc import QUALIFIERS
from tests.conftest import REPO
from tests.support.corpus_paths import corpus_dir
from tests.support.crafted_units import first_in_body

# a block as the compiler writes one; `{body}` lines go at the end of its `__call__`
BLOCK = """\
class POU_M:
    __slots__ = ('n', 'text', 'fb')

    def __init__(s):
        s.n = 0
        s.text = ''
        s.fb = POU_OTHER()

    def __call__(s):
        __t1 = _tick
        s.n = _idiv(s.n + 1, 2)
{body}
"""
BODY_LINE = 12  # the line of the first body line in BLOCK


def block(*lines: str) -> str:
    return BLOCK.format(body="\n".join("        " + line for line in lines))


def refusal(source: str) -> str:
    with pytest.raises(GeneratedCodeError) as refused:
        check_source(source, "<PROGRAM Main>")
    return str(refused.value)


def test_a_block_as_the_compiler_writes_it_passes() -> None:
    check_source(
        block("if __t1 is not None:", "    __t1()", "__t2 = s.fb", "__t2.__call__()"), "<PROGRAM M>"
    )


# (a body line, what the refusal names)
ESCAPES = [
    ("s.n = _idiv.__globals__['builtins']", "the attribute '__globals__'"),
    ("_idiv.__globals__['builtins'].__import__('os').system('id')", "attribute 'system'"),
    ("s.n = (1).__class__.__mro__", "the attribute '__mro__'"),
    ("s.n = ''.__class__.__base__.__subclasses__()", "attribute '__subclasses__'"),
    ("s.n = _copy.__closure__", "the attribute '__closure__'"),
    ("s.n = (x for x in range(3)).gi_frame.f_globals", "a generator expression"),
    ("s.n = str.mro()", "a call of the attribute 'mro'"),
    ("s.n = str.mro", "str other than called"),
    ("s.text = '{0.__globals__}'.format(_idiv)", "a call of the attribute 'format'"),
    ("s.text = s.text.format_map(s)", "a call of the attribute 'format_map'"),
    ("s.n = getattr(s, '__class__')", "a call of 'getattr'"),
    ("s.n = type(s)", "a call of 'type'"),
    ("s.n = eval('1')", "a call of 'eval'"),
    ("exec('import os')", "a call of 'exec'"),
    ("open('/tmp/padt-escape', 'w')", "a call of 'open'"),
    ("__import__('os')", "a call of '__import__'"),
    ("s.n = __builtins__", "the name '__builtins__'"),
    ("s.n = _math.pi", "_math other than called"),
    ("s.n = _safe_math(_math.__loader__, 1.0)", "_safe_math of anything but a function"),
    ("s.n = _safe_math(s.text.format, 1.0)", "_safe_math of anything but a function"),
    ("_math.sqrt = _copy", "_math other than called"),
    ("s.n = (lambda: 0)()", "a call of a lambda"),
    ("s.n = lambda: 0", "a lambda"),
    ("yield s.n", "a yield"),
    ("import os", "an import"),
    ("from os import system", "an import"),
    ("global x", "a global"),
    ("try:\n            pass\n        except Exception:\n            pass", "a try"),
    ("with s.fb:\n            pass", "a with"),
    ("del s.n", "a del"),
    ("s.text = f'{s}'", "an f-string"),
    ("s.n = max(*s.text)", "a starred argument"),
    ("s.n = max(s.n, key=_copy)", "max() with keywords"),
    ("s.n = _copy(s.fb, memo=s)", "_copy() with keywords"),
    ("s.n = FN_X(**s.fb)", "a ** argument"),
    ("s.n = {'a': 1}", "a dict"),
    ("s.n = {s.n}", "a set"),
    ("__builtins__ = {}", "an assignment to '__builtins__'"),
    ("_copy = s.text.format\n        _copy(s)", "_copy as a local"),
    ("(_deref := s.text.format)\n        s.n = _deref(s)", "_deref as a local"),
    ("__t2 = s.text.format\n        __t2('x')", "a call of '__t2'"),
    ("__t1 = s.text.format\n        __t1()", "a call of '__t1'"),
    ("_SYS.now_ns = 0", "an assignment to _SYS.now_ns"),
    ("s.n = _SYS.__class__", "the attribute _SYS.__class__"),
    ("_P.POU_M = s", "_P other than called"),
    ("s.n = s.M__run", "the attribute 'M__run'"),
    ("s.n = s.text.__call__", "the attribute '__call__'"),
    ("POU_M.__call__(_idiv)", "__call__ other than of a block instance"),
    ("s.n = _ref(s, ('__class__',), '')", "a reference through '__class__'"),
    ("s.n = _init(s, {'__class__': 1})", "_init of a member that is not a variable name"),
    ("s.n = _deref(s.fb).__class__.__base__", "the attribute '__base__'"),
    ("s.n = _deref(s.fb).__class__.__dict__.get('__init__', ())", "attribute 'get'"),
    ("s.n = _deref(s.fb).__class__.__dict__['KIND__']", "the attribute '__dict__'"),
    ("s.é = 1", "an assignment to the attribute 'é'"),
    ("é = 1", "an assignment to 'é'"),
    ("s.n = s.n @ s.n", "the operator MatMult"),
    ("s.n = b'x'", "a constant of type bytes"),
    ("s.n = 1j", "a constant of type complex"),
    ("s.n = ...", "a constant of type ellipsis"),
    ("class Inner:\n            pass", "a class definition"),
    ("def inner():\n            pass", "a function definition"),
    ("assert s.n", "an assert"),
    ("raise ProgramFault('x')", "a raise"),
    ("a = b = 1", "a chained assignment"),
]


@pytest.mark.parametrize(("line", "reason"), ESCAPES, ids=[line for line, _ in ESCAPES])
def test_an_escape_is_refused_naming_the_unit_the_line_and_what(line: str, reason: str) -> None:
    found = refusal(block(line))
    assert found.startswith("generated code of PROGRAM Main, line "), found
    assert reason in found, found
    assert "is not allowed" in found


def test_the_line_named_is_the_line_of_the_source() -> None:
    found = refusal(block("s.n = 1", "s.n = _idiv.__globals__"))
    assert f"line {BODY_LINE + 1}:" in found, found


# (a unit, what the refusal names): the shape of the unit around the bodies
UNITS = [
    (BLOCK.format(body="") + "import os\n", "a second top-level statement"),
    ("import os\n", "an import at the top level"),
    ("class _idiv:\n    __slots__ = ()\n", "a class named '_idiv'"),
    ("def FN_X(a=open('/tmp/x', 'w')):\n    return a\n", "a call of 'open'"),
    ("def FN_X(a=_idiv.__globals__):\n    return a\n", "the attribute '__globals__'"),
    ("@FN_Y\ndef FN_X():\n    return 1\n", "decorators"),
    ("def FN_X(*args):\n    return 1\n", "*args"),
    ("def FN_X(a: int = 1):\n    return a\n", "annotations"),
    ("class POU_M(FN_X):\n    __slots__ = ()\n", "a class with bases"),
    ("class POU_M(metaclass=FN_X):\n    __slots__ = ()\n", "a class with bases"),
    ("class POU_M:\n    def __call__(s):\n        pass\n", "a class without __slots__ first"),
    ("class POU_M:\n    __slots__ = ('__dict__',)\n", "the slot '__dict__'"),
    ("class POU_M:\n    __slots__ = ('M__run',)\n", "the slot 'M__run'"),
    ("class POU_M:\n    __slots__ = ()\n    KIND__ = (FN_X(),)\n", "KIND__ entry"),
    ("class POU_M:\n    __slots__ = ()\n    def __del__(s):\n        pass\n", "'__del__'"),
    ("class POU_M:\n    __slots__ = ()\n    __getattr__ = FN_X\n", "an assignment in a class"),
    ("class POU_M:\n    __slots__ = ()\n    M__a = _idiv.M__a\n", "an assignment in a class"),
    ("class POU_M:\n    __slots__ = ()\n    @FN_X\n    def M__a(s):\n        pass\n", "decor"),
    ("class POU_M:\n    __slots__ = ()\n    def M__a(s, x=open('f')):\n        pass\n", "'open'"),
    ("POU_M = _idiv\n", "an assignment at the top level"),
    ("async def FN_X():\n    return 1\n", "an async function at the top level"),
    ("def FN_X(:\n", "generated code of PROGRAM Main, line 1: "),
]


@pytest.mark.parametrize(("source", "reason"), UNITS, ids=[r for _, r in UNITS])
def test_a_unit_of_another_shape_is_refused(source: str, reason: str) -> None:
    found = refusal(source)
    assert reason in found, found


def test_compile_unit_compiles_nothing_it_refuses() -> None:
    with pytest.raises(GeneratedCodeError, match="line 12: the attribute '__globals__'"):
        compile_unit(block("s.n = _idiv.__globals__"), "<PROGRAM Main>")
    assert compile_unit(block(), "<PROGRAM Main>").co_filename == "<PROGRAM Main>"


def test_the_runtime_names_are_one_table() -> None:
    names = namespace(SystemView())
    assert names.keys() - {"__builtins__", "__name__"} == INTRINSICS
    assert names["__builtins__"].keys() - {"__build_class__"} == BUILTINS
    emitted = {code.removeprefix("_math.") for code in compiler_builtins._MATH.values()}
    assert emitted <= MATH_FUNCTIONS


def test_a_reference_made_at_run_time_keeps_to_variables_of_generated_objects() -> None:
    """A step the source check cannot see (`'__glo' + 'bals__'`) is refused when the code
    runs, and a reference once made cannot be changed."""
    code = compile_unit(BLOCK.format(body="").replace("POU_OTHER()", "0"), "<PROGRAM M>")
    names = namespace(SystemView())
    exec(code, names)
    instance = names["POU_M"]()
    make = reference_maker({})
    assert make(instance, ("n",), "n").get() == 0
    with pytest.raises(ProgramFault, match="through '__globals__'"):
        make(instance, ("__glo" + "bals__",), "")
    with pytest.raises(ProgramFault, match="a reference into a module"):
        make(names["_math"], ("sqrt",), "")
    with pytest.raises(ProgramFault, match="a reference into a function"):
        make(names["_idiv"], ("x",), "")
    made = make(instance, ("n",), "n")
    assert isinstance(made, Reference)
    with pytest.raises(AttributeError):
        made.steps = ("__class__",)
    with pytest.raises(AttributeError):
        made.root = names["_idiv"]


# ---- the names an artifact gives its units, which the runtime and the native tier use


def _artifact(source: str) -> Artifact:
    return _compiled([SourceFile("t.st", source)])


def _compiled(sources: list[SourceFile]) -> Artifact:
    result = compile_sources(sources)
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


FB = """
FUNCTION_BLOCK Fb
VAR_INPUT x : DINT; END_VAR
VAR_OUTPUT y : DINT; END_VAR
y := x * 2;
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : Fb; END_VAR
f(x := 1);
END_PROGRAM
"""
C_INJECTION = 'X */ __attribute__((constructor)) static void f(void) { system("touch x"); } /*'


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        ({"name": C_INJECTION}, "is not an identifier"),
        ({"class_name": "POU_X */ int y; /*"}, "is not the name of such a unit"),
        ({"class_name": "_idiv"}, "is not the name of such a unit"),
        ({"kind": "MODULE"}, "a unit of kind 'MODULE'"),
        ({"variables": (VarInfo("x", "__class__", "DINT", "VAR"),)}, "'__class__' is not a"),
        ({"variables": (VarInfo("x", "x */ y", "DINT", "VAR"),)}, "'x */ y' is not a"),
    ],
)
def test_a_unit_named_otherwise_than_the_compiler_names_it_is_refused(
    change: dict[str, object], reason: str
) -> None:
    artifact = _artifact(FB)
    fb = artifact.pou("Fb")
    hostile = replace(fb, **change)  # type: ignore[arg-type]
    others = tuple(p for p in artifact.pous if p is not fb)
    bad = replace(artifact, pous=(hostile, *others)).with_crc()
    with pytest.raises(GeneratedCodeError, match=reason.replace("*", r"\*")):
        check_artifact_names(bad)
    with pytest.raises(GeneratedCodeError):
        ArtifactTranslation.of(bad)  # nothing of it is translated to C


def test_the_native_worker_builds_nothing_of_an_artifact_with_a_name_of_its_own(
    tmp_path: Path,
) -> None:
    """The worker process, fed as the runtime feeds it: a POU name that would close the
    comment it is written into and add C of its own is refused, nothing is compiled."""
    artifact = _artifact(FB)
    fb = artifact.pou("Fb")
    named = replace(fb, name=C_INJECTION)
    bad = replace(artifact, pous=(named, *(p for p in artifact.pous if p is not fb))).with_crc()
    done = subprocess.run(
        [sys.executable, "-m", "runtime.code.native.worker", str(tmp_path / "cache")],
        input=bad.to_json().encode(),
        capture_output=True,
        env=child_environment(),
        timeout=300,
        check=False,
    )
    answer = json.loads(done.stdout)
    assert "is not an identifier" in answer.get("error", ""), answer
    assert not [p for p in tmp_path.rglob("*") if p.suffix in (".c", ".so")]
    assert not (tmp_path / "x").exists()


def test_a_name_that_reached_the_translator_stays_in_its_comment() -> None:
    """Behind the check, the translator's comments hold any name (the unit's name goes
    into the C source's first comment)."""
    artifact = _artifact(FB)
    translation = ArtifactTranslation.of(artifact)
    fb = artifact.pou("Fb")
    source = translation.translate(replace(fb, name=C_INJECTION)).source
    first = source.splitlines()[0]
    assert first.startswith("/* native code of <FUNCTION_BLOCK X * / __attribute__")
    assert first.endswith("runtime/code/native/translate.py */") and first.count("*/") == 1


def test_no_text_of_a_source_reaches_the_c_of_the_native_tier_unchecked() -> None:
    """A string constant with C in it stays Python (the tier translates no strings); a
    source that does not pass is not translated at all."""
    artifact = _artifact(
        FB.replace("y := x * 2;", 'y := x * 2; s := \'"); system("x"); ("\';').replace(
            "VAR_OUTPUT y : DINT;", "VAR_OUTPUT y : DINT; s : STRING;"
        )
    )
    translation = ArtifactTranslation.of(artifact)
    for unit in translation.units:
        assert "system(" not in translation.translate(unit).source
    fb = artifact.pou("Fb")
    first = replace(artifact, pous=(fb, *(p for p in artifact.pous if p is not fb)))
    imported = Evaluate(Call("__import__", (Const("os", "STRING"),), ""), 0)
    with pytest.raises(GeneratedCodeError, match="generated code of FUNCTION_BLOCK Fb"):
        ArtifactTranslation.of(first_in_body(first, imported))


# ---- every artifact the compiler makes passes


def _check_all(artifact: Artifact) -> None:
    check_artifact_names(artifact)
    units: list[PouCode] = [*artifact.types, *artifact.pous]
    if artifact.globals is not None:
        units.append(artifact.globals)
    for unit in units:
        check_source(unit.source, code_filename(unit))


def test_every_unit_of_the_demo_the_language_tests_and_the_feature_samples_passes() -> None:
    files = sorted(
        p for p in REPO.rglob("*.st") if ".venv" not in p.parts and "node_modules" not in p.parts
    )
    assert len(files) >= 10
    # a project's files (a folder with its padt.toml) compile together: one may declare the
    # globals another names (the SFC template does)
    projects = sorted({p.parent for p in files if (p.parent / "padt.toml").is_file()})
    # a project's tests (its test/ folder) compile with it, as `padt test` compiles them;
    # the OSCAT example's need the OSCAT library from the corpus (its own test has it)
    tests = {p: folder for folder in projects for p in files if p.is_relative_to(folder / "test")}
    for folder in projects:
        if folder.name == "oscat-tests":
            continue
        together = [
            SourceFile(p.relative_to(folder).as_posix(), p.read_text())
            for p in files
            if p.parent == folder or tests.get(p) == folder
        ]
        _check_all(_compiled(together))
    for path in files:
        if path.parent not in projects and path not in tests:
            _check_all(_artifact(path.read_text()))
    samples = [
        KITCHEN_SINK.format(names=""),
        DRIVES + "PROGRAM Main\nVAR s : Servo; END_VAR\ns(speed := 1); s.Run();\nEND_PROGRAM\n",
        MACHINES
        + "PROGRAM Main\nVAR m : Mixer; i : INamed; r : REF_TO FastMixer; k : INT; END_VAR\n"
        "i := m; r ?= i; k := i.Run(1);\nEND_PROGRAM\n",
        MOTOR + "PROGRAM Main\nVAR m : Motor; v : INT; END_VAR\nm(); v := m.Velocity;\n"
        "m.Velocity := 3;\nEND_PROGRAM\n",
        QUALIFIERS,
    ]
    for sample in samples:
        _check_all(_artifact(sample))


def test_every_unit_of_the_corpus_passes() -> None:
    """OSCAT, matiec and the rest of ../shared/corpus (skipped when it is absent, never in
    CI)."""
    corpus_dir("oscat")
    checked = 0
    for folder, together in sorted(FOLDERS.items()):
        files = [p for p in st_files(corpus_dir(folder)) if name_of(p) not in KNOWN]
        sets = [files] if together else [[p] for p in files]
        for paths in sets:
            result = compile_sources([read_source(p, name_of(p)) for p in paths], programs=[])
            assert result.artifact is not None, paths
            _check_all(result.artifact)
            checked += len(result.artifact.pous)
    assert checked > 500


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(programs())
def test_every_random_program_passes(program: str) -> None:
    _check_all(_artifact(program))
