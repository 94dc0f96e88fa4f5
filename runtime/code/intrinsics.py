"""What generated code may call: the runtime's side of the artifact contract.

Generated source runs with exactly these names in its global namespace (plus the classes
of the other POUs). `docs/artifact.md` lists them; changing one is a new artifact version.
"""

from __future__ import annotations

import builtins
import copy
import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from operator import attrgetter
from typing import Any

from runtime.contract.code.names import BUILTINS, INTRINSICS, is_data_attr
from runtime.contract.system_variables import SYSTEM_VARIABLES
from runtime.contract.values import format_time, to_real32

GENERATED_MODULE = "padt_generated"  # `__name__` of generated code: its classes' module
VIEWS_MODULE = "padt_memory"  # the module of the views of a memory image (padt_memory.c)


class ProgramFault(Exception):
    """A run-time error of a user program (puts that program in ERROR)."""


class DivisionByZero(ProgramFault):
    def __init__(self) -> None:
        super().__init__("integer division by zero")


class IndexOutOfRange(ProgramFault):
    def __init__(self, index: int, low: int, high: int) -> None:
        super().__init__(f"array index {index} outside {low}..{high}")


class NullDereference(ProgramFault):
    def __init__(self) -> None:
        super().__init__("dereference of NULL")


class Reference(str):
    """A value of `REF_TO T` (NULL is None): the place it refers to, as the object that
    holds it (`root`: an instance, the globals) and the accessors below it, followed anew
    at every use, so that an assignment that replaces a structure or array below the root
    leaves the reference good. As a string it is the path of that place, which is what
    every reader outside the program (OLT, recordings, `padt sim`) shows; two references
    are equal when they refer to the same place.

    A reference cannot be changed once made (generated code could otherwise write any
    step into one, `r.steps = ...`, and have `get` follow it)."""

    root: Any
    steps: tuple[str | int, ...]

    def __new__(cls, text: str, root: Any, steps: tuple[str | int, ...]) -> Reference:
        made = super().__new__(cls, text)
        object.__setattr__(made, "root", root)
        object.__setattr__(made, "steps", steps)
        return made

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("a reference cannot be changed")

    def get(self) -> Any:
        value = self.root
        for step in self.steps:
            value = value[step] if isinstance(step, int) else getattr(value, step)
        return value

    def set(self, value: Any) -> None:
        target = self.root
        for step in self.steps[:-1]:
            target = target[step] if isinstance(step, int) else getattr(target, step)
        last = self.steps[-1]
        held = target[last] if isinstance(last, int) else getattr(target, last)
        if _is_aggregate(held) and _is_aggregate(value):
            _fill(held, value)  # in place, as a whole store is: an in-out may hold it
        elif isinstance(last, int):
            target[last] = value
        else:
            setattr(target, last, value)

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Reference):  # ST `r1 = r2`: the same place
            return other.root is self.root and other.steps == self.steps
        return str.__eq__(self, other)  # a reader outside the program: the path

    def __ne__(self, other: object) -> bool:
        return not self == other

    __hash__ = str.__hash__

    def __deepcopy__(self, memo: dict[int, Any]) -> Reference:
        return self  # copying a structure copies its references, not what they refer to

    def __copy__(self) -> Reference:
        return self


def reference_maker(roots: dict[int, str]) -> Callable[..., Reference]:
    """`_ref` of generated code: REF(x) as the object holding x (`root`), the accessors
    below it and the ST text below it (`label`, empty for the root itself); `roots` names
    the instances the runtime knows (`Instances`), so that the reference reads as a whole
    path. A label that is already whole (below a dereference: `REF(r^.x)`) is taken as it
    is."""

    def make(root: Any, steps: tuple[str | int, ...], label: str, whole: bool = False) -> Reference:
        check_reference(root, steps)
        prefix = "" if whole else roots.get(id(root), "")
        # an empty label: the root itself (THIS, a reference to the instance)
        return Reference(f"{prefix}.{label}" if prefix and label else prefix or label, root, steps)

    return make


