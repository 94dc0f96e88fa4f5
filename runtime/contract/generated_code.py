"""Generated code beyond its typed form: the names of an artifact's units and variables,
which the runtime and the native tier use outside the code, and the compile of the Python
the runtime prints from a unit's form.

What the code itself may contain is checked on the form, where it is decoded from an
artifact (runtime/contract/code/form_check.py, `PouCode.unit`): the runtime never parses
the Python it prints. Anything refused here is a `GeneratedCodeError` (an
`ArtifactError`): a runtime answers the load with a refusal and keeps what it runs.
"""

from __future__ import annotations

from types import CodeType

from runtime.contract.artifact import Artifact, ArtifactError, PouCode
from runtime.contract.code.form_check import UNIT_KINDS
from runtime.contract.code.names import IDENTIFIER, is_data_attr


class GeneratedCodeError(ArtifactError):
    """A unit named otherwise than the compiler names units, or whose Python does not
    compile: the unit, the line, what."""


def check_artifact_names(artifact: Artifact) -> None:
    """The names of an artifact's units and variables that the runtime and the native tier
    use as attribute names and put into C: plain identifiers, units named for their kind.
    Cheap: the code is checked where its form is decoded (`PouCode.unit`)."""
    for unit in artifact.units():
        _check_unit_names(unit)
    for program in artifact.programs:
        for attr in (*program.writes, *program.reads):
            if not is_data_attr(attr):
                raise GeneratedCodeError(
                    f"program {program.name!r}: the global {attr!r} is not a variable name"
                )


def _check_unit_names(unit: PouCode) -> None:
    kind = UNIT_KINDS.get(unit.kind)
    if kind is None:
        raise GeneratedCodeError(f"a unit of kind {unit.kind!r} is not one an artifact has")
    if IDENTIFIER.match(unit.name) is None:
        raise GeneratedCodeError(f"the unit name {unit.name!r} is not an identifier")
    if kind.names.match(unit.class_name) is None:
        raise GeneratedCodeError(
            f"{unit.kind} {unit.name}: {unit.class_name!r} is not the name of such a unit"
        )
    for variable in unit.variables:
        if not is_data_attr(variable.attr):
            raise GeneratedCodeError(
                f"{unit.kind} {unit.name}: {variable.attr!r} is not a variable name"
            )


def compile_unit(source: str, filename: str) -> CodeType:
    """The code of one unit's Python, as the runtime printed it from the unit's checked
    form; `filename` (`<PROGRAM Main>`) names the unit in tracebacks and refusals. Python
    that does not compile is a GeneratedCodeError: a form can pass its check and still
    print what Python refuses (two keywords of one name, `:=` in a comprehension of a
    class body), and such a unit must be refused as its artifact's fault."""
    try:
        return compile(source, filename, "exec", dont_inherit=True)
    except SyntaxError as exc:
        raise GeneratedCodeError(f"{_unit(filename)}, line {exc.lineno}: {exc.msg}") from None
    except (ValueError, MemoryError, RecursionError) as exc:
        raise GeneratedCodeError(
            f"{_unit(filename)}: the source does not compile ({exc})"
        ) from None


def _unit(filename: str) -> str:
    return f"generated code of {filename.strip('<>')}"
