"""The saved context for a warm start (runtime/context.py, docs/context.md): snapshot and
restore of compiled programs, and the context file (checksum, signature, atomic save)."""

from __future__ import annotations

import hashlib
import json
import math
import struct
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.code.code_image import CodeImage
from runtime.code.intrinsics import SystemView
from runtime.context import (
    CONTEXT_FORMAT,
    CONTEXT_VERSION,
    Context,
    ContextInvalid,
    encode_context,
    load_context,
    save_context,
)
from runtime.context_snapshot import ContextMismatch, UnsupportedValue, restore, snapshot
from runtime.contract.artifact import Artifact
from tests.conftest import REPO

CYCLE_NS = 100_000_000

KINDS = """
TYPE Color : (Red, Green, Blue); END_TYPE
TYPE Point : STRUCT x : REAL; y : LREAL; tag : STRING[8]; END_STRUCT; END_TYPE
VAR_GLOBAL
  gCount : UDINT;
  gPoints : ARRAY[0..2] OF Point;
  gMatrix : ARRAY[1..2, 1..3] OF LINT;
END_VAR
FUNCTION_BLOCK Inner
VAR_INPUT go : BOOL; END_VAR
VAR count : DINT; edge : R_TRIG; pts : ARRAY[1..2] OF Point; END_VAR
edge(CLK := go);
IF edge.Q THEN count := count + 1; pts[2].x := pts[2].x + 0.5; END_IF;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Outer
VAR_INPUT go : BOOL; END_VAR
VAR inner : Inner; timer : TON; END_VAR
inner(go := go);
timer(IN := TRUE, PT := T#10s);
END_FUNCTION_BLOCK
PROGRAM Kinds
VAR
  b : BOOL; si : SINT; i : INT; di : DINT; li : LINT;
  usi : USINT; ui : UINT; udi : UDINT; uli : ULINT;
  by : BYTE; w : WORD; dw : DWORD; lw : LWORD;
  r : REAL; lr : LREAL; nan : LREAL; negzero : LREAL; inf : REAL; one : LREAL;
  t : TIME; lt : LTIME; d : DATE; tod : TOD; dt : DT;
  s : STRING; ws : WSTRING; c : CHAR; col : Color;
  outer : Outer; pts : ARRAY[1..3] OF Point; grid : ARRAY[0..1, 0..2] OF INT;
  cycles : INT;
END_VAR
cycles := cycles + 1;
outer(go := cycles MOD 2 = 0);
gCount := gCount + 1;
gPoints[1].y := gPoints[1].y - 0.25;
gMatrix[2, 3] := gMatrix[2, 3] - 1;
pts[3].tag := 'abc';
grid[1, 2] := cycles * 100;
col := Blue;
d := D#2024-01-31; tod := TOD#12:00:00.5; dt := DT#2024-01-31-12:00:00;
t := T#1h2m3.5s; lt := LTIME#5ns;
END_PROGRAM
"""

SFC = """
PROGRAM Chart
VAR go : BOOL; running : BOOL; ticks : INT; END_VAR
INITIAL_STEP Idle: END_STEP
TRANSITION FROM Idle TO Run := go; END_TRANSITION
STEP Run: running(N); Tick(N); END_STEP
TRANSITION FROM Run TO Done := Run.T >= T#500ms; END_TRANSITION
STEP Done: END_STEP
TRANSITION FROM Done TO Idle := NOT go; END_TRANSITION
ACTION Tick: ticks := ticks + 1; END_ACTION
END_PROGRAM
"""

TIMER = """
PROGRAM Delay
VAR start : BOOL := TRUE; t : TON; done : BOOL; END_VAR
t(IN := start, PT := T#1s);
done := t.Q;
END_PROGRAM
"""

IN_OUT = """
TYPE Pair : STRUCT a, b : INT; END_STRUCT; END_TYPE
FUNCTION_BLOCK Bump
VAR_IN_OUT arr : ARRAY[1..3] OF INT; pair : Pair; END_VAR
arr[1] := arr[1] + 1; pair.b := pair.b + 2;
END_FUNCTION_BLOCK
PROGRAM Caller
VAR f : Bump; a : ARRAY[1..3] OF INT; p : Pair; END_VAR
f(arr := a, pair := p);
END_PROGRAM
"""