def check_reference(root: Any, steps: tuple[str | int, ...]) -> None:
    """What a reference may be made of: a root that generated code made (an instance of a
    generated class, a list), and steps that are list offsets or variable names. The
    check of the form lets offsets be computed; this makes sure none of them computes to a
    name such as `__globals__`, nor lets `_deref_set` change a class or a module."""
    if not isinstance(root, list) and type(root).__module__ != GENERATED_MODULE:
        raise ProgramFault(f"a reference into a {type(root).__name__}")
    for step in steps:
        if type(step) is not int and not (type(step) is str and is_data_attr(step)):
            raise ProgramFault(f"a reference through {step!r}")


def _deref(reference: Reference | None) -> Any:
    if reference is None:
        raise NullDereference()
    return reference.get()


def _deref_set(reference: Reference | None, value: Any) -> None:
    if reference is None:
        raise NullDereference()
    reference.set(value)


EMERGENCY_STOPS = tuple(v.name for v in SYSTEM_VARIABLES if v.name.startswith("EMERGENCY_STOP"))
# the Emergency Stop switches of a SystemView in one C call: read after every program run
emergency_switches = attrgetter(*EMERGENCY_STOPS)


@dataclass(slots=True)  # slots: the CPU cycle in C writes them (padt_cycle.c)
class SystemView:
    """The system values a program sees; the scheduler sets them before each program cycle.

    Besides `now_ns` (the running program's time), one attribute per system variable of
    `runtime.system_variables.SYSTEM_VARIABLES`, named as there: ST reads `SYS.COLDSTART`
    as `_SYS.COLDSTART`; the writable ones (FORCE_DEACTIVATION, ...) are written by logic."""

    now_ns: int = 0
    # read-only in ST: the runtime sets them
    COLDSTART: bool = False
    WARMSTART: bool = False
    START_CYCLE: bool = False
    CYCLE_TIME_LAST: int = 0  # TIME, ns
    CYCLE_TIME_MIN: int = 0
    CYCLE_TIME_MAX: int = 0
    CYCLE_TIME_MEAN: int = 0
    WATCHDOG_TIME: int = 0
    SYSTEM_TICK: int = 0  # UDINT, ms since the runtime started, wrapping at 2^32
    FORCE_TIME_REMAINING: int = 0
    CONFIGURATION_CRC: int = 0  # DWORD
    DATE_AND_TIME: int = 0  # DT, ns since 1970-01-01
    # writable by logic and I/O
    FORCE_DEACTIVATION: bool = False
    RELOAD_DEACTIVATION: bool = False
    READ_ONLY_IN_RUN: bool = False
    EMERGENCY_STOP_1: bool = False
    EMERGENCY_STOP_2: bool = False
    EMERGENCY_STOP_3: bool = False
    EMERGENCY_STOP_4: bool = False


def _idiv(a: int, b: int) -> int:
    """IEC integer division: truncates toward zero; division by zero is a program error."""
    if b == 0:
        raise DivisionByZero()
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


def _imod(a: int, b: int) -> int:
    if b == 0:
        raise DivisionByZero()
    return a - b * _idiv(a, b)


def _fdiv(a: float, b: float) -> float:
    if b == 0:
        if a == 0 or math.isnan(a):
            return math.nan
        return math.copysign(math.inf, a) * math.copysign(1.0, b)
    return a / b


def _tdiv(a: int, b: float) -> int:
    if b == 0:
        raise DivisionByZero()
    return int(a / b)


def _pow(a: float, b: float) -> float:
    """EXPT: zero to a negative power and an overflow +inf, a negative base to a power that
    is no whole number NaN (Python's power is a complex number there, which a REAL held)."""
    try:
        result = float(a) ** b
    except (ZeroDivisionError, OverflowError):
        return math.inf
    return result if type(result) is float else math.nan


def _ix(index: int, low: int, high: int) -> int:
    """The list offset of an array index, or a program fault outside the bounds."""
    if low <= index <= high:
        return index - low
    raise IndexOutOfRange(index, low, high)


