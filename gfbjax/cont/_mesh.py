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
there).

Kinks, and errors between the nodes.  Where f has a kink (the bearing's exact Gumbel condition max(p - 1, 0))
the estimate above sees the kink inside an interval only as the polynomial smooths it: on the kinked oscillator of
the tests the orbit's true error was 12-25x that estimate at omega = 1 (8.6e-4 against 3.4e-5 at N = 16), and up
to 100x along its resonance branch.  On a smooth orbit whose fast stretch a coarse mesh barely resolves (van der
Pol at N = 16) it fell 3.5-15x short as well.  The second estimate uses the running defect the collocation
equations leave inside each interval,

.. math::  D_j(s) = x(t_j + s h_j) - x(t_j) - T \int_{t_j}^{t_j + s h_j} f(x(t), \lambda)\, dt,
           \qquad \delta_j = D_j(1),

the integrals by a finer quadrature (:data:`SUBINTERVALS` pieces of m + 2 Gauss-Legendre points, D at the pieces'
ends).  The collocation equations make the m-point quadrature of :math:`\delta_j` vanish, so :math:`\delta_j` is
the quadrature error of the collocation points on :math:`f(x(t))`: of order :math:`h^{2m+1}` where f(x(t)) is
smooth, of order :math:`h^2` on an interval where it has a kink.  The orbit's error at the mesh points is what
these local defects add up to over the period, and between them it grows from there by :math:`D_j(s)` (the
error e obeys e' = T (f_x e + residual), and over one interval the first term is of higher order).  Their sum
bounds the leading term; the estimate is the larger of the two, within a factor 2 of the sum,

.. math::  \max_c \max\Big(\sum_j |\delta_{j,c}|,\ \max_{j,s} |D_{j,c}(s)|\Big)

over the components c (the sum itself came out 1.2-1.8x the true error on the kinked oscillator and put a false
flag at the end of the GFB reference branch).  "True error" here is the orbit against a tight time integration from its own first
node, the accuracy of the orbit as a solution.  Near a fold, or wherever a multiplier approaches +1, the
distance to the exact cycle at the same lam is larger by about 1/|1 - mu| (the problem at fixed lam is
ill-conditioned there); special points carry their own estimate (``SpecialPoint.lam_error``).  Measured
(tests/cont/test_cont_mesh.py, a fresh-user review, scripts of the session notes): 0.7-1.4x the true error on
the kinked oscillator at omega = 1 (N = 16-64) and 0.7-1.5x along its resonance branch; 0.7-3.1x on other kinked
fields (abs, a clearance spring, kinks in a fast variable; m = 4, N = 16 and 32); 0.7-1.3x on van der Pol at mu = 1 and 4 with m = 2-5,
Gauss and Radau, except where the orbit is not resolved at all (0.25-0.5 where the true error is 0.05-5).  On
the GFB it is conservative, because the stiff film modes damp the local defects that the sum adds up: against
the orbit on N = 128, 2.5x and 1.3x above it at N = 16 and 32 (16x2, Omega_bar 0.38), 3.9x and 2.8x (48x8,
Omega_bar 0.95).  It costs one evaluation of f at
N x SUBINTERVALS x (m + 2) points per recorded point.  :func:`error_estimate` returns the larger of the largest
:math:`\varepsilon_j` and (given f) this estimate, relative to ``1 + max |x|``.

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

__all__ = ["interval_errors", "running_defects", "defect_errors", "error_estimate", "equidistributed_mesh", "remesh", "SUBINTERVALS"]

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
def _defect_rule(scheme: col.Scheme) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(B, w, E): the Lagrange basis of the nodes at the fine quadrature points of [0, 1], (S*q, m+1), their
    weights on each piece (q,), and the basis at the pieces' right ends k/S, (S, m+1)."""
    g, w = np.polynomial.legendre.leggauss(scheme.m + 2)
    pts = ((np.arange(SUBINTERVALS)[:, None] + 0.5 * (g[None, :] + 1.0)) / SUBINTERVALS).ravel()
    ends = np.arange(1, SUBINTERVALS + 1) / SUBINTERVALS
    return scheme.basis_at(pts), 0.5 * w / SUBINTERVALS, scheme.basis_at(ends)


@functools.partial(jax.jit, static_argnums=(0,))
def _running(f: Callable, args: Any, U: jax.Array, h: jax.Array, T: jax.Array, lam: jax.Array,
             B: jax.Array, w: jax.Array, E: jax.Array) -> jax.Array:
    X = jnp.einsum("qi,jin->jqn", B, U)
    F = jax.vmap(jax.vmap(lambda x: f(x, lam, args)))(X)
    pieces = jnp.einsum("q,jpqn->jpn", w, F.reshape(U.shape[0], E.shape[0], w.shape[0], U.shape[2]))
    return (jnp.einsum("ki,jin->jkn", E, U) - U[:, :1]) - T * h[:, None, None] * jnp.cumsum(pieces, axis=1)


def running_defects(f: Callable, args: Any, orbit: col.Orbit, scheme: col.Scheme) -> np.ndarray:
    """(N, SUBINTERVALS, n): the running defect D_j(s) = x(t_j + s h_j) - x(t_j) - T int_{t_j}^{t_j + s h_j} f dt
    at s = 1/S, 2/S, ..., 1 on each interval, by the finer quadrature (module docstring), state units; the last
    is the defect delta_j.  ``f(x, lam, args)`` is the problem's vector field."""
    B, w, E = (jnp.asarray(a, orbit.xm.dtype) for a in _defect_rule(scheme))
    return np.asarray(_running(f, args, orbit.nodes(), jnp.diff(orbit.mesh), orbit.T, orbit.lam, B, w, E), float)


def defect_errors(f: Callable, args: Any, orbit: col.Orbit, scheme: col.Scheme) -> np.ndarray:
    """(N, n): |delta_j|, the defect of the collocation equations on each interval (per component, state units)."""
    return np.abs(running_defects(f, args, orbit, scheme)[:, -1])


def error_estimate(orbit: col.Orbit, scheme: col.Scheme, f: Callable | None = None, args: Any = None) -> float:
    """The a-posteriori accuracy of a collocation orbit relative to ``1 + max |x|``: the largest interval error
    (:func:`interval_errors`) or, given the vector field ``f``, the larger of that and the defect estimate
    max_c (sum_j |delta_j,c| + max_{j,s} |D_j,c(s)|) (:func:`running_defects`, module docstring), which sees
    kinks of f and the error between the nodes where the interpolation estimate falls short.  Infinite where f is
    NaN or inf at the quadrature points (an orbit through a region where the field is undefined is not
    resolved, and a NaN would pass every comparison with a tolerance); a region narrower than their spacing can
    be missed."""
    scale = 1.0 + float(np.max(np.abs(np.asarray(orbit.xm))))
    est = float(np.max(interval_errors(orbit, scheme)))
    if f is not None:
        D = np.abs(running_defects(f, args, orbit, scheme))
        inside = D[:, :-1].max(axis=(0, 1)) if D.shape[1] > 1 else 0.0
        defects = float(np.max(np.maximum(D[:, -1].sum(axis=0), inside)))
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