def compiled(text: str) -> Artifact:
    result = compile_sources([SourceFile("context.st", textwrap.dedent(text))])
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


class Running:
    """One program of an artifact in its own code image, run on virtual time."""

    def __init__(self, artifact: Artifact, pou: str) -> None:
        self.system = SystemView()
        self.image = CodeImage(artifact, self.system)
        self.program = self.image.new_instance(pou)
        self.time_ns = 0

    def cycle(self, **inputs: Any) -> None:
        for name, value in inputs.items():
            setattr(self.program, name, value)
        self.system.now_ns = self.time_ns
        self.program()
        self.time_ns += CYCLE_NS

    def context(self, artifact: Artifact, saved_ns: int = 1_700_000_000_000_000_000) -> Context:
        return Context(
            signature=artifact.crc,
            saved_ns=saved_ns,
            resource={"cycle": 7},
            programs={
                "P": {"state": "RUN", "time_ns": self.time_ns, "values": snapshot(self.program)}
            },
            globals=snapshot(self.image.globals),
        )

    def warm_start(self, context: Context) -> None:
        restore(self.program, context.programs["P"]["values"])
        restore(self.image.globals, context.globals)
        self.time_ns = context.programs["P"]["time_ns"]


def bits(value: float) -> bytes:
    return struct.pack("<d", value)


def loaded(path: Path, signature: str) -> Context:
    context = load_context(path, signature)
    assert isinstance(context, Context), context
    return context


def invalid(path: Path, signature: str) -> str:
    context = load_context(path, signature)
    assert isinstance(context, ContextInvalid), context
    return context.reason


# ---- snapshot and restore of compiled programs


def test_every_kind_of_value_survives_save_load_and_restore(tmp_path: Path) -> None:
    artifact = compiled(KINDS)
    before = Running(artifact, "Kinds")
    for _ in range(5):
        before.cycle()
    p = before.program
    signed_nan = struct.unpack("<d", struct.pack("<Q", 0xFFF8_0000_0000_1234))[0]
    p.nan, p.negzero, p.inf, p.one = signed_nan, -0.0, -math.inf, 1.0
    p.r, p.lr = 0.10000000149011612, 1 / 3
    p.li, p.uli, p.lw = -(2**63), 2**64 - 1, 2**64 - 2
    p.s = "caf\xe9 \xff\x00$"  # a STRING holds bytes: chars above 127 and NUL
    p.ws = "\U0001f600 \udc00 \u20ac"  # UTF-16 code units, a lone surrogate included
    p.c = "\xa7"
    p.pts[2].y = 5e-324
    before.image.globals.gPoints[0].x = math.nan
    original = before.context(artifact)

    save_context(tmp_path / "context", original)
    context = loaded(tmp_path / "context", artifact.crc)
    assert context == original
    after = Running(artifact, "Kinds")
    after.warm_start(context)

    assert snapshot(after.program) == snapshot(before.program)
    assert snapshot(after.image.globals) == snapshot(before.image.globals)
    q = after.program
    assert bits(q.nan) == bits(signed_nan)  # sign and payload of a NaN
    assert bits(q.negzero) == bits(-0.0)
    assert q.inf == -math.inf
    assert type(q.one) is float and q.one == 1.0  # a float never turns into an int
    assert (q.r, q.lr) == (0.10000000149011612, 1 / 3)
    assert (q.li, q.uli, q.lw) == (-(2**63), 2**64 - 1, 2**64 - 2)
    assert type(q.b) is bool and type(q.i) is int
    assert (q.s, q.ws, q.c) == (p.s, p.ws, p.c)
    assert q.pts[2].y == 5e-324
    assert q.outer.inner.count == p.outer.inner.count == 2  # nested FB instances
    assert q.outer.inner.pts[1].x == 1.0  # ST pts[2]: lists count from 0
    assert q.outer.timer.ET == 400_000_000 and q.outer.timer.running
    assert q.grid == [0, 0, 0, 0, 0, 500]
    assert math.isnan(after.image.globals.gPoints[0].x)
    assert after.image.globals.gMatrix == [0, 0, 0, 0, 0, -5]

    # the warm-started program goes on exactly as the original does
    for _ in range(4):
        before.cycle()
        after.cycle()
        assert snapshot(after.program) == snapshot(before.program)
        assert snapshot(after.image.globals) == snapshot(before.image.globals)