def _setbits(value: int, shift: int, width: int, part: int) -> int:
    """`x.3 := TRUE`, `x.%B1 := 16#FF`: replace `width` bits at `shift` (two's complement
    kept: the result has the sign of the original when the top bit is not touched)."""
    mask = ((1 << width) - 1) << shift
    return (value & ~mask) | ((int(part) << shift) & mask)


def _fill(target: Any, value: Any) -> None:
    """`x := v` of an array or a structure x of an instance, the globals or an element: v's
    values written into x's object (or view), member by member and element by element, so
    that x and every object within keep their identity: a block's in-out may hold x (the
    caller's very variable, as IEC 61131-3 passes an in-out). `value` is of x's type.

    The target is checked as `_deref_set`'s root is: a structure of a generated class (a
    view's class is one too), a list, an image's array; never the runtime's objects the
    code may name (`_SYS`, whose read-only members its checked stores never write)."""
    structure = type(value).__module__ == GENERATED_MODULE  # (an object or a view)
    kind = type(target)
    if not (kind.__module__ == GENERATED_MODULE if structure else kind is list or _in_image(kind)):
        raise ProgramFault(f"a whole store into a {kind.__name__}")
    if structure:
        for name in type(target).__slots__:
            item = getattr(value, name)
            if _is_aggregate(item):
                _fill(getattr(target, name), item)
            else:
                setattr(target, name, item)
        return
    if type(target) is list and not (value and _is_aggregate(value[0])):
        target[:] = value  # elementary values, at once
        return
    for index, item in enumerate(value):  # an image's array, or one of aggregates
        if _is_aggregate(item):
            _fill(target[index], item)
        else:
            target[index] = item


def _in_image(kind: type) -> bool:
    """An array of a memory image (padt_memory.c's `Elements`)."""
    return kind.__module__ == VIEWS_MODULE and kind.__name__ == "Elements"


def _is_aggregate(value: Any) -> bool:
    """An array (a list) or a structure (an object of a generated class, a view), whose
    values go into the target's own; not a number, a text, a reference or an image's array
    (whose store copies its values)."""
    return isinstance(value, list) or type(value).__module__ == GENERATED_MODULE


def _init(target: Any, values: dict[str, Any]) -> Any:
    """Apply a structure initializer `(a := 1, b := 2)` to a fresh object."""
    for name, value in values.items():
        setattr(target, name, value)
    return target


def _round(value: float) -> int:
    """REAL to integer: to the nearest, halves away from zero (as CODESYS does; see
    docs/language.md). The fraction is taken exactly: adding 0.5 before rounding down would
    itself round, taking 0.49999999999999994 to 1 and 2**52 + 1 to 2**52 + 2."""
    if math.isnan(value) or math.isinf(value):
        return 0
    magnitude = abs(value)
    whole = math.floor(magnitude)
    if magnitude - whole >= 0.5:  # exact (Sterbenz): whole <= magnitude < 2 * whole, or 0
        whole += 1
    return whole if value >= 0 else -whole


def _rol(value: int, n: int, bits: int) -> int:
    n %= bits
    return ((value << n) | (value >> (bits - n))) & ((1 << bits) - 1)


def _ror(value: int, n: int, bits: int) -> int:
    n %= bits
    return ((value >> n) | (value << (bits - n))) & ((1 << bits) - 1)


def _mux(k: int, *inputs: Any) -> Any:
    if not 0 <= k < len(inputs):
        raise IndexOutOfRange(k, 0, len(inputs) - 1)
    return inputs[k]


def _bcd_to_int(value: int) -> int:
    """Packed BCD (one decimal digit per nibble) to its number; a nibble above 9 is a
    program fault, as on PLCs that check BCD input."""
    result, factor = 0, 1
    value &= (1 << 64) - 1
    while value:
        digit = value & 0xF
        if digit > 9:
            raise ProgramFault(f"{digit:X} is not a BCD digit")
        result += digit * factor
        factor *= 10
        value >>= 4
    return result


