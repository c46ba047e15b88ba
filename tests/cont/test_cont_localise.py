"""The zero search of a special point's relocation on another discretisation (``_localise._bracketed_zero``):
analytic test functions with known zeros, in place of the corrections that evaluate them on a branch."""
import math

import numpy as np
import pytest

from gfbjax.cont._localise import _bracketed_zero


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