def test_a_timer_restored_mid_timing_runs_out_on_time() -> None:
    artifact = compiled(TIMER)
    before = Running(artifact, "Delay")
    for _ in range(4):
        before.cycle()
    assert before.program.t.ET == 300_000_000
    after = Running(artifact, "Delay")
    after.warm_start(before.context(artifact))
    assert after.program.t.ET == 300_000_000 and after.time_ns == before.time_ns
    done = []
    for _ in range(8):
        before.cycle()
        after.cycle()
        assert snapshot(after.program) == snapshot(before.program)
        done.append(after.program.done)
    assert done == [False] * 6 + [True] * 2  # ET reaches 1 s at program time 1.0 s


def test_an_sfc_restores_its_active_step_and_step_time() -> None:
    artifact = compiled(SFC)
    before = Running(artifact, "Chart")
    before.cycle()
    before.cycle(go=True)  # Idle -> Run
    before.cycle()
    before.cycle()
    chart = before.program
    assert (chart.Idle.X, chart.Run.X, chart.Done.X) == (False, True, False)
    assert chart.Run.T == 100_000_000 and chart.running and chart.ticks == 2

    after = Running(artifact, "Chart")
    assert after.program.Idle.X and not after.program.Run.X  # the cold-start state
    after.warm_start(before.context(artifact))
    restored = after.program
    assert (restored.Idle.X, restored.Run.X, restored.Done.X) == (False, True, False)
    assert restored.Run.T == 100_000_000 and restored.running and restored.ticks == 2

    trace = []
    for _ in range(6):
        before.cycle()
        after.cycle()
        assert snapshot(after.program) == snapshot(before.program)
        trace.append((restored.Run.X, restored.Done.X, restored.ticks))
    # Run's time counts across the warm start: it reaches 500 ms in the 4th cycle after it
    assert trace == [
        (True, False, 3),
        (True, False, 4),
        (True, False, 5),
        (False, True, 6),  # Run.T = 500 ms: the transition fires at the end of the cycle
        (False, True, 7),  # the final scan of Tick
        (False, True, 7),
    ]


def test_a_var_in_out_binding_stays_one_array() -> None:
    artifact = compiled(IN_OUT)
    before = Running(artifact, "Caller")
    before.cycle()
    before.cycle()
    tree = snapshot(before.program)
    assert "@" in json.dumps(tree)  # the FB's in-out slots alias the caller's variables
    after = Running(artifact, "Caller")
    restore(after.program, json.loads(json.dumps(tree)))
    assert after.program.f.arr is after.program.a and after.program.f.pair is after.program.p
    assert after.program.a == [2, 0, 0] and after.program.p.b == 4
    assert snapshot(after.program) == tree
    before.cycle()
    after.cycle()
    assert snapshot(after.program) == snapshot(before.program)


def test_restore_fills_containers_in_place() -> None:
    artifact = compiled(KINDS)
    before = Running(artifact, "Kinds")
    before.cycle()
    after = Running(artifact, "Kinds")
    points, outer = after.image.globals.gPoints, after.program.outer
    after.warm_start(before.context(artifact))
    # `_G` in the generated code and `prog();` registrations keep pointing at the same objects
    assert after.image.globals.gPoints is points and after.program.outer is outer


def test_snapshot_is_json_and_deterministic() -> None:
    artifact = compiled(KINDS)
    one, two = Running(artifact, "Kinds"), Running(artifact, "Kinds")
    for running in (one, two):
        running.cycle()
        running.program.nan = math.nan
    assert encode_context(one.context(artifact)) == encode_context(two.context(artifact))
    tree = snapshot(one.program)
    assert json.loads(json.dumps(tree, allow_nan=False)) == tree


# ---- mismatches: validate first, then write


