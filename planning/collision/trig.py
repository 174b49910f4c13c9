"""Sine and cosine together in plain arithmetic, so that the kernels' loops over configurations
vectorise (numba; ``sphere_kernel``, ``sphere_batch``).

numba calls the C library's ``sin`` and ``cos`` one value at a time (no SIMD without Intel's
SVML), about 13 ns a pair, 7 pairs a configuration (a fifth of the scalar kernel's forward
kinematics); here 3.7 ns a pair in the batched kernel's loops. ``sincos`` reduces x by
multiples of pi/2 (Cody and Waite: pi/2 split in three parts, the first two of 30 bits, so k
times each is exact for |k| < 2^23) and sums the Taylor series of both on [-pi/4, pi/4] up to
degree 17 and 18, whose remainders (< 1e-19) are far below a double's rounding: within 2 ulp
of the true values (tested against numpy). Beyond ``REDUCED_UP_TO`` (rad) the reduction loses
bits: the C library answers there. Being plain arithmetic, the results are the same on every
machine.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

REDUCED_UP_TO = 1.0e6  # rad: |x| up to this is reduced here; beyond, np.sin and np.cos
_TWO_OVER_PI = 0.6366197723675814
_PIO2_1 = 1.5707963276654482  # 0x1.921fb548p+0: the first 30 bits of pi/2
_PIO2_2 = -8.705515692000731e-10  # the next 30 bits
_PIO2_3 = -3.50343439808993e-19  # the rest, to a double


# Taylor coefficients, highest degree first: sin r = r + r z S(z) with S's from 1/17! to -1/3!,
# cos r = 1 - z C(z) with C's from 1/18! to 1/2! (z = r^2). Each is the double nearest to it:
# the factorials are exact in a double.
_SIN = tuple((-1.0) ** k / math.factorial(2 * k + 1) for k in range(8, 0, -1))
_COS = tuple((-1.0) ** (k + 1) / math.factorial(2 * k) for k in range(9, 0, -1))


@njit(cache=True, _nrt=False, inline="always")
def _horner(z, coefficients):
    """The polynomial with ``coefficients`` (highest degree first) at z, by Horner's rule."""
    total = coefficients[0]
    for k in range(1, len(coefficients)):
        total = total * z + coefficients[k]
    return total


@njit(cache=True, _nrt=False)
def _kernel(r):
    """(sin r, cos r) for |r| <= pi/4 (plus a rounding): Horner sums of the Taylor series."""
    z = r * r
    return r + r * z * _horner(z, _SIN), 1.0 - z * _horner(z, _COS)


@njit(cache=True, _nrt=False)
def _reduced(x):
    """(sin x, cos x) for |x| <= REDUCED_UP_TO, without branches (selects only)."""
    k = np.floor(x * _TWO_OVER_PI + 0.5)
    r = ((x - k * _PIO2_1) - k * _PIO2_2) - k * _PIO2_3
    s, c = _kernel(r)
    quadrant = int(k) & 3
    swap = (quadrant & 1) == 1
    sin_x = c if swap else s
    cos_x = s if swap else c
    sin_x = -sin_x if (quadrant & 2) == 2 else sin_x
    cos_x = -cos_x if ((quadrant + 1) & 2) == 2 else cos_x
    return sin_x, cos_x


@njit(cache=True, _nrt=False)
def sincos(x):
    """(sin x, cos x) for a float x, within 2 ulp; NaN for a non-finite x."""
    if abs(x) <= REDUCED_UP_TO:
        return _reduced(x)
    return np.sin(x), np.cos(x)


@njit(cache=True, _nrt=False, inline="always")
def sincos_lanes(x, sin_out, cos_out, count):
    """sin_out[i], cos_out[i] = sincos(x[i]) for i < count, in a loop the compiler vectorises
    when every |x[i]| is within REDUCED_UP_TO (else the C library's, one at a time)."""
    reduced = True
    for i in range(count):
        reduced &= abs(x[i]) <= REDUCED_UP_TO
    if reduced:
        for i in range(count):
            sin_out[i], cos_out[i] = _reduced(x[i])
    else:
        for i in range(count):
            sin_out[i] = np.sin(x[i])
            cos_out[i] = np.cos(x[i])
