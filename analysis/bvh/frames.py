"""The MOTION block of a BVH file, parsed in one compiled pass over the bytes.

The scanner converts numbers and checks the frame layout at the same time: every non-blank line
must hold exactly one value per channel, and there must be as many lines as declared. It returns
an error code with the offending line instead of raising, so the message is built in Python.

More well-formed frame lines than the ``Frames:`` count declares are kept, with a warning, when the
caller passes a ``warnings`` list (Blender and PyMO read every frame line whatever the count says;
an exporter that wrote the count before the take ended leaves such files).
"""

from __future__ import annotations

import numba
import numpy as np
import numpy.typing as npt

from analysis.bvh.errors import BVHError

OK, BAD_TOKEN, TOO_MANY_VALUES, TOO_FEW_VALUES, TOO_MANY_FRAMES, TOO_FEW_FRAMES = range(6)
_POW10 = np.array([10.0**k for k in range(23)])


@numba.njit(cache=True, nogil=True)
def _scale(mantissa: float, exponent: int) -> float:
    # Powers of ten up to 1e22 are exact in float64, so one multiply or divide keeps ~1 ulp.
    value = mantissa
    while exponent > 22:
        value *= 1e22
        exponent -= 22
    while exponent < -22:
        value /= 1e22
        exponent += 22
    if exponent >= 0:
        return value * _POW10[exponent]
    return value / _POW10[-exponent]


@numba.njit(cache=True, nogil=True)
def _is_space(c: int) -> bool:
    return c == 32 or c == 9 or c == 13 or c == 11 or c == 12  # noqa: PLR1714 (numba: no set)


@numba.njit(cache=True, nogil=True)
# One compiled loop per number: splitting it into helpers would cost the scanner its speed.
def _parse_number(  # noqa: C901, PLR0912
    data: npt.NDArray[np.uint8], i: int, n: int
) -> tuple[float, int, bool]:
    """Parse one decimal number starting at i; returns (value, next index, ok)."""
    sign = 1.0
    if data[i] == 45 or data[i] == 43:  # '-' '+'
        sign = -1.0 if data[i] == 45 else 1.0
        i += 1
    # The digits gather in an integer (18 of them fit in int64): one integer multiply-add per
    # digit instead of a floating one, and a single rounding when it becomes a float.
    mantissa, exponent, digits, significant = 0, 0, 0, 0
    while i < n and 48 <= data[i] <= 57:
        if significant < 18:
            mantissa = mantissa * 10 + int(data[i] - 48)
            significant += 1 if (mantissa > 0) else 0
        else:
            exponent += 1
        digits += 1
        i += 1
    if i < n and data[i] == 46:  # '.'
        i += 1
        while i < n and 48 <= data[i] <= 57:
            if significant < 18:
                mantissa = mantissa * 10 + int(data[i] - 48)
                significant += 1 if (mantissa > 0) else 0
                exponent -= 1
            digits += 1
            i += 1
    if digits == 0:
        return 0.0, i, False
    if i < n and (data[i] == 101 or data[i] == 69):  # 'e' 'E'
        i += 1
        exp_sign = 1
        if i < n and (data[i] == 45 or data[i] == 43):
            exp_sign = -1 if data[i] == 45 else 1
            i += 1
        exp_digits, exp_value = 0, 0
        while i < n and 48 <= data[i] <= 57:
            if exp_value < 100000:
                exp_value = exp_value * 10 + (data[i] - 48)
            exp_digits += 1
            i += 1
        if exp_digits == 0:
            return 0.0, i, False
        exponent += exp_sign * exp_value
    ok = i >= n or _is_space(data[i]) or data[i] == 10
    return sign * _scale(float(mantissa), exponent), i, ok


@numba.njit(cache=True, nogil=True)
def scan(  # noqa: C901, PLR0911 (one pass over the bytes; each exit is an error code)
    data: npt.NDArray[np.uint8], out: npt.NDArray[np.float64], n_frames: int, n_channels: int
) -> tuple[int, int, int]:
    """Fill out (n_frames × n_channels) from data; returns (code, line offset, frames read)."""
    n = data.shape[0]
    i, line, frame, column = 0, 0, 0, 0
    while i < n:
        c = data[i]
        if c == 10:
            if column != 0:
                if column < n_channels:
                    return TOO_FEW_VALUES, line, frame
                frame += 1
                column = 0
            line += 1
            i += 1
        elif _is_space(c):
            i += 1
        else:
            if column == 0 and frame >= n_frames:
                return TOO_MANY_FRAMES, line, frame
            if column >= n_channels:
                return TOO_MANY_VALUES, line, frame
            value, i, ok = _parse_number(data, i, n)
            if not ok or not np.isfinite(value):
                return BAD_TOKEN, line, frame
            out[frame, column] = value
            column += 1
    if column != 0:
        if column < n_channels:
            return TOO_FEW_VALUES, line, frame
        frame += 1
    if frame < n_frames:
        return TOO_FEW_FRAMES, line, frame
    return OK, line, frame


def describe_bad_token(text_line: str, n_channels: int) -> str:
    for token in text_line.split():
        try:
            value = float(token)
        except ValueError:
            return f"'{token[:40]}' is not a number"
        if not np.isfinite(value):
            return f"'{token[:40]}' is not a finite number (NaN or infinite values are not allowed)"
    return "a value is not a well-formed number"


def _count_frame_lines(data: bytes | memoryview) -> int:
    return sum(1 for line in bytes(data).split(b"\n") if line.strip())


def parse_frames(
    data: bytes | memoryview,
    n_frames: int,
    n_channels: int,
    first_line: int,
    *,
    warnings: list[str] | None = None,
    max_values: int | None = None,
) -> npt.NDArray[np.float64]:
    """Parse the frame lines (bytes after the Frame Time line) into an (F, C) float64 array.

    With ``warnings``, frame lines beyond the declared count are read too (up to ``max_values``
    values) and a warning is appended; without it they are an error.
    """
    buffer = np.frombuffer(data, dtype=np.uint8)
    out = np.empty((n_frames, n_channels), dtype=np.float64)
    code, line_offset, frames_read = scan(buffer, out, n_frames, n_channels)
    if code == TOO_MANY_FRAMES and warnings is not None:
        found = _count_frame_lines(data)
        if max_values is None or found * n_channels <= max_values:
            out = np.empty((found, n_channels), dtype=np.float64)
            code, line_offset, frames_read = scan(buffer, out, found, n_channels)
            if code == OK:
                warnings.append(
                    f"line {first_line - 2}: {n_frames} frames declared but {found} frame lines "
                    f"found; all {found} were read"
                )
    if code == OK:
        return out
    line = first_line + int(line_offset)
    if code == TOO_FEW_FRAMES:
        raise BVHError(f"{n_frames} frames declared but {frames_read} found", line)
    if code == TOO_MANY_FRAMES:
        raise BVHError(f"more frame lines than the {n_frames} declared", line)
    text_line = bytes(data).split(b"\n")[int(line_offset)].decode("utf-8", "replace")
    found = len(text_line.split())
    if code in (TOO_MANY_VALUES, TOO_FEW_VALUES):
        raise BVHError(
            f"frame line has {found} values but the skeleton has {n_channels} channels", line
        )
    raise BVHError(describe_bad_token(text_line, n_channels), line)
