"""A C-style `printf` for ST test programs (a non-standard helper, not IEC 61131-3).

Test programs such as the rusty-lit corpus print with the C library's `printf`, declared as
an external variadic function. This module reproduces what glibc on x86-64 Linux prints, so
that their expected output can be checked without a C toolchain.

The caller has already decoded the ST string escapes (`$N`, `$T`, ...) of the format, and
passes the arguments as Python values: `int` for every ST integer type, `float` for REAL and
LREAL, `bool` for BOOL (printed as 0/1) and `str` for STRING.

Supported: `%d %i %u %x %X %o %f %F %e %E %g %G %s %c %%`, the flags `- + space 0 #`, a
width, a precision, `*` for either (taken from the arguments, as in C), and the length
modifiers `hh h l ll` (also `j z t L`, all 64 bits on x86-64). Anything else after a `%` is
printed literally, and a conversion whose argument is missing prints nothing. The function
never raises.

Integer widths. C knows the size of each argument; a Python `int` does not carry it, so the
size is inferred from the length modifier and the value:

* `hh` and `h` keep the low 8 and 16 bits, signed for `%d`/`%i`, unsigned for the others.
* `l`, `ll` (and `j z t L`) use 64 bits: `%lld` of ULINT 2**64 - 1 prints -1, as in C.
* Without a modifier C reads a 32-bit `int`. A value that fits in 32 bits, that is lies in
  [-2**31, 2**32), is reinterpreted in 32 bits: `%u` of -1 prints 4294967295 and `%d` of
  DWORD 16#FFFF0000 prints -65536 (the corpus test `enums/typed_enum_various_integer_types`
  relies on this). A value outside that range can only come from a 64-bit type (LINT,
  ULINT, LWORD), and there C would print just the low 32 bits; printing it in 64 bits
  instead is this module's main departure from C, because a test that forgets the `ll`
  most likely wants to see the whole number.

Other choices where C leaves the behaviour undefined or the types differ:

* `%f` and friends accept an `int` (converted to float); `%d` and friends accept a `float`
  (truncated toward zero; NaN and infinity print as under `%f`). Any other mismatch (a
  string under `%d`) prints the argument as `%s` would, so that the mistake shows.
* NaN and infinity print as `nan`/`inf` (upper case for `%F %E %G`), with `-nan` for a NaN
  whose sign bit is set, and are padded with spaces even under the `0` flag, as glibc does.
* `%s` counts width and precision in UTF-8 bytes, as C does on UTF-8 text. Where the
  precision cuts a character, the stump prints as U+FFFD, which is what a reader decoding
  C's output would see. Non-string arguments print as `str(value)`.
* `%c` prints the character with the given code point; a code point outside Unicode keeps
  its low 8 bits (C's conversion to `unsigned char`), and a surrogate prints as U+FFFD so
  that the output stays encodable. A string argument prints its first character; an empty
  string stands for CHAR 0.
* Widths and precisions are capped at 10,000: C would happily print a billion spaces, which
  here would only exhaust memory.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["format_printf"]

_MAX_FIELD = 10_000
_FLAG_CHARS = "-+ #0"
_INT_CONVERSIONS = "diuxXo"
_FLOAT_CONVERSIONS = "fFeEgG"
_CONVERSIONS = _INT_CONVERSIONS + _FLOAT_CONVERSIONS + "sc%"
# Longest first, so that "hh" is not read as "h" followed by a conversion "h".
_LENGTHS = ("hh", "h", "ll", "l", "j", "z", "t", "L")
_LENGTH_BITS = {"hh": 8, "h": 16, "ll": 64, "l": 64, "j": 64, "z": 64, "t": 64, "L": 64}


@dataclass(frozen=True)
class _Spec:
    flags: str
    width: int | None
    precision: int | None
    length: str
    conversion: str


class _Arguments:
    """The argument list, consumed left to right as C's va_arg would."""

    def __init__(self, values: Sequence[object]) -> None:
        self._values = values
        self._next = 0

    def take(self) -> tuple[bool, object]:
        if self._next >= len(self._values):
            return False, None
        value = self._values[self._next]
        self._next += 1
        # BOOL travels as an int in C; doing it here spares every conversion the case.
        if isinstance(value, bool):
            return True, int(value)
        return True, value