def test_a_tree_of_another_layout_is_refused_and_nothing_is_written() -> None:
    old = compiled("PROGRAM P VAR a : INT; b : REAL; zz : ARRAY[1..3] OF INT; END_VAR END_PROGRAM")
    new = compiled("PROGRAM P VAR a : INT; b : REAL; zz : ARRAY[1..4] OF INT; END_VAR END_PROGRAM")
    saved = Running(old, "P").program
    saved.a, saved.b = 42, 2.5
    target = Running(new, "P").program
    untouched = snapshot(target)
    with pytest.raises(ContextMismatch) as error:
        restore(target, snapshot(saved))
    # `a` and `b` come before `zz` and fit: they must not have been written either
    assert snapshot(target) == untouched
    assert str(error.value) == "zz: expected an array of 4, found an array of 3"


def fields(tree: Any, *path: str | int) -> Any:
    """The fields of the instance node at `path` below `tree`."""
    node = tree
    for key in path:
        node = node["v"][key] if isinstance(key, str) else node[key]
    return node["v"]


MISMATCHES: list[tuple[Any, str]] = [
    (lambda t: fields(t).pop("i"), "POU_P fields differ: missing ['i'], unknown none"),
    (lambda t: fields(t).update(x=1), "POU_P fields differ: missing none, unknown ['x']"),
    (lambda t: t.update(c="POU_Q"), "expected an instance of POU_P, found POU_Q"),
    (
        lambda t: fields(t)["pts"][1].update(c="STRUCT_OTHER"),
        "pts[1]: expected an instance of STRUCT_PT, found STRUCT_OTHER",
    ),
    (
        lambda t: fields(t, "pts", 0).update(x=[1]),
        "pts[0].x: expected a value, found an array of 1",
    ),
    (lambda t: fields(t).update(t=5), "t: expected an instance of POU_TON, found a value"),
    (lambda t: fields(t).update(pts={"@": 99}), "pts: alias to an unknown container 99"),
    (
        lambda t: fields(t).update(pts={"@": 0}),
        "pts: alias to an instance of POU_P where an array of 2 is",
    ),
    (
        lambda t: fields(t).update(r={"ieee": "0000000000000000"}),
        "r: malformed NaN or infinity '0000000000000000'",  # 0.0 is a plain number
    ),
    (lambda t: fields(t).update(r={"ieee": "zz"}), "r: malformed NaN or infinity 'zz'"),
    (lambda t: fields(t).update(r={"what": 1}), "r: malformed node {'what': 1}"),
    (lambda t: fields(t).update(r=(1, 2)), "r: malformed node (1, 2)"),
    (lambda t: fields(t).update(i="7"), "i: expected a whole number, found '7'"),
    (lambda t: fields(t).update(i=True), "i: expected a whole number, found True"),
    (lambda t: fields(t).update(i=7.0), "i: expected a whole number, found 7.0"),
    (
        lambda t: fields(t).update(r=10**400),
        "r: expected a number, found " + str(10**400)[:57] + "...",
    ),
    (lambda t: fields(t, "pts", 1).update(y=None), "pts[1].y: expected a number, found None"),
    (lambda t: fields(t, "t").update(Q=0), "t.Q: expected TRUE or FALSE, found 0"),
]


@pytest.mark.parametrize(("change", "message"), MISMATCHES)
def test_every_mismatch_names_where_and_writes_nothing(change: Any, message: str) -> None:
    artifact = compiled(
        """
        TYPE PT : STRUCT x, y : REAL; END_STRUCT; END_TYPE
        PROGRAM P VAR i : INT; r : REAL; t : TON; pts : ARRAY[1..2] OF PT; END_VAR END_PROGRAM
        """
    )
    saved = Running(artifact, "P").program
    saved.i, saved.r, saved.pts[0].y = 7, 1.5, 2.5
    tree = snapshot(saved)
    change(tree)
    target = Running(artifact, "P").program
    untouched = snapshot(target)
    with pytest.raises(ContextMismatch) as error:
        restore(target, tree)
    assert str(error.value) == message
    assert snapshot(target) == untouched


def test_a_whole_number_saved_for_a_real_comes_back_as_a_float() -> None:
    """What generated code, and the native tier on every read, rely on: a REAL holds a
    float (a context saved while a Modbus input fed a REAL the integer 0 held `0`)."""
    artifact = compiled(
        """
        TYPE PT : STRUCT x, y : REAL; END_STRUCT; END_TYPE
        PROGRAM P VAR r : REAL; pts : ARRAY[1..2] OF PT; rs : ARRAY[1..3] OF LREAL; END_VAR
        END_PROGRAM
        """
    )
    tree = snapshot(Running(artifact, "P").program)
    fields(tree).update(r=3, rs=[1, 2.5, -4])
    fields(tree, "pts", 1).update(y=0)
    target = Running(artifact, "P").program
    restore(target, tree)
    assert (target.r, target.rs, target.pts[1].y) == (3.0, [1.0, 2.5, -4.0], 0.0)
    assert {type(target.r), *map(type, target.rs), type(target.pts[1].y)} == {float}