def _int_to_bcd(value: int) -> int:
    if value < 0:
        raise ProgramFault(f"{value} has no BCD form")
    result, shift = 0, 0
    while value:
        value, digit = divmod(value, 10)
        result |= digit << shift
        shift += 4
    return result


def _str_to_int(text: str) -> int:
    cleaned = text.strip().replace("_", "")
    try:
        if "#" in cleaned:
            base, _, digits = cleaned.partition("#")
            return int(digits, int(base))
        return int(float(cleaned)) if "." in cleaned or "e" in cleaned.lower() else int(cleaned)
    except ValueError:
        return 0


def _str_to_real(text: str) -> float:
    try:
        return float(text.strip().replace("_", ""))
    except ValueError:
        return 0.0


def _str_to_bool(text: str) -> bool:
    return text.strip().upper() in ("TRUE", "1")


def _real_to_str(value: float) -> str:
    return repr(value)


def _date_to_str(ns: int, kind: str) -> str:
    """DATE/TOD/DT to STRING: `D#2024-01-15`, `TOD#12:30:05`, `DT#2024-01-15-12:30:05`
    (L-forms with their own prefixes)."""
    import datetime

    prefix = {"DATE": "D#", "LDATE": "LDATE#", "TOD": "TOD#", "LTOD": "LTOD#", "DT": "DT#"}.get(
        kind, f"{kind}#"
    )
    moment = datetime.datetime(1970, 1, 1) + datetime.timedelta(microseconds=ns // 1000)
    fraction = ns % 1_000_000_000
    clock = moment.strftime("%H:%M:%S")
    if fraction:
        clock += f".{fraction:09d}".rstrip("0")
    if kind in ("DATE", "LDATE"):
        return f"{prefix}{moment.strftime('%Y-%m-%d')}"
    if kind in ("TOD", "LTOD"):
        return f"{prefix}{clock}"
    return f"{prefix}{moment.strftime('%Y-%m-%d')}-{clock}"


def _str_to_time(text: str) -> int:
    """STRING_TO_TIME: an IEC duration literal (`T#1s`, `LTIME#5ns`) to nanoseconds."""
    import re

    units = {"d": 86_400_000_000_000, "h": 3_600_000_000_000, "m": 60_000_000_000,
             "s": 1_000_000_000, "ms": 1_000_000, "us": 1_000, "ns": 1}  # fmt: skip
    body = text.strip().partition("#")[2] or text.strip()
    negative = body.startswith("-")
    total = 0
    for number, unit in re.findall(r"([0-9][0-9_]*(?:\.[0-9_]+)?)(d|h|ms|m|s|us|ns)", body.lower()):
        total += round(float(number.replace("_", "")) * units[unit])
    return -total if negative else total


# String functions: positions count from 1, as in IEC 61131-3. Out-of-range lengths are
# clamped; an invalid position leaves the input unchanged (MID gives ''), as CODESYS does.
def _left(text: str, n: int) -> str:
    return text[: max(n, 0)]


def _right(text: str, n: int) -> str:
    return text[len(text) - n :] if n > 0 else ""


def _mid(text: str, n: int, p: int) -> str:
    if not 1 <= p <= len(text):
        return ""
    return text[p - 1 : p - 1 + max(n, 0)]


def _insert(text: str, other: str, p: int) -> str:
    if not 0 <= p <= len(text):
        return text
    return text[:p] + other + text[p:]


def _delete(text: str, n: int, p: int) -> str:
    if not 1 <= p <= len(text):
        return text
    return text[: p - 1] + text[p - 1 + max(n, 0) :]


def _replace(text: str, other: str, n: int, p: int) -> str:
    if not 1 <= p <= len(text):
        return text
    return text[: p - 1] + other + text[p - 1 + max(n, 0) :]


def _find(text: str, other: str) -> int:
    return text.find(other) + 1


def _safe_math(function: Callable[[float], float], value: float) -> float:
    try:
        return function(value)
    except (ValueError, OverflowError):
        return math.nan


def to_bytes(text: str) -> bytes:
    """The bytes of a STRING value (one character per byte); characters beyond a byte can
    only come from a WSTRING and are written as UTF-8."""
    try:
        return text.encode("latin-1")
    except UnicodeEncodeError:
        return b"".join(
            ch.encode("latin-1") if ord(ch) < 256 else ch.encode("utf-8", "replace") for ch in text
        )


def _w2s(text: str) -> str:
    """WSTRING (UTF-16 code units) to STRING (UTF-8 bytes); unpaired surrogates become
    U+FFFD."""
    units = b"".join(ord(ch).to_bytes(2, "little") for ch in text if ord(ch) < 0x10000)
    return units.decode("utf-16-le", "replace").encode("utf-8").decode("latin-1")


def _s2w(text: str) -> str:
    """STRING (UTF-8 bytes) to WSTRING (UTF-16 code units)."""
    decoded = to_bytes(text).decode("utf-8", "replace").encode("utf-16-le", "surrogatepass")
    return "".join(
        chr(int.from_bytes(decoded[i : i + 2], "little")) for i in range(0, len(decoded), 2)
    )


class NotUnderTest(RuntimeError):
    """A test function called outside `padt test` (no configuration of a test file is ever
    downloaded: only a crafted artifact gets here)."""


def _no_test_runner(*args: Any) -> Any:
    raise NotUnderTest("a test function (docs/testing.md) runs only under padt test")


def _stdout_printf(fmt: str, *args: Any) -> int:
    from runtime.code.printf import format_printf

    data = to_bytes(format_printf(fmt, args))
    sys.stdout.flush()
    sys.stdout.buffer.write(data)
    sys.stdout.buffer.flush()
    return len(data)


class _SfcStep:
    """An SFC step: X (active), T (time active); `since` is when it became active."""

    __slots__ = ("T", "X", "since")

    def __init__(self) -> None:
        self.X = False
        self.T = 0
        self.since: int | None = None


def _step_time(step: _SfcStep, now: int) -> int:
    if step.since is None:  # the first cycle in which the step is active
        step.since = now
    return now - step.since


def _step_enter(step: _SfcStep) -> None:
    step.X = True
    step.T = 0
    step.since = None


class _ActionControl:
    """The action control block of IEC 61131-3 for one action. Inputs are the OR of the
    `.X` flags of the steps that name the action with each qualifier; Q says the action is
    active; A that its body runs this cycle: while Q, once more after Q falls (the final
    scan), and once for each pulse (P on activation, P1 on activation, P0 on
    deactivation; pulses have no final scan). Timers work like TON on program time."""

    __slots__ = (
        "A",
        "Q",
        "d_since",
        "ds_since",
        "ds_stored",
        "held",
        "l_since",
        "p0_prev",
        "p1_prev",
        "p_prev",
        "sd_set",
        "sd_since",
        "sl_set",
        "sl_since",
        "stored",
    )  # fmt: skip

    def __init__(self) -> None:
        self.A = self.Q = self.held = False
        self.stored = self.sd_set = self.ds_stored = self.sl_set = False
        self.p_prev = self.p1_prev = self.p0_prev = False
        self.l_since: int | None = None
        self.d_since: int | None = None
        self.sd_since: int | None = None
        self.ds_since: int | None = None
        self.sl_since: int | None = None

    @staticmethod
    def _elapsed(on: bool, since: int | None, now: int) -> tuple[int | None, int]:
        if not on:
            return None, -1
        start = now if since is None else since
        return start, now - start

    def update(
        self, now: int, *, N: bool = False, R: bool = False, S: bool = False,
        P: bool = False, P0: bool = False, P1: bool = False, L: bool = False,
        D: bool = False, SD: bool = False, DS: bool = False, SL: bool = False,
        TL: int = 0, TD: int = 0, TSD: int = 0, TDS: int = 0, TSL: int = 0,
    ) -> None:  # fmt: skip
        self.stored = not R and (S or self.stored)
        self.l_since, l_elapsed = self._elapsed(L, self.l_since, now)
        self.d_since, d_elapsed = self._elapsed(D, self.d_since, now)
        self.sd_set = not R and (SD or self.sd_set)
        self.sd_since, sd_elapsed = self._elapsed(self.sd_set, self.sd_since, now)
        self.ds_since, ds_elapsed = self._elapsed(DS, self.ds_since, now)
        self.ds_stored = not R and ((ds_elapsed >= TDS >= 0 and DS) or self.ds_stored)
        self.sl_set = not R and (SL or self.sl_set)
        self.sl_since, sl_elapsed = self._elapsed(self.sl_set, self.sl_since, now)
        pulse = (P and not self.p_prev) or (P1 and not self.p1_prev) or (self.p0_prev and not P0)
        self.p_prev, self.p1_prev, self.p0_prev = P, P1, P0
        active = not R and (
            N
            or (L and l_elapsed < TL)
            or (D and d_elapsed >= TD)
            or self.stored
            or (self.sd_set and sd_elapsed >= TSD)
            or self.ds_stored
            or (self.sl_set and sl_elapsed < TSL)
        )
        # Q includes a pulse (a BOOL action is TRUE for that cycle); the final scan follows
        # only the loss of held activity, so a pulse runs its action exactly once
        final_scan = self.held and not active
        self.held = active
        self.Q = active or pulse
        self.A = active or pulse or final_scan


class Namespace:
    """A plain attribute holder (`_P`: program instances by class name)."""


def namespace(system: SystemView, printf: Callable[..., int] = _stdout_printf) -> dict[str, Any]:
    """A fresh global namespace for one resource's generated code: the names of
    `runtime.contract.code.names` (INTRINSICS, BUILTINS), which the check of generated
    code holds it to."""
    reference_roots: dict[int, str] = {}  # filled by `Instances`: the paths of instances
    names = {
        # only what generated classes need: user code cannot reach open(), import, ...
        "__builtins__": {
            "__build_class__": builtins.__build_class__,
            **{name: getattr(builtins, name) for name in sorted(BUILTINS)},
        },
        "__name__": GENERATED_MODULE,
        "_SYS": system,
        "_G": None,  # the globals, once the code image has made them
        # loop passes are not metered (None), or a SliceMeter's tick while a sliced program runs
        "_tick": None,
        "_idiv": _idiv,
        "_imod": _imod,
        "_fdiv": _fdiv,
        "_tdiv": _tdiv,
        "_pow": _pow,
        "_f32": to_real32,
        "_ix": _ix,
        "_reference_roots": reference_roots,
        "_ref": reference_maker(reference_roots),
        "_deref": _deref,
        "_deref_set": _deref_set,
        "_setbits": _setbits,
        "_copy": copy.deepcopy,
        "_fill": _fill,
        "_init": _init,
        "_round": _round,
        "_rol": _rol,
        "_ror": _ror,
        "_mux": _mux,
        "_str_to_int": _str_to_int,
        "_str_to_real": _str_to_real,
        "_str_to_bool": _str_to_bool,
        "_real_to_str": _real_to_str,
        "_time_to_str": format_time,
        "_date_to_str": _date_to_str,
        "_str_to_time": _str_to_time,
        "_w2s": _w2s,
        "_bcd_to_int": _bcd_to_int,
        "_int_to_bcd": _int_to_bcd,
        "_ord": lambda ch: ord(ch[0]) if ch else 0,
        "_s2w": _s2w,
        "_left": _left,
        "_right": _right,
        "_mid": _mid,
        "_insert": _insert,
        "_delete": _delete,
        "_replace": _replace,
        "_find": _find,
        "_math": math,
        "_safe_math": _safe_math,
        "_printf": printf,
        "_P": Namespace(),
        "_SfcStep": _SfcStep,
        "_ActionControl": _ActionControl,
        "_step_time": _step_time,
        "_step_enter": _step_enter,
        "_test": _no_test_runner,  # `CodeImage.run_tests_with` gives it a test runner
    }
    assert names.keys() - {"__builtins__", "__name__"} == INTRINSICS, "see contract/code/names.py"
    return names