def format_printf(fmt: str, args: Sequence[object]) -> str:
    """Format `args` by the C format string `fmt`, as glibc's printf would print them."""
    out: list[str] = []
    arguments = _Arguments(args)
    pos = 0
    length = len(fmt)
    while pos < length:
        percent = fmt.find("%", pos)
        if percent < 0:
            out.append(fmt[pos:])
            break
        out.append(fmt[pos:percent])
        pos = _convert(fmt, percent, arguments, out)
    return "".join(out)


def _convert(fmt: str, start: int, arguments: _Arguments, out: list[str]) -> int:
    """Handle the conversion starting at `fmt[start] == '%'`; return where text resumes."""
    pos = start + 1
    end = len(fmt)
    flags_start = pos
    while pos < end and fmt[pos] in _FLAG_CHARS:
        pos += 1
    flags = fmt[flags_start:pos]

    width_star = False
    width_digits = ""
    if pos < end and fmt[pos] == "*":
        width_star = True
        pos += 1
    else:
        digits_start = pos
        while pos < end and fmt[pos].isascii() and fmt[pos].isdigit():
            pos += 1
        width_digits = fmt[digits_start:pos]

    precision_star = False
    precision_digits: str | None = None
    if pos < end and fmt[pos] == ".":
        pos += 1
        if pos < end and fmt[pos] == "*":
            precision_star = True
            pos += 1
        else:
            digits_start = pos
            while pos < end and fmt[pos].isascii() and fmt[pos].isdigit():
                pos += 1
            precision_digits = fmt[digits_start:pos]

    length_modifier = ""
    for candidate in _LENGTHS:
        if fmt.startswith(candidate, pos):
            length_modifier = candidate
            pos += len(candidate)
            break

    if pos >= end or fmt[pos] not in _CONVERSIONS:
        # Not a conversion C knows: show it as written, and leave the arguments alone so
        # that the following conversions still get theirs.
        stop = min(pos + 1, end)
        out.append(fmt[start:stop])
        return stop
    conversion = fmt[pos]
    pos += 1

    if conversion == "%":
        out.append("%")
        return pos

    width: int | None = _parse_count(width_digits) if width_digits else None
    if width_star:
        present, value = arguments.take()
        star = _as_int(value) if present else None
        if star is None:
            return pos
        if star < 0:
            # C: a negative `*` width is a `-` flag plus the positive width.
            flags += "-"
            star = -star
        width = star
    precision: int | None = None
    if precision_digits is not None:
        precision = _parse_count(precision_digits)
    if precision_star:
        present, value = arguments.take()
        star = _as_int(value) if present else None
        if star is None:
            return pos
        # C: a negative `*` precision is taken as if the precision were omitted.
        precision = star if star >= 0 else None

    present, value = arguments.take()
    if not present:
        return pos
    spec = _Spec(
        flags=flags,
        width=None if width is None else min(width, _MAX_FIELD),
        precision=None if precision is None else min(precision, _MAX_FIELD),
        length=length_modifier,
        conversion=conversion,
    )
    out.append(_format_value(spec, value))
    return pos


def _parse_count(digits: str) -> int:
    """A width or precision written in the format, capped (see the module docstring)."""
    significant = digits.lstrip("0")
    # Checking the length first also keeps int() below Python's limit on digit strings.
    if len(significant) > len(str(_MAX_FIELD)):
        return _MAX_FIELD
    return min(int(significant or "0"), _MAX_FIELD)


def _format_value(spec: _Spec, value: object) -> str:
    conversion = spec.conversion
    if conversion in _INT_CONVERSIONS:
        number = _as_int(value)
        if number is None:
            if isinstance(value, float):
                return _format_nonfinite(spec, value)
            return _format_string(spec, value)
        return _format_int(spec, number)
    if conversion in _FLOAT_CONVERSIONS:
        real = _as_float(value)
        if real is None:
            return _format_string(spec, value)
        return _format_float(spec, real)
    if conversion == "c":
        return _format_char(spec, value)
    return _format_string(spec, value)


def _as_int(value: object) -> int | None:
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        return int(value) if math.isfinite(value) else None
    return None


def _as_float(value: object) -> float | None:
    if isinstance(value, float):
        return value
    if isinstance(value, int):
        try:
            return float(value)
        except OverflowError:
            # Only a Python int beyond any ST type gets here; C would have no such value.
            return math.inf if value > 0 else -math.inf
    return None


def _reinterpret(spec: _Spec, number: int) -> int:
    """The value C would print for `number` under `spec`'s length modifier (see module doc)."""
    signed = spec.conversion in "di"
    bits = _LENGTH_BITS.get(spec.length)
    if bits is None:
        bits = 32 if -(1 << 31) <= number < (1 << 32) else 64
    unsigned = number & ((1 << bits) - 1)
    if signed and unsigned >= 1 << (bits - 1):
        return unsigned - (1 << bits)
    return unsigned