def test_restore_of_missing_globals() -> None:
    restore(None, None)  # no globals in the code, none saved
    with pytest.raises(ContextMismatch, match="cannot restore into a NoneType"):
        restore(None, {"c": "GLOBALS", "v": {}})
    artifact = compiled("VAR_GLOBAL g : INT; END_VAR PROGRAM P g := 1; END_PROGRAM")
    with pytest.raises(ContextMismatch, match="expected an instance of GLOBALS, found a value"):
        restore(Running(artifact, "P").image.globals, None)


# ---- any object with slots or a __dict__


class Base:
    __slots__ = ("__weakref__", "a")


class Derived(Base):
    __slots__ = ("__hidden", "b", "link")

    def __init__(self) -> None:
        self.a, self.__hidden = 1, "h"
        self.b: Any = 2.5
        self.link: Any = None


class Loose:
    def __init__(self) -> None:
        self.x = 1.5
        self.items: list[Any] = [Derived(), Derived()]
        # what a fresh instance is bound to, as generated code binds VAR_IN_OUT slots
        self.items[0].link = self.items[1]  # an alias
        self.items[1].link = self  # a cycle


def test_slots_of_base_classes_private_slots_and_plain_dicts() -> None:
    source = Loose()
    source.items[1].a = 10
    source.items[1].b = math.inf
    tree = snapshot(source)
    assert tree["c"] == "Loose"
    assert set(fields(tree, "items", 0)) == {"_Derived__hidden", "a", "b", "link"}
    target = Loose()
    restore(target, json.loads(json.dumps(tree)))
    assert target.items[1].a == 10 and target.items[1].b == math.inf
    assert target.items[0].link is target.items[1] and target.items[1].link is target
    assert snapshot(target) == tree


def test_an_unset_slot_is_left_out() -> None:
    class Sparse:
        __slots__ = ("a", "b")
        a: float
        b: float

    source, target = Sparse(), Sparse()
    source.a = target.a = 1.0
    assert snapshot(source) == {"c": "Sparse", "v": {"a": 1.0}}
    source.a = 3.0
    restore(target, snapshot(source))
    assert target.a == 3.0 and not hasattr(target, "b")


def test_a_value_snapshot_cannot_hold_is_named() -> None:
    source = Loose()
    source.items[0].b = {1, 2}
    with pytest.raises(UnsupportedValue, match=r"items\[0\]\.b: cannot save a value of type set"):
        snapshot(source)
    tree = snapshot(Loose())
    fields(tree, "items", 0)["b"] = [1, 2]
    target = Loose()
    target.items[0].b = (1, 2)
    with pytest.raises(ContextMismatch, match=r"items\[0\]\.b: cannot restore into a tuple"):
        restore(target, tree)


floats = st.integers(0, 2**64 - 1).map(lambda n: struct.unpack("<d", struct.pack("<Q", n))[0])
values = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(2**70), 2**70),
    floats,
    st.text(st.characters(exclude_categories=())),  # lone surrogates too
)


@given(st.lists(values, max_size=8))
def test_any_elementary_value_survives_bit_for_bit(items: list[Any]) -> None:
    source, target = Loose(), Loose()
    # a slot holds the kind of value it always held (a restore checks it)
    source.items, target.items = items, [None if v is None else type(v)() for v in items]
    tree = json.loads(encode_context(Context("S", 0, {}, {}, snapshot(source))).split(b"\n")[1])
    restore(target, tree["globals"])
    assert len(target.items) == len(items)
    for got, want in zip(target.items, items, strict=True):
        assert type(got) is type(want)
        if isinstance(want, float):
            assert bits(got) == bits(want)
        else:
            assert got == want


# ---- the context file


