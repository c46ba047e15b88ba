"""The zero search of a special point's relocation on another discretisation (``_localise._bracketed_zero``):
analytic test functions with known zeros, in place of the corrections that evaluate them on a branch."""
import math

import numpy as np
import pytest

from gfbjax.cont._localise import _bracketed_zero, locate


def counted(fn):
    """g(s) -> (fn(s), lam = 2 s + 0.1), counting its evaluations in ``calls``."""
    calls = []

    def g(s):
        calls.append(s)
        return fn(s), 2.0 * s + 0.1

    return g, calls


def start(fn, lo, hi):
    return {lo: (fn(lo), 2.0 * lo + 0.1), hi: (fn(hi), 2.0 * hi + 0.1)}


@pytest.mark.parametrize("fn, zero", [
    (lambda s: s - 0.3, 0.3),
    (lambda s: np.tanh(40.0 * (s - 0.31)), 0.31),          # steep at the zero, flat at the ends
    (lambda s: (s - 0.27) * (1.0 + 30.0 * s ** 2), 0.27),  # curved: regula falsi keeps one end and creeps
    (lambda s: np.exp(8.0 * s) - np.exp(8.0 * 0.42), 0.42),
])
def test_zero_found_to_the_tolerance(fn, zero):
    g, calls = counted(fn)
    known = start(fn, 0.0, 1.0)
    tol = 1e-3 * min(1.0, max(abs(v) for v, _ in known.values()))
    lam = _bracketed_zero(g, known, tol, [16])
    # |fn| <= tol at the returned point: its distance from the zero is at most tol / |fn'| there
    slope = abs(fn(zero + 1e-7) - fn(zero - 1e-7)) / 2e-7
    assert abs(lam - (2.0 * zero + 0.1)) <= 2.0 * 1.5 * tol / slope
    assert len(calls) <= 12


def test_a_jump_is_bracketed_and_its_line_zero_returned():
    """A test function that jumps (a mesh node crossing a kink): no value within tol exists; the bracket closes to
    1e-4 and the zero of the line through its ends lies inside it."""
    fn = lambda s: 1.0 if s < 0.37 else -1.0  # noqa: E731
    g, calls = counted(fn)
    lam = _bracketed_zero(g, start(fn, 0.0, 1.0), 1e-6, [40])
    assert abs(lam - (2.0 * 0.37 + 0.1)) <= 2.0 * 1e-4
    assert len(calls) <= 40


def test_a_failed_correction_or_an_empty_budget_gives_the_brackets_line_zero():
    """A correction that fails inside the bracket (NaN) or no correction left: the bracket found so far still holds
    the zero, and the line through its ends gives it (exact for a straight test function)."""
    fn = lambda s: s - 0.3  # noqa: E731
    calls = []

    def failing(s):
        calls.append(s)
        return math.nan, None

    assert _bracketed_zero(failing, start(fn, 0.0, 1.0), 1e-9, [16]) == pytest.approx(0.7, abs=1e-12)
    assert len(calls) == 1
    # a failure next to the zero after some progress: the narrowest sign change found before it
    curved = lambda s: (s - 0.27) * (1.0 + 30.0 * s ** 2)  # noqa: E731
    g, seen = counted(curved)
    lam = _bracketed_zero(lambda s: (math.nan, None) if len(seen) >= 2 else g(s), start(curved, 0.0, 1.0), 1e-12,
                          [16])
    g0, g1 = curved(0.0), curved(1.0)
    first_line = 0.1 + 2.0 * g0 / (g0 - g1)  # the line zero of the bracket as given: 0.12, the zero is at 0.64
    assert len(seen) == 2 and abs(lam - (2.0 * 0.27 + 0.1)) < 0.25 * abs(first_line - (2.0 * 0.27 + 0.1))
    g, calls = counted(fn)
    lam = _bracketed_zero(g, start(fn, 0.0, 1.0), 1e-12, [0])
    assert calls == [] and lam == pytest.approx(0.7, abs=1e-12)


@pytest.mark.parametrize("width", [1e-2, 1e-5, 1e-8])
def test_a_narrow_bracket_is_refined_as_a_wide_one(width):
    """The bracket closes relative to its width: a shift far below 1e-4 in s is still searched inside, to the
    tolerance (an absolute closure left a bracket of 1e-5 without an evaluation: the secant through its ends,
    98 % off on this exponential)."""
    zero = 0.42 * width
    fn = lambda s: np.exp(8.0 * s / width) - np.exp(8.0 * zero / width)  # noqa: E731
    g, calls = counted(fn)
    known = start(fn, 0.0, width)
    tol = 1e-3 * min(1.0, max(abs(v) for v, _ in known.values()))
    lam = _bracketed_zero(g, known, tol, [16])
    slope = 8.0 / width * np.exp(8.0 * zero / width)
    assert len(calls) >= 1
    assert abs(lam - (2.0 * zero + 0.1)) <= 2.0 * 1.5 * tol / slope


# ---- locate: the regula falsi that localises an event on the branch itself
def _noisy(slope, zero, noise):
    """A straight test function plus +-noise, random in s but repeatable (a branch point's multiplier test,
    computed only to ~sqrt(eps) next to its zero)."""
    def fn(s):
        sign = np.random.default_rng(int(s * 2.0**52) % 2**32).choice([-1.0, 1.0])
        return slope * (s - zero) * (1.0 + 10.0 * s) + noise * sign  # curved: no secant lands on the zero
    return fn


def _run(fn, s_hi, **kw):
    calls, info = [], {}

    def g(s):
        calls.append(s)
        return fn(s), s

    s, _, value, located = locate(g, s_hi, fn(0.0), fn(s_hi), tol=1e-8, info=info, **kw)
    return s, value, located, info, len(calls)


def test_locate_stops_at_the_noise_floor_of_a_test_function():
    """Down in its noise a test function cannot say where its zero is better than |noise / slope|, and the regula
    falsi went on to a bracket of 1e-10 s_hi (on the Brusselator's first branch point of cycles, n = 20, three
    attempts of 22-30 corrections each, the step halved between them).  With ``noise_stop`` it ends there, not
    located, with the noise flagged, and the zero lies within the noise over the slope of the returned s."""
    slope, zero, noise = 0.2, 0.0123, 3.6e-7
    fn = _noisy(slope, zero, noise)
    s, value, located, info, calls = _run(fn, 0.05, noise_stop=True)
    assert not located and info.get("noise")
    assert abs(s - zero) <= 2.0 * noise / slope + (info["bracket"][1] - info["bracket"][0])
    assert abs(value) <= 2 * noise
    # without it the bracket closes to 1e-10 on a value that happens to be small, which passes for a located zero
    _, _, _, info_old, calls_old = _run(fn, 0.05)
    assert not info_old.get("noise") and calls < calls_old, (calls, calls_old)


@pytest.mark.parametrize("steep", [1.0, 50.0])
def test_locate_with_noise_stop_still_locates_a_steep_smooth_zero(steep):
    """A continuous test function whose slope at its zero is up to 50 times its mean slope over the step is located
    as before (the noise test fires only beyond NOISE_SPAN = 100 times)."""
    zero = 0.0311
    k = 2.0 * steep / 0.05  # tanh(k (s - zero)) on [0, 0.05]: mean slope ~2 / 0.05, slope k at the zero
    fn = lambda s: math.tanh(k * (s - zero))  # noqa: E731
    s, value, located, info, _ = _run(fn, 0.05, noise_stop=True)
    assert located and not info.get("noise") and abs(value) <= 1e-8
    assert abs(s - zero) <= 1e-8 / k * 1.01
