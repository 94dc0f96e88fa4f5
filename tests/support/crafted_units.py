"""Artifacts whose first POU's typed form is changed as an attacker who read the format
would change it, every CRC redone: what only the runtime's decoding and check of the form
(runtime/contract/code/form_check.py) can refuse."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from runtime.contract.artifact import Artifact, crc32_hex
from runtime.contract.code.form_json import encode_unit
from runtime.contract.code.statements import Evaluate, Stmt
from runtime.contract.code.typed_form import Call, Const, Expr, Index, Member, Named, Repeated, This
from runtime.contract.code.units import Class, Function, Slot, Unit


def with_form(artifact: Artifact, form: str) -> Artifact:
    """`artifact` whose first POU carries `form` as its typed form."""
    pou = replace(artifact.pous[0], form=form, crc=crc32_hex(form))
    return replace(artifact, pous=(pou, *artifact.pous[1:])).with_crc()


def with_unit(artifact: Artifact, unit: Unit) -> Artifact:
    return with_form(artifact, encode_unit(unit))


def first_in_body(artifact: Artifact, *first: Stmt) -> Artifact:
    """`artifact` whose first POU's body (its class's `__call__`) begins with `first`."""
    unit = artifact.pous[0].unit
    assert isinstance(unit, Class), unit
    call = unit.functions[0]
    assert isinstance(call, Function) and call.name == "__call__", call
    called = replace(call, body=(*first, *call.body))
    return with_unit(artifact, replace(unit, functions=(called, *unit.functions[1:])))


def _text(value: str) -> Const:
    return Const(value, "STRING")


def _called(base: Expr, attr: str, *args: Expr) -> Call:
    return Call(Member(base, attr, ""), args, "")


def escape(written: Path) -> Stmt:
    """`_idiv.__globals__['builtins'].__import__('pathlib').Path(written).write_text('ran')`:
    a line that, run, writes `written` through the globals of an intrinsic (before the
    check of generated code, such a line ran when the configuration was set up)."""
    builtins = Index(Member(Named("_idiv"), "__globals__", ""), _text("builtins"), "")
    pathlib = _called(builtins, "__import__", _text("pathlib"))
    path = _called(pathlib, "Path", _text(str(written)))
    return Evaluate(_called(path, "write_text", _text("ran")), 0)


# the refusal of `escape`'s line by the check of the form
ESCAPE_REFUSED = "a call of the attribute 'write_text' is not allowed"


# the refusal of `smuggled`'s name by the decoding of the form
SMUGGLED_REFUSED = "not an identifier"


def smuggled(artifact: Artifact, written: Path) -> Artifact:
    """`artifact` whose first POU's body reads a member whose name carries a second line of
    Python: the escape, as text that only printing the name as it came would run."""
    line = f"_idiv.__globals__['builtins'].__import__('os').system('touch {written}')"
    return first_in_body(artifact, Evaluate(Member(This(""), f"x\n{line}", ""), 0))


def failing_set_up(unit: Unit) -> Class:
    """`unit`'s class with a slot whose initial value divides by zero: its set-up fails."""
    assert isinstance(unit, Class), unit
    zero = Call("_idiv", (Const(1, "INT"), Const(0, "INT")), "INT")
    return replace(unit, slots=(*unit.slots, Slot("fails", zero)))


def memory_bomb(unit: Unit) -> Class:
    """`unit`'s class with a slot of a million lists of a million values each: every count
    within the form's bounds, 10**12 cells together (a runtime that set it up would be
    killed for memory)."""
    assert isinstance(unit, Class), unit
    row = Repeated(Const(0, "INT"), 1_000_000, False, "ARRAY[1..1000000] OF INT")
    rows = Repeated(row, 1_000_000, True, "ARRAY[1..1000000] OF ARRAY[1..1000000] OF INT")
    return replace(unit, slots=(*unit.slots, Slot("huge", rows)))