def small_context(signature: str = "4134ED7B", counter: int = 1) -> Context:
    return Context(
        signature=signature,
        saved_ns=1_700_000_000_123_456_789,
        resource={"cycle": counter, "state": "RUN"},
        programs={
            "Main": {"state": "RUN", "time_ns": 5, "values": {"c": "POU_MAIN", "v": {"n": counter}}}
        },
        globals=None,
    )


def test_the_file_is_a_header_line_and_a_canonical_body(tmp_path: Path) -> None:
    path = tmp_path / "context"
    save_context(path, small_context())
    header_line, body = path.read_bytes().split(b"\n")
    header = json.loads(header_line)
    assert header["format"] == CONTEXT_FORMAT and header["version"] == CONTEXT_VERSION
    assert header["body_bytes"] == len(body) and len(header["sha256"]) == 64
    assert json.dumps(json.loads(body), sort_keys=True, separators=(",", ":")).encode() == body
    assert sorted(p.name for p in tmp_path.iterdir()) == ["context"]  # no temp file left
    assert loaded(path, "4134ED7B") == small_context()


def test_missing_file(tmp_path: Path) -> None:
    assert invalid(tmp_path / "context", "4134ED7B") == "no saved context"


def test_a_flipped_byte_fails_the_checksum(tmp_path: Path) -> None:
    path = tmp_path / "context"
    save_context(path, small_context())
    data = bytearray(path.read_bytes())
    data[data.index(b'"cycle":1') + 8] ^= 0x02  # 1 -> 3: still JSON, no longer the same
    path.write_bytes(data)
    assert invalid(path, "4134ED7B").startswith("checksum mismatch")


@pytest.mark.parametrize("keep", [0, 10, -1, -200])
def test_a_truncated_file_is_invalid(tmp_path: Path, keep: int) -> None:
    path = tmp_path / "context"
    save_context(path, small_context())
    data = path.read_bytes()
    path.write_bytes(data[:keep] if keep >= 0 else data[: len(data) + keep])
    assert invalid(path, "4134ED7B").startswith("truncated")


def test_another_configuration_signature_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "context"
    save_context(path, small_context("1234ABCD"))
    assert invalid(path, "9CCC0001") == (
        "signature 1234ABCD is not the loaded configuration's 9CCC0001"
    )


def rewritten(path: Path, **header: Any) -> None:
    """The file with header fields replaced and a body checksum that fits."""
    line, body = path.read_bytes().split(b"\n")
    fields = {**json.loads(line), **header}
    path.write_bytes(json.dumps(fields, sort_keys=True).encode() + b"\n" + body)


@pytest.mark.parametrize(
    ("header", "reason"),
    [
        ({"version": 2}, "format version 2 unknown"),
        ({"version": True}, "format version True unknown"),
        ({"format": "padt-artifact"}, "not a padt context (format 'padt-artifact')"),
        ({"sha256": None}, "malformed header: body_bytes or sha256 missing"),
    ],
)
def test_a_foreign_or_newer_header_is_refused(
    tmp_path: Path, header: dict[str, Any], reason: str
) -> None:
    path = tmp_path / "context"
    save_context(path, small_context())
    rewritten(path, **header)
    assert invalid(path, "4134ED7B") == reason


def test_garbage_never_raises(tmp_path: Path) -> None:
    path = tmp_path / "context"
    for data in (b"\xff\xfe\n\x00", b"[]\n{}", b"x" * 5000, b'{"format": "padt-context"\n'):
        path.write_bytes(data)
        assert isinstance(load_context(path, "4134ED7B"), ContextInvalid)
    assert invalid(tmp_path, "4134ED7B").startswith("cannot read the context")  # a directory


def test_a_body_of_the_wrong_shape_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "context"
    body = b'{"globals":null,"programs":[],"resource":{},"saved_ns":1,"signature":"4134ED7B"}'
    save_context(path, small_context())
    rewritten(path, body_bytes=len(body), sha256=hashlib.sha256(body).hexdigest())
    path.write_bytes(path.read_bytes().split(b"\n")[0] + b"\n" + body)
    assert invalid(path, "4134ED7B") == "malformed body: programs is not an object of objects"


# ---- atomic saving: a crash at any point leaves the previous context valid


