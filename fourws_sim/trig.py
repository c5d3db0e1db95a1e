# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""sin, cos and atan of the vehicle model's compiled kernels, written in plain arithmetic.

Why not ``math.sin``: the study's batch kernel advances many points at once with SIMD
instructions (:mod:`fourws_study.lanes`), and a call into the C library cannot be vectorized.
These functions are branch-free chains of IEEE additions, multiplications and one division,
so the compiler vectorizes them, and a vector lane computes exactly the bits the scalar code
computes: the simulator, the offline twin and the batch kernel agree bit for bit. They are
also the same on every machine (the C library's last bit differs between versions).

The algorithms and coefficients are those of fdlibm (Sun Microsystems, 1993; freely
redistributable, the source of most C libraries' versions), as kept in musl's ``__sin.c``,
``__cos.c`` and ``s_atan.c``: a Cody-Waite reduction by pi/2 in three parts and the
degree-13/14 minimax kernels for sin and cos, and the four-interval reduction with a
degree-22 odd polynomial for atan. ``test_trig.py`` checks them against ``math`` to 1 ulp
on the arguments the model sees (|x| < 1e5 for sin/cos: headings of many turns; any x for
atan) and bit for bit between plain Python and compiled code.

They are plain functions (numba compiles and inlines them where the kernels call them, via
``register_jitable``), so the NumPy reference and the tire's Python path give the same
numbers as the kernels.
"""

from __future__ import annotations

import warnings

from numba.core.errors import NumbaIRAssumptionWarning
from numba.extending import register_jitable

# These functions are inlined into the kernels at numba's IR level (so the compiler can
# vectorize the loops that call them); numba's pedantic SSA check then reports the inlined
# conditional expressions' variables as "not in scope" although the compiled code is right
# (the batch kernel equals the scalar one bit for bit, test_eightdof_regression). Only that
# check's warning is silenced.
warnings.filterwarnings("ignore", message=r"variable '.*' is not in scope",
                        category=NumbaIRAssumptionWarning)

#: 1.5 * 2**52: adding and subtracting it rounds a double of magnitude < 2**51 to the
#: nearest integer (ties to even), as rint does, without a call.
_RINT = 6755399441055744.0
_INV_PIO2 = 6.36619772367581382433e-01
#: pi/2 in three parts (33 + 33 + 53 bits): k * _PIO2_1 and k * _PIO2_2 are exact for
#: |k| < 2**20.
_PIO2_1 = 1.57079632673412561417e+00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_2T = 2.02226624879595063154e-21

_S1 = -1.66666666666666324348e-01
_S2 = 8.33333333332248946124e-03
_S3 = -1.98412698298579493134e-04
_S4 = 2.75573137070700676789e-06
_S5 = -2.50507602534068634195e-08
_S6 = 1.58969099521155010221e-10

_C1 = 4.16666666666666019037e-02
_C2 = -1.38888888888741095749e-03
_C3 = 2.48015872894767294178e-05
_C4 = -2.75573143513906633035e-07
_C5 = 2.08757232129817482790e-09
_C6 = -1.13596475577881948265e-11

_ATANHI0 = 4.63647609000806093515e-01
_ATANHI1 = 7.85398163397448278999e-01
_ATANHI2 = 9.82793723247329054082e-01
_ATANHI3 = 1.57079632679489655800e+00
_ATANLO0 = 2.26987774529616870924e-17
_ATANLO1 = 3.06161699786838301793e-17
_ATANLO2 = 1.39033110312309984516e-17
_ATANLO3 = 6.12323399573676603587e-17
_AT0 = 3.33333333333329318027e-01
_AT1 = -1.99999999998764832476e-01
_AT2 = 1.42857142725034663711e-01
_AT3 = -1.11111104054623557880e-01
_AT4 = 9.09088713343650656196e-02
_AT5 = -7.69187620504482999495e-02
_AT6 = 6.66107313738753120669e-02
_AT7 = -5.83357013379057348645e-02
_AT8 = 4.97687799461593236017e-02
_AT9 = -3.65315727442169155270e-02
_AT10 = 1.62858201153657823623e-02


@register_jitable(error_model="numpy", inline="always")
def sincos(x: float) -> tuple[float, float]:
    """``(sin(x), cos(x))`` to 1 ulp for |x| < 1e5 rad (a heading of 16000 turns); the
    reduction is exact up to 2**20 quarter turns (1.6e6 rad) and meaningless far beyond
    (NaN from about 1e150); NaN for inf and NaN."""
    k = (x * _INV_PIO2 + _RINT) - _RINT  # nearest quarter turn
    # fdlibm's medium reduction with its second round always taken (r + y = x - k pi/2 to
    # about 118 bits, so sin(pi) has its last bits too)
    t = x - k * _PIO2_1  # exact
    w = k * _PIO2_2  # exact
    hi = t - w
    lo = k * _PIO2_2T - ((t - hi) - w)
    r = hi - lo
    y = (hi - r) - lo  # the part of the reduced argument r does not hold
    z = r * r
    w = z * z
    # fdlibm __kernel_sin(r, y, 1)
    poly = _S2 + z * (_S3 + z * _S4) + z * w * (_S5 + z * _S6)
    v = z * r
    s = r - ((z * (0.5 * y - v * poly) - y) - v * _S1)
    # fdlibm __kernel_cos(r, y)
    rc = z * (_C1 + z * (_C2 + z * _C3)) + w * w * (_C4 + z * (_C5 + z * _C6))
    hz = 0.5 * z
    one_hz = 1.0 - hz
    c = one_hz + (((1.0 - one_hz) - hz) + (z * rc - r * y))
    # quadrant q = k mod 4 in {-2, -1, 0, 1, 2} (exact for |k| < 2**50)
    q = k - 4.0 * ((k * 0.25 + _RINT) - _RINT)
    odd = q == 1.0 or q == -1.0
    sin_neg = q == 2.0 or q == -2.0 or q == -1.0
    cos_neg = q == 1.0 or q == 2.0 or q == -2.0
    sv = c if odd else s
    cv = s if odd else c
    return (-sv if sin_neg else sv), (-cv if cos_neg else cv)


@register_jitable(error_model="numpy", inline="always")
def sin(x: float) -> float:
    """sin(x) (:func:`sincos`)."""
    return sincos(x)[0]


@register_jitable(error_model="numpy", inline="always")
def cos(x: float) -> float:
    """cos(x) (:func:`sincos`)."""
    return sincos(x)[1]


@register_jitable(error_model="numpy", inline="always")
def atan(x: float) -> float:
    """atan(x) to 1 ulp for every x (fdlibm's reduction to |x| < 7/16, branch-free);
    +-pi/2 at +-inf, NaN for NaN."""
    t = abs(x)
    small = t < 0.4375
    if t < 0.6875:
        num, den, hi, lo = 2.0 * t - 1.0, 2.0 + t, _ATANHI0, _ATANLO0
    elif t < 1.1875:
        num, den, hi, lo = t - 1.0, t + 1.0, _ATANHI1, _ATANLO1
    elif t < 2.4375:
        num, den, hi, lo = t - 1.5, 1.0 + 1.5 * t, _ATANHI2, _ATANLO2
    else:
        num, den, hi, lo = -1.0, t, _ATANHI3, _ATANLO3
    if small:
        num, den = x, 1.0
    xr = num / den
    z = xr * xr
    w = z * z
    s1 = z * (_AT0 + w * (_AT2 + w * (_AT4 + w * (_AT6 + w * (_AT8 + w * _AT10)))))
    s2 = w * (_AT1 + w * (_AT3 + w * (_AT5 + w * (_AT7 + w * _AT9))))
    if small:
        return xr - xr * (s1 + s2)
    big = hi - ((xr * (s1 + s2) - lo) - xr)
    return -big if x < 0.0 else big


__all__ = ["atan", "cos", "sin", "sincos"]
