r"""Adaptive collocation meshes: an a-posteriori error estimate per interval, and its equidistribution.

Why: a uniform mesh in the scaled time wastes intervals where the orbit moves slowly and starves the fast parts
(a relaxation oscillation, a cycle near a homoclinic or saddle-node-on-invariant-circle limit whose period grows
without bound, a bearing orbit with a kink where the film pressure is clipped).  There the trivial multiplier
can stay at 1 to rounding while the period is wrong in the fourth digit, so the mesh error must be estimated
on its own.

Estimate (the approach of AUTO's mesh adaptation).  On interval :math:`j` of width :math:`h_j` the collocation
solution is a polynomial of degree m; its m-th derivative :math:`d_j = \Delta^m U_j / (h_j/m)^m` is constant
there (:math:`\Delta^m`: the m-th difference of the m+1 equally spaced nodes).  The jumps of :math:`d` between
neighbouring intervals estimate the (m+1)-th derivative, :math:`e_j \approx |x^{(m+1)}|` on interval j, and

.. math::  \varepsilon_j = \frac{h_j^{m+1}\, e_j}{(m+1)!} \max_{s \in [0,1]} \Big|\prod_{i=0}^{m} (s - i/m)\Big|

is the Lagrange remainder of interpolating at the m+1 equally spaced nodes: an estimate of the error of the orbit
between its nodes on that interval, in the units of the state.  Checked against the true error (the orbit
against a tight time integration from its own initial point) on a cycle near an infinite-period limit: the two
agree within a factor of about 2 over periods from 3.6 to 58 (tests/cont/test_cont_mesh.py).  Mesh values, the
period and the multipliers of a smooth orbit are more accurate than this (Gauss collocation is superconvergent
there).  It can fall short where the orbit is barely resolved: on van der Pol at N = 16 the error sits between the
nodes of the fast stretch, 3.5-15x above this estimate (found by a fresh-user review; see Limits below).

Kinks.  Where f has a kink (the bearing's exact Gumbel condition max(p - 1, 0)) the estimate above sees the kink
inside an interval only as the polynomial smooths it: on the kinked oscillator of the tests the orbit's true error
was 12-25x that estimate at omega = 1 (8.6e-4 against 3.4e-5 at N = 16), and up to 100x along its resonance
branch.  The second estimate is the defect the collocation equations leave over each interval,

.. math::  \delta_j = x(t_{j+1}) - x(t_j) - T \int_{t_j}^{t_{j+1}} f(x(t), \lambda)\, dt,

the integral by a finer quadrature (:data:`SUBINTERVALS` pieces of m + 2 Gauss-Legendre points).  The collocation
equations make the m-point quadrature of this integral vanish, so :math:`\delta_j` is the quadrature error of the
collocation points on :math:`f(x(t))`: of order :math:`h^{2m+1}` where f(x(t)) is smooth (far below the first
estimate), of order :math:`h^2` on an interval where it has a kink.  The orbit's error at the mesh points is what
these local defects add up to over the period, so the estimate is :math:`\max_c \sum_j |\delta_{j,c}|` over the
components c.  "True error" here is the orbit against a tight time integration from its own first node, the
accuracy of the orbit as a solution.  Near a fold, or wherever a multiplier approaches +1, the distance to the
exact cycle at the same lam is larger by about 1/|1 - mu| (the problem at fixed lam is ill-conditioned there);
special points carry their own estimate (``SpecialPoint.lam_error``).  Measured: 0.7-1.4x the true error on the
kinked oscillator at omega = 1 (N = 16-64) and 0.7-1.5x along its resonance branch (tests/cont/test_cont_mesh.py);
0.3-5x on other kinked fields in a fresh-user review (abs, a clearance spring, several kinks per period, a kink in
a fast variable; m = 2-5, Gauss and Radau).  On the GFB, against the orbit on N = 128: 2.5x and 1.3x above it at
N = 16 and 32 (16x2, Omega_bar 0.38), 3.6x and 2.8x (48x8, Omega_bar 0.95).  Summing each interval's largest
component instead added kinks of different pressure nodes and was 5-8x above it there.  It costs one evaluation
of f at N x SUBINTERVALS x (m + 2) points per recorded point.
:func:`error_estimate` returns the larger of the largest :math:`\varepsilon_j` and (given f) the summed defects of
the worst component, relative to ``1 + max |x|``.

Limits.  Errors between the nodes of a smooth but barely resolved stretch (the van der Pol case above) are not
covered.  The running defect inside an interval, x(t) - x(t_j) - T int f, estimates them well for non-stiff
components (0.7-0.8x on van der Pol), but it ignores the damping of stiff components, whose error is about the
residual divided by their rate, not its integral: on a component with h K = 1.6e4 it said 1.9e-3 for a true
4.4e-6 and flagged a good point, and on the GFB (film modes) it over-estimated 4-8x; it was tried in session 9
and withdrawn.  The summed defects share that fault in milder form: a stiff component's defects are its rate times
a small interpolation error, and the error they cause decays within an interval instead of adding up.  On a
component x' = -k (x - u^3) driven by a unit-circle oscillator (k = 1e4) the estimate was 28x the true error
with Radau m = 4, N = 16, 89x with Gauss m = 2 and 1.3e4x with Radau m = 2 (N = 32): conservative, but it flags
good points.  With Gauss m = 4 it stays below the interpolation estimate there; on the GFB it stays below
mesh_tol with both point sets (Radau N = 16: 5e-5 at Omega_bar 0.38).  The cure for both limits is to propagate
the defects through the linearisation (the interval transfer maps damp the stiff parts) instead of summing them.

Equidistribution.  The new mesh gives every interval the same share of :math:`\int e(t)^{1/(m+1)}\,dt`
(:math:`e` piecewise constant on the old mesh), so that every :math:`\varepsilon_j` comes out about equal; a floor
of a small fraction of the mean density keeps quiet stretches from losing all their intervals.  The orbit (and
any tangent) is carried to the new mesh by evaluating its piecewise polynomial at the new nodes.
"""
from __future__ import annotations

