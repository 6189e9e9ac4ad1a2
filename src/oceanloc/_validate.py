"""Argument checks at the public entry points: shape, finiteness, magnitude and size, in one message form.

Public functions take arrays from notebooks and other programs. Whatever they are given, they either
return finite results or raise :class:`~oceanloc.errors.ArgumentError` naming the argument, what is wrong
with it and the allowed range, e.g. ``sigma_m: 1e-300 is outside the allowed range [1e-06, 1e+06] m``.
NaN, infinities, numbers beyond any physical geometry (``1e300``), empty or mis-shaped arrays and sizes
that would allocate gigabytes are all refused at the entry, before any arithmetic can overflow into a
``LinAlgError``, a ``MemoryError`` or a silent NaN.

The bounds are physical, stated once here:

* positions and ranges: at most :data:`MAX_LENGTH_M` in magnitude (ECEF coordinates are 6.4e6 m);
* standard deviations of lengths: within :data:`SIGMA_RANGE_M`;
* covariance eigenvalues (any unit, squared): at most :data:`MAX_VARIANCE`; information eigenvalues at
  most :data:`MAX_INFORMATION`;
* memory: no array an entry point allocates beyond :data:`MAX_BYTES`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from oceanloc._typing import ArrayLike, FloatArray
from oceanloc.errors import ArgumentError

MAX_LENGTH_M = 1e8
"""Largest position coordinate or range accepted, metres (beyond the Earth by a factor of 15)."""
SIGMA_RANGE_M = (1e-6, 1e6)
"""Smallest and largest standard deviation of a length, metres (a micrometre to a thousand km)."""
MAX_VARIANCE = 1e12
"""Largest covariance eigenvalue accepted (a sigma of 1e6 in the state's units)."""
MAX_INFORMATION = 1e18
"""Largest information eigenvalue accepted (a sigma of 1e-9 in the state's units)."""
MAX_BYTES = 2 << 30
"""Largest working array an entry point may allocate (2 GiB)."""


def _shape_text(shape: Sequence[int | None]) -> str:
    text = ", ".join("n" if s is None else str(s) for s in shape)
    return f"({text},)" if len(shape) == 1 else f"({text})"


def float_array(
    name: str,
    value: ArrayLike,
    *,
    shape: Sequence[int | None] | None = None,
    min_ndim: int | None = None,
    last: Sequence[int] | None = None,
    allow_empty: bool = False,
    allow_nan: bool = False,
    max_abs: float | None = None,
    unit: str = "",
) -> FloatArray:
    """``value`` as a float array, checked.

    Parameters
    ----------
    name : str
        The argument's name, as the caller knows it.
    shape : sequence of int or None, optional
        The exact shape, ``None`` for a free axis.
    min_ndim : int, optional
        At least this many axes (with ``last``: leading batch axes are free).
    last : sequence of int, optional
        The trailing axes' lengths, e.g. ``(2, 2)`` for a stack of 2-by-2 matrices.
    allow_empty : bool
        Accept an array with no elements.
    allow_nan : bool
        Accept NaN (a missing value where the caller documents that); infinities are refused always.
    max_abs : float, optional
        Largest magnitude of a finite element.
    unit : str
        Printed after the bound.

    Raises
    ------
    ArgumentError
    """
    try:
        x = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ArgumentError(f"{name}: not an array of numbers ({exc})") from None
    if shape is not None and (
        x.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, x.shape, strict=True))
    ):
        raise ArgumentError(f"{name}: shape {x.shape}, expected {_shape_text(shape)}")
    if last is not None:
        k = len(last)
        if x.ndim < max(k, min_ndim or 0) or tuple(x.shape[x.ndim - k :]) != tuple(last):
            raise ArgumentError(f"{name}: shape {x.shape}, expected (..., {', '.join(map(str, last))})")
    elif min_ndim is not None and x.ndim < min_ndim:
        raise ArgumentError(f"{name}: {x.ndim} axes, expected at least {min_ndim}")
    if x.size == 0 and not allow_empty:
        raise ArgumentError(f"{name}: empty (shape {x.shape}); at least one value is needed")
    bad = np.isinf(x) if allow_nan else ~np.isfinite(x)
    if bad.any():
        at = tuple(int(i) for i in np.argwhere(bad)[0])
        what = "infinite" if allow_nan else "NaN or infinite"
        raise ArgumentError(f"{name}: {what} value {x[at]} at index {at}")
    if max_abs is not None and x.size:
        big = np.abs(np.nan_to_num(x)) > max_abs
        if big.any():
            at = tuple(int(i) for i in np.argwhere(big)[0])
            raise ArgumentError(
                f"{name}: {x[at]:.6g} at index {at} is beyond the allowed magnitude {max_abs:g}{_u(unit)}"
            )
    return x