def test_a_stray_temp_file_from_a_crash_is_ignored_and_replaced(tmp_path: Path) -> None:
    path = tmp_path / "context"
    save_context(path, small_context(counter=1))
    half = encode_context(small_context(counter=2))
    (tmp_path / "context.tmp").write_bytes(half[: len(half) // 2])  # died while writing
    assert loaded(path, "4134ED7B") == small_context(counter=1)
    save_context(path, small_context(counter=3))
    assert loaded(path, "4134ED7B") == small_context(counter=3)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["context"]


def test_a_failed_rename_keeps_the_previous_context(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "context"
    save_context(path, small_context(counter=1))

    def no_rename(source: Any, target: Any) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("runtime.context.os.replace", no_rename)
    with pytest.raises(OSError, match="No space"):
        save_context(path, small_context(counter=2))
    assert loaded(path, "4134ED7B") == small_context(counter=1)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["context"]


@pytest.mark.parametrize("dies_in", ["fsync", "replace"])
def test_a_process_killed_mid_save_leaves_the_previous_context(
    tmp_path: Path, dies_in: str
) -> None:
    path = tmp_path / "context"
    save_context(path, small_context(counter=1))
    # a real process exit, no cleanup: the temp file is written (fully or not) but not renamed
    script = f"""
import os
from pathlib import Path
from runtime import context
from tests.runtime.test_context import small_context
os.{dies_in} = lambda *args: os._exit(9)
context.save_context(Path({str(path)!r}), small_context(counter=2))
"""
    run = subprocess.run([sys.executable, "-c", script], cwd=REPO, capture_output=True)
    assert run.returncode == 9, run.stderr
    assert (tmp_path / "context.tmp").exists()
    assert loaded(path, "4134ED7B") == small_context(counter=1)
    save_context(path, small_context(counter=3))
    assert loaded(path, "4134ED7B") == small_context(counter=3)


# ---- the periodic save: rows taken on the cycle thread, nodes made when encoded

RECORDS = """
TYPE Sample : STRUCT v : REAL; n : DINT; ok : BOOL; tag : STRING[4]; END_STRUCT; END_TYPE
FUNCTION_BLOCK Hold
VAR_IN_OUT s : Sample; END_VAR
s.n := s.n + 1;
END_FUNCTION_BLOCK
PROGRAM Log
VAR
  a_first : Hold; samples : ARRAY[1..50] OF Sample; z_last : Hold;
  more : ARRAY[1..3] OF Sample; cycles : INT;
END_VAR
a_first(s := samples[7]);
z_last(s := more[2]);
cycles := cycles + 1;
samples[cycles].v := INT_TO_REAL(cycles) / 3.0;
samples[cycles].tag := 'ab';
END_PROGRAM
"""


def test_a_captured_context_encodes_to_the_same_bytes_as_a_snapshot() -> None:
    """`capture` leaves arrays of value-only structs as rows, NaN, infinities and
    elements that a VAR_IN_OUT aliases included; the file is byte for byte the one
    `snapshot` gives, and restores the same values."""
    from runtime.context_snapshot import Records, capture

    artifact = compiled(RECORDS)
    run = Running(artifact, "Log")
    for _ in range(5):
        run.cycle()
    run.program.samples[9].v = math.nan
    run.program.samples[10].v = -math.inf
    run.program.more[1].v = math.inf

    captured = capture(run.program)
    assert any(type(node) is Records for node in fields(captured).values())
    deferred = Context("S", 1, {}, {"Log": {"values": captured}}, capture(run.image.globals))
    same = Context(
        "S", 1, {}, {"Log": {"values": snapshot(run.program)}}, snapshot(run.image.globals)
    )
    assert encode_context(deferred) == encode_context(same)

    # taken means taken: later cycles do not reach the rows
    before = encode_context(deferred)
    run.program.samples[1].n = 12345
    run.cycle()
    assert encode_context(deferred) == before

    # restored from the captured tree directly (a warm start in the same process)
    target = Running(artifact, "Log")
    restore(target.program, captured)
    assert (
        snapshot(target.program) == json.loads(before.split(b"\n")[1])["programs"]["Log"]["values"]
    )
    assert math.isnan(target.program.samples[9].v) and target.program.more[1].v == math.inf
    assert target.program.a_first.s is target.program.samples[6]  # samples[7] in ST