import functools
import math
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from . import _collocation as col

__all__ = ["interval_errors", "defect_errors", "error_estimate", "equidistributed_mesh", "remesh", "SUBINTERVALS"]

#: pieces of each mesh interval for the defect's quadrature (each with m + 2 Gauss-Legendre points): the sums
#: came out the same with 16 on the kinked oscillator
SUBINTERVALS = 4
# density floor, as a fraction of the mean density (keeps every stretch of the period resolved)
_FLOOR = 0.1


def _mth_derivative(U: np.ndarray, h: np.ndarray, m: int) -> np.ndarray:
    """(N, n): the m-th derivative in the scaled time of each interval's polynomial (nodes U: (N, m+1, n))."""
    coef = np.array([(-1) ** (m - k) * math.comb(m, k) for k in range(m + 1)], float)
    return np.einsum("k,jkn->jn", coef, U) / (h[:, None] / m) ** m


def _jump_rates(orbit: col.Orbit, scheme: col.Scheme) -> tuple[np.ndarray, np.ndarray]:
    """(e_j, h_j): the estimated |x^(m+1)| per interval (max over the components) and the widths."""
    U = np.asarray(orbit.nodes(), float)
    mesh = np.asarray(orbit.mesh, float)
    h = np.diff(mesh)
    m = scheme.m
    d = _mth_derivative(U, h, m)
    # periodic neighbours: the orbit is closed, so interval N-1 borders interval 0
    right = np.abs(np.roll(d, -1, axis=0) - d).max(axis=1) / (0.5 * (h + np.roll(h, -1)))
    left = np.abs(d - np.roll(d, 1, axis=0)).max(axis=1) / (0.5 * (h + np.roll(h, 1)))
    return 0.5 * (left + right), h


@functools.lru_cache(maxsize=None)
def _node_polynomial_max(m: int) -> float:
    """max over s in [0, 1] of |prod_i (s - i/m)|: the Lagrange remainder's constant for m+1 equal nodes."""
    s = np.linspace(0.0, 1.0, 20001)
    return float(np.max(np.abs(np.prod(s[:, None] - np.linspace(0.0, 1.0, m + 1)[None, :], axis=1))))


def interval_errors(orbit: col.Orbit, scheme: col.Scheme) -> np.ndarray:
    """(N,): the estimated interpolation error of the orbit on each interval (module docstring), state units."""
    e, h = _jump_rates(orbit, scheme)
    m = scheme.m
    return h ** (m + 1) * e * _node_polynomial_max(m) / math.factorial(m + 1)