def _format_int(spec: _Spec, number: int) -> str:
    value = _reinterpret(spec, number)
    conversion = spec.conversion
    flags = spec.flags
    sign = ""
    if conversion in "di":
        if value < 0:
            sign = "-"
        elif "+" in flags:
            sign = "+"
        elif " " in flags:
            sign = " "
    magnitude = abs(value)
    if conversion == "x":
        digits = format(magnitude, "x")
    elif conversion == "X":
        digits = format(magnitude, "X")
    elif conversion == "o":
        digits = format(magnitude, "o")
    else:
        digits = str(magnitude)

    if spec.precision is not None:
        # C prints no digits at all for a zero value with a zero precision.
        digits = "" if spec.precision == 0 and magnitude == 0 else digits.zfill(spec.precision)
    prefix = sign
    if "#" in flags:
        if conversion in "xX" and magnitude != 0:
            prefix += "0" + conversion
        elif conversion == "o" and not digits.startswith("0"):
            digits = "0" + digits

    # The 0 flag is ignored under `-` and when a precision is given (C 7.21.6.1).
    zero_pad = "0" in flags and "-" not in flags and spec.precision is None
    return _justify(prefix, digits, spec, zero_pad)


def _format_float(spec: _Spec, real: float) -> str:
    if not math.isfinite(real):
        return _format_nonfinite(spec, real)
    flags = spec.flags
    precision = 6 if spec.precision is None else spec.precision
    # Python's printf-style float formatting is C's for finite values (both round the exact
    # binary value correctly), so it does the digits; width stays ours for the cap.
    python_flags = "".join(flag for flag in "+ #" if flag in flags)
    body = f"%{python_flags}.{precision}{spec.conversion}" % real
    sign = ""
    if body[:1] in "+- ":
        sign, body = body[:1], body[1:]
    zero_pad = "0" in flags and "-" not in flags
    return _justify(sign, body, spec, zero_pad)


def _format_nonfinite(spec: _Spec, real: float) -> str:
    text = "nan" if math.isnan(real) else "inf"
    if spec.conversion in "FEG":
        text = text.upper()
    if math.copysign(1.0, real) < 0:
        sign = "-"
    elif "+" in spec.flags:
        sign = "+"
    elif " " in spec.flags:
        sign = " "
    else:
        sign = ""
    # glibc pads inf and nan with spaces even under the 0 flag.
    return _justify(sign, text, spec, zero_pad=False)


def _justify(prefix: str, digits: str, spec: _Spec, zero_pad: bool) -> str:
    body_length = len(prefix) + len(digits)
    width = spec.width or 0
    if body_length >= width:
        return prefix + digits
    fill = width - body_length
    if "-" in spec.flags:
        return prefix + digits + " " * fill
    if zero_pad:
        return prefix + "0" * fill + digits
    return " " * fill + prefix + digits


def _format_char(spec: _Spec, value: object) -> str:
    if isinstance(value, str):
        char = value[:1] or "\0"
    else:
        code = _as_int(value)
        if code is None:
            return _format_string(spec, value)
        if not 0 <= code <= 0x10FFFF:
            code &= 0xFF
        char = "\ufffd" if 0xD800 <= code <= 0xDFFF else chr(code)
    # C writes one byte for %c, so the field is one wide whatever the character is.
    return _pad_text(char, 1, spec)


def _format_string(spec: _Spec, value: object) -> str:
    text = value if isinstance(value, str) else _safe_str(value)
    # surrogatepass: a lone surrogate counts as the three bytes C would see, and no error.
    raw = text.encode("utf-8", "surrogatepass")
    if spec.precision is not None and len(raw) > spec.precision:
        # C cuts after `precision` bytes even inside a character; a UTF-8 reader then sees
        # U+FFFD for the stump, and so does the caller of this function.
        raw = raw[: spec.precision]
        text = raw.decode("utf-8", "replace")
    return _pad_text(text, len(raw), spec)


def _pad_text(text: str, size: int, spec: _Spec) -> str:
    width = spec.width or 0
    if size >= width:
        return text
    fill = " " * (width - size)
    return text + fill if "-" in spec.flags else fill + text


def _safe_str(value: object) -> str:
    try:
        return str(value)
    except Exception:
        # A test helper must not take the program down over an argument that cannot print.
        return f"<{type(value).__name__}>"
