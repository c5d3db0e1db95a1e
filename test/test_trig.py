# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""fourws_sim.trig: sin, cos and atan of the compiled kernels against the C library (1 ulp,
the accuracy fdlibm states for its kernels) and bit for bit between plain Python, compiled
scalar code and a vectorized loop."""

from __future__ import annotations

import math

import numba
import numpy as np

from fourws_sim import trig

RNG = np.random.default_rng(20261130)
#: Arguments: steering, slip and roll angles (small), headings of many turns (up to 1e5 rad),
#: the interval edges of atan's reduction, multiples of pi/2 (where sin and cos cancel).
ARGS = np.concatenate([
    RNG.uniform(-4.0, 4.0, 20000), RNG.normal(0.0, 0.05, 20000),
    RNG.uniform(-1e5, 1e5, 20000),
    [0.0, -0.0, 1e-300, 5e-324, 0.4375, 0.6875, 1.1875, 2.4375, -2.4375, 1e20, -1e300],
    np.arange(-64, 65) * (math.pi / 2)])


def _ulps(got: float, want: float) -> float:
    return abs(got - want) / math.ulp(want) if want != 0.0 else abs(got) / 5e-324


@numba.njit(error_model="numpy")
def _compiled(xs, out):  # type: ignore[no-untyped-def]
    for i in range(xs.size):
        s, c = trig.sincos(xs[i])
        out[0, i] = s
        out[1, i] = c
        out[2, i] = trig.atan(xs[i])


def test_sin_cos_atan_within_one_ulp_of_the_c_library():
    worst = {"sin": 0.0, "cos": 0.0, "atan": 0.0}
    for x in ARGS:
        x = float(x)
        s, c = trig.sincos(x)
        if abs(x) <= 1e5:
            assert (trig.sin(x), trig.cos(x)) == (s, c)
            worst["sin"] = max(worst["sin"], _ulps(s, math.sin(x)))
            worst["cos"] = max(worst["cos"], _ulps(c, math.cos(x)))
        worst["atan"] = max(worst["atan"], _ulps(trig.atan(x), math.atan(x)))
    assert max(worst.values()) <= 1.0, worst
    # odd and even symmetry, limits
    for x in (0.3, 1.0, 7.5, 1234.5):
        assert trig.sincos(-x) == (-trig.sin(x), trig.cos(x))
        assert trig.atan(-x) == -trig.atan(x)
    assert trig.atan(math.inf) == math.pi / 2 and trig.atan(-math.inf) == -math.pi / 2
    assert trig.sincos(0.0) == (0.0, 1.0)


def test_non_finite_arguments_give_nan():
    for x in (math.inf, -math.inf, math.nan):
        assert all(math.isnan(v) for v in trig.sincos(x))
    assert math.isnan(trig.atan(math.nan))


def test_python_and_compiled_code_give_the_same_bits():
    out = np.empty((3, ARGS.size))
    _compiled(ARGS, out)
    for i, x in enumerate(ARGS):
        s, c = trig.sincos(float(x))
        got = (out[0, i], out[1, i], out[2, i])
        assert np.array([s, c, trig.atan(float(x))]).tobytes() == np.array(got).tobytes(), x


def test_wide_vectors_only_where_the_user_has_not_chosen(monkeypatch):
    """use_wide_vectors (fourws study, fourws bench --study) turns off LLVM's 256-bit
    preference only on an x86-64 CPU with AVX-512 and never over the user's own numba CPU
    settings; the features it writes are the host's, with that one change."""
    from numba.core import codegen

    from fourws_sim import lanes

    host = codegen.get_host_cpu_features()
    for user in ({"NUMBA_CPU_FEATURES": "+sse2"}, {"NUMBA_CPU_NAME": "generic"}):
        env = dict(user)
        assert lanes.use_wide_vectors(env) is False and env == user
    monkeypatch.setattr(lanes.platform, "machine", lambda: "aarch64")
    env: dict[str, str] = {}
    assert lanes.use_wide_vectors(env) is False and env == {}
    monkeypatch.setattr(lanes.platform, "machine", lambda: "x86_64")
    env = {}
    done = lanes.use_wide_vectors(env)
    assert done == ("+avx512f" in host.split(","))
    assert env == ({"NUMBA_CPU_FEATURES": host + ",-prefer-256-bit"} if done else {})