def _u(unit: str) -> str:
    return f" {unit}" if unit else ""


def number(
    name: str,
    value: object,
    *,
    lo: float | None = None,
    hi: float | None = None,
    lo_open: bool = False,
    unit: str = "",
) -> float:
    """A finite real number within ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``)."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise ArgumentError(f"{name}: expected a number, got {type(value).__name__} {value!r}")
    v = float(value)
    below = lo is not None and (v <= lo if lo_open else v < lo)
    if not np.isfinite(v) or below or (hi is not None and v > hi):
        left = "(" if lo_open else "["
        lo_text = "-inf" if lo is None else f"{lo:g}"
        hi_text = "inf" if hi is None else f"{hi:g}"
        raise ArgumentError(
            f"{name}: {v:g} is outside the allowed range {left}{lo_text}, {hi_text}]{_u(unit)}"
        )
    return v


def integer(name: str, value: object, *, lo: int, hi: int) -> int:
    """An integer within ``[lo, hi]`` (a bool is not an integer here)."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise ArgumentError(f"{name}: expected an integer, got {type(value).__name__} {value!r}")
    if not lo <= int(value) <= hi:
        raise ArgumentError(f"{name}: {int(value)} is outside the allowed range [{lo}, {hi}]")
    return int(value)


def sigmas(
    name: str, value: ArrayLike, *, bounds: tuple[float, float] = SIGMA_RANGE_M, unit: str = "m"
) -> FloatArray:
    """Standard deviations: finite, within ``bounds`` (a sigma of 1e-300 or 1e300 breaks every solver)."""
    x = float_array(name, value, allow_empty=True, unit=unit)
    bad = (x < bounds[0]) | (x > bounds[1])
    if bad.any():
        at = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ArgumentError(
            f"{name}: {x[at]:g} is outside the allowed range [{bounds[0]:g}, {bounds[1]:g}]{_u(unit)}"
        )
    return x


def covariances(
    name: str,
    value: ArrayLike,
    *,
    dim: int | None = None,
    max_variance: float = MAX_VARIANCE,
    allow_empty: bool = False,
    unit: str = "",
) -> FloatArray:
    """A stack of covariance matrices ``(..., d, d)``: finite, symmetric, positive semi-definite (to
    rounding) and with no eigenvalue above ``max_variance``.

    Positive definiteness, where a caller needs it (an inverse), is the caller's check: it knows what a
    singular matrix means there.
    """
    bound = max_variance if np.isfinite(max_variance) else None
    x = float_array(name, value, min_ndim=2, max_abs=bound, allow_empty=allow_empty, unit=unit)
    d = x.shape[-1]
    if x.shape[-2] != d or (dim is not None and d != dim):
        want = f"(..., {dim}, {dim})" if dim is not None else "(..., d, d)"
        raise ArgumentError(f"{name}: shape {x.shape}, expected {want}")
    scale = np.max(np.abs(x), axis=(-1, -2), keepdims=True)
    asym = np.abs(x - np.swapaxes(x, -1, -2)) > 1e-9 * np.maximum(scale, 1e-300)
    if asym.any():
        at = tuple(int(i) for i in np.argwhere(asym)[0][:-2])
        raise ArgumentError(f"{name}: matrix {at or ''} is not symmetric".replace("  ", " "))
    w = np.linalg.eigvalsh(0.5 * (x + np.swapaxes(x, -1, -2)))
    top = w[..., -1]
    if np.any(~(top <= max_variance)):
        at = tuple(int(i) for i in np.argwhere(~(top <= max_variance))[0]) if top.ndim else ()
        raise ArgumentError(
            f"{name}: eigenvalue {np.max(top):.3g} of matrix {at or ''} is beyond the allowed "
            f"{max_variance:g}{_u(unit)} (a sigma of {np.sqrt(max_variance):g})".replace("  ", " ")
        )
    low = w[..., 0] < -1e-9 * np.maximum(np.abs(top), 1e-300)
    if low.any():
        raise ArgumentError(f"{name}: not positive semi-definite (eigenvalue {np.min(w[..., 0]):.3g})")
    return x


def memory(name: str, n_bytes: float, *, what: str) -> None:
    """Refuse a size whose working arrays would exceed :data:`MAX_BYTES`."""
    if n_bytes > MAX_BYTES:
        raise ArgumentError(
            f"{name}: {what} would need {n_bytes / 2**30:.3g} GiB of working memory; the limit is "
            f"{MAX_BYTES / 2**30:g} GiB: ask for less"
        )