@functools.lru_cache(maxsize=None)
def _defect_rule(scheme: col.Scheme) -> tuple[np.ndarray, np.ndarray]:
    """(B, w): the Lagrange basis of the nodes at the fine quadrature points of [0, 1], (Q, m+1), and weights (Q,)."""
    g, w = np.polynomial.legendre.leggauss(scheme.m + 2)
    pts = ((np.arange(SUBINTERVALS)[:, None] + 0.5 * (g[None, :] + 1.0)) / SUBINTERVALS).ravel()
    return scheme.basis_at(pts), np.tile(0.5 * w, SUBINTERVALS) / SUBINTERVALS


@functools.partial(jax.jit, static_argnums=(0,))
def _defects(f: Callable, args: Any, U: jax.Array, h: jax.Array, T: jax.Array, lam: jax.Array,
             B: jax.Array, w: jax.Array) -> jax.Array:
    X = jnp.einsum("qi,jin->jqn", B, U)
    F = col._f_batched(f, X, lam, args)
    return U[:, -1] - U[:, 0] - T * h[:, None] * jnp.einsum("q,jqn->jn", w, F)


def defect_errors(f: Callable, args: Any, orbit: col.Orbit, scheme: col.Scheme) -> np.ndarray:
    """(N, n): |delta_j|, the defect of the collocation equations on each interval by the finer quadrature
    (module docstring), per component, state units.  ``f(x, lam, args)`` is the problem's vector field."""
    B, w = _defect_rule(scheme)
    U = orbit.nodes()
    d = _defects(f, args, U, jnp.diff(orbit.mesh), orbit.T, orbit.lam, jnp.asarray(B, U.dtype), jnp.asarray(w, U.dtype))
    return np.abs(np.asarray(d, float))


def error_estimate(orbit: col.Orbit, scheme: col.Scheme, f: Callable | None = None, args: Any = None) -> float:
    """The a-posteriori accuracy of a collocation orbit relative to ``1 + max |x|``: the largest interval error
    (:func:`interval_errors`) and, given the vector field ``f``, the defects (:func:`defect_errors`) summed over
    the intervals for the worst component, whichever is larger (the second is the one that sees kinks of f).
    Infinite where f is NaN or inf at the quadrature points (an orbit through a region where the field is
    undefined is not resolved, and a NaN would pass every comparison with a tolerance); a region narrower than
    their spacing can be missed."""
    scale = 1.0 + float(np.max(np.abs(np.asarray(orbit.xm))))
    est = float(np.max(interval_errors(orbit, scheme)))
    if f is not None:
        defects = float(np.max(np.sum(defect_errors(f, args, orbit, scheme), axis=0)))
        est = est if defects <= est else defects  # max() would drop a NaN
    return est / scale if np.isfinite(est) else math.inf


def equidistributed_mesh(orbit: col.Orbit, scheme: col.Scheme) -> np.ndarray:
    """(N+1,): a mesh with the same number of intervals on which the estimated errors are equal."""
    e, h = _jump_rates(orbit, scheme)
    rho = e ** (1.0 / (scheme.m + 1))
    mean = float(np.sum(rho * h))
    if not np.isfinite(mean) or mean <= 0.0:
        return np.asarray(orbit.mesh, float)
    rho = np.maximum(rho, _FLOOR * mean)
    cum = np.concatenate([[0.0], np.cumsum(rho * h)])
    levels = np.linspace(0.0, cum[-1], len(h) + 1)
    mesh = np.interp(levels, cum, np.asarray(orbit.mesh, float))
    mesh[0], mesh[-1] = 0.0, 1.0
    return mesh


def remesh(orbit: col.Orbit, scheme: col.Scheme, mesh: np.ndarray, shift: float = 0.0) -> col.Orbit:
    """The orbit's piecewise polynomial sampled on the nodes of ``mesh`` (T and lam unchanged); with ``shift``,
    the orbit moved in time: the new orbit at scaled time t is the old one at t + shift (mod 1)."""
    old = np.asarray(orbit.mesh, float)
    U = np.asarray(orbit.nodes(), float)

    def x_of_t(t):
        t = np.mod(np.asarray(t, float) + shift, 1.0)
        j = np.clip(np.searchsorted(old, t, side="right") - 1, 0, len(old) - 2)
        s = (t - old[j]) / (old[j + 1] - old[j])
        B = scheme.basis_at(s)  # (len(t), m+1): each row for its own local point
        return np.einsum("ti,tin->tn", B, U[j])

    new = col.orbit_from_function(x_of_t, float(orbit.T), float(orbit.lam), scheme, mesh)
    return col.Orbit(new.mesh, new.xm, new.xi, jnp.asarray(orbit.T), jnp.asarray(orbit.lam))
