r"""Adaptive collocation meshes: an a-posteriori error estimate per interval, and its equidistribution.

Why: a uniform mesh in the scaled time wastes intervals where the orbit moves slowly and starves the fast parts
(a relaxation oscillation, a cycle near a homoclinic or saddle-node-on-invariant-circle limit whose period grows
without bound, a bearing orbit with a kink where the film pressure is clipped).  There the trivial multiplier
can stay at 1 to rounding while the period is wrong in the fourth digit, so the mesh error must be estimated
on its own.

The orbit's error is estimated three ways, and :func:`error_estimate` reports the largest, relative to
``1 + max |x|`` (so on a field whose largest component is a velocity, that component sets the scale).  What is
estimated is the orbit's distance from the exact cycle: the cycle that satisfies the same phase and continuation
conditions, at the same lam away from folds.  It is measured below against the same cycle corrected on N = 512
intervals ("dist").  On a stable cycle that is about the orbit's error against a tight time integration from its
own first node ("ivp"); on an unstable one the time integration amplifies the orbit's error by the unstable
multiplier, up to 1e3x on the cases below, while the orbit stays close to the cycle.  Near a fold, or wherever a
multiplier approaches +1, the distance to the exact cycle at the same lam is larger by about 1/|1 - mu| (the
problem at fixed lam is ill-conditioned there); with the continuation condition the estimate measures the distance
across the branch, and special points carry their own estimate (``SpecialPoint.lam_error``).

1. Interpolation (the approach of AUTO's mesh adaptation).  On interval :math:`j` of width :math:`h_j` the
collocation solution is a polynomial of degree m; its m-th derivative :math:`d_j = \Delta^m U_j / (h_j/m)^m` is
constant there (:math:`\Delta^m`: the m-th difference of the m+1 equally spaced nodes).  The jumps of :math:`d`
between neighbouring intervals estimate the (m+1)-th derivative, :math:`e_j \approx |x^{(m+1)}|` on interval j,
and

.. math::  \varepsilon_j = \frac{h_j^{m+1}\, e_j}{(m+1)!} \max_{s \in [0,1]} \Big|\prod_{i=0}^{m} (s - i/m)\Big|

is the Lagrange remainder of interpolating at the m+1 equally spaced nodes (:func:`interval_errors`).  It assumes
a smooth field, and it drives the equidistribution below.  On a cycle near an infinite-period limit it agrees with
the true error within a factor of about 2 over periods from 3.6 to 58 (tests/cont/test_cont_mesh.py).  It is
blind to a kink of f inside an interval (the bearing's exact Gumbel condition max(p - 1, 0)), which the polynomial
smooths: on the kinked oscillator of the tests the true error was 12-25x this estimate at omega = 1, up to 100x
along its resonance branch.  It also falls short where the mesh barely resolves a fast stretch: 0.06-0.4x on van
der Pol (mu = 1, N = 16).

2. Propagated defects (:func:`propagated_errors`).  The running defect of interval j,

.. math::  D_j(s) = x(t_j + s h_j) - x(t_j) - T \int_{t_j}^{t_j + s h_j} f(x(t), \lambda)\, dt,

is evaluated at the interval's nodes by a finer quadrature (m + 2 Gauss-Legendre points on each node spacing,
:func:`running_defects`); at s = 1 it is the interval's defect :math:`\delta_j`.  The collocation equations make
the m-point quadrature of :math:`\delta_j` vanish, so :math:`\delta_j` is of order :math:`h^{2m+1}` where f(x(t))
is smooth and of order :math:`h^2` on an interval that holds a kink; inside the interval :math:`D_j` is of the
order of the interpolation error.  The orbit's error obeys the linearised equation forced by the derivative of
:math:`D_j` (the residual of the polynomials), so the defects are passed through the orbit's linearisation (the
Newton system the corrector has already factorised, :mod:`._linear`): each :math:`\delta_j`, spread evenly over its
interval, forces the periodic problem with the orbit's phase and continuation rows, and the rest of :math:`D_j`
goes through interval j's own collocation block only.  Where a component is slow the result is about the running
defect, added up along the orbit; where it is strongly damped (h |f_x| >> 1: the film modes) the implicit
collocation step damps its share, so that the estimate does not grow with the stiffness.  Summing
:math:`|\delta_j|` instead (session 9) ignored that damping and flagged good points: 28x to 1.3e4x the true error
on a component x' = -k (x - u^3) with k = 1e4; the running defect alone without the damping gave 400x.  Carrying
the defects from the first node as an initial-value problem (a first version of session 10) let them grow with an
unstable multiplier: 135x and 290x the distance on the reversed van der Pol cycle below (multiplier 7.9e7).

3. Mesh values with Gauss points (:func:`mesh_value_errors`).  A component with h |f_x| >> 1 is accurate at the
Gauss points, but the mesh value is the polynomial extrapolated from the last Gauss point to the interval's end,
and Gauss collocation does not damp what that extrapolation gets wrong (its stability function tends to
(-1)^m): the mesh values of such a component lose the method's order, and no defect shows it.  The polynomial
through the m Gauss-point values on each side of a mesh point gives an independent value there; where f is
smooth and slow the two agree to the accuracy of the Gauss-point values.  With Radau points the mesh point is a
collocation point and this term is zero.

Measured, estimate / dist (scripts quoted in the closing note of session 10):

- kinked oscillator, omega = 1, N = 16 / 32 / 64: 0.80 / 0.79 / 0.92 (the interpolation estimate alone: 0.04 /
  0.05 / 0.09);
- van der Pol, mu = 1, N = 16: 0.80 (Gauss), 0.71 (Radau);
- van der Pol reversed in time (unstable, multipliers 1.2e3 at mu = 1 and 7.9e7 at mu = 2), m = 4, Gauss and
  Radau: 0.84-1.05 at N = 16, 32, 128;
- a strongly damped component x' = -k (x - u^3), k = 1e4, driven by a unit-circle oscillator: Radau m = 4, N = 16:
  0.81; Radau m = 2, N = 32: 0.71; Gauss m = 2 and m = 4, N = 32: 1.02 and 1.00 (the third estimate);
- the cycle near the infinite-period limit, T = 3.6 / 40 / 100 / 140, adapted mesh (against ivp): 1.34 / 0.92 /
  0.79 / 0.69;
- the GFB against the orbit on N = 128: 16x2 at Omega_bar 0.38, N = 16 / 32: 0.84 / 1.43; 48x8 at 0.95,
  N = 16 / 32: 0.89 / 0.72 (the summed defects of session 9: 2.5 / 1.3 and 3.6 / 2.8);
- a fresh-user review of the first version tried other kinked and discontinuous fields (|x|, several kinks per
  period, a relay sign(v), a dead zone), stiffness off the diagonal of f_x, adapted meshes and coarse N: 0.45-2.7
  on stable cycles; a stiff contact spring with Radau points, m = 2, was 0.2-0.3x at N = 64-128 (true error
  6.7e-3, flagged all the same).

Cost per recorded point: one evaluation of f at N m (m + 2) points, one solve of the Newton system and N block
solves, all on interval factorisations: with the sparse solver those the corrector already has, and the solve a
GMRES of about 16 sweeps; with the dense one, LU factors of the N blocks made on the host and the reduced (n + 2)
system formed by one block sweep (:meth:`~._linear.Linearisation.host_solve`; the compiled condensation would
condense the whole system again, and compile again for every new shape).

Limits.  The second and third estimates are evaluated at the nodes; between the nodes only the first looks, so an
error that peaks between the nodes of a barely resolved stretch is seen at the nearest node (van der Pol above:
0.7-0.8).  The estimate is not conservative: most factors above are below 1, and a point with an error a little
above mesh_tol can pass (the first review found |x|-kinked orbits 1.0-1.8e-4 from the exact flow unflagged; a
second review of the final version, 34 cases, none more than 1e-4 from its cycle, the closest flagged with a 4 %
margin).

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
from ._linear import DenseCondensation
from ._newton import LinearSolveError
from ._problem import CycleProblem

__all__ = ["interval_errors", "mesh_value_errors", "running_defects", "running_defects_linear", "defect_errors",
           "propagated_errors", "error_estimate", "equidistributed_mesh", "halved_mesh",
           "remesh"]

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


def mesh_value_errors(orbit: col.Orbit, scheme: col.Scheme) -> np.ndarray:
    """(N, n): at each mesh point t_{j+1} (j = 0..N-1), the distance of the orbit's value from the polynomial
    through the m collocation-point values of the interval before it and the m of the interval after it
    (periodic), state units (module docstring).  Zero for Radau points, whose last collocation point is the
    mesh point."""
    if scheme.kind == "radau":
        return np.zeros((orbit.N, orbit.n))
    U = np.asarray(orbit.nodes(), float)
    h = np.diff(np.asarray(orbit.mesh, float))
    S = np.einsum("ki,jin->jkn", scheme.l, U)  # (N, m, n): the values at the collocation points
    # the times of the 2m points relative to the mesh point between them, and their Lagrange basis there
    t = np.concatenate([(scheme.points - 1.0)[None, :] * h[:, None], scheme.points[None, :] * np.roll(h, -1)[:, None]],
                       axis=1)  # (N, 2m)
    others = ~np.eye(t.shape[1], dtype=bool)
    ratio = np.where(others, -t[:, None, :] / np.where(others, t[:, :, None] - t[:, None, :], 1.0), 1.0)
    weights = np.prod(ratio, axis=2)  # (N, 2m): prod over b != a of (0 - t_b) / (t_a - t_b)
    near = np.concatenate([S, np.roll(S, -1, axis=0)], axis=1)  # (N, 2m, n)
    return np.abs(np.einsum("ja,jan->jn", weights, near) - U[:, -1])


@functools.lru_cache(maxsize=None)
def _running_rule(scheme: col.Scheme) -> tuple[np.ndarray, np.ndarray]:
    """(B, w): the Lagrange basis of the nodes at m + 2 Gauss-Legendre points on each of the m node spacings of
    [0, 1], (m (m+2), m+1), and the weights of those points for the integral over their own spacing, (m+2,)."""
    m = scheme.m
    g, w = np.polynomial.legendre.leggauss(m + 2)
    pts = ((np.arange(m)[:, None] + 0.5 * (g[None, :] + 1.0)) / m).ravel()
    return scheme.basis_at(pts), 0.5 * w / m


def _defect(U: jax.Array, F: jax.Array, h: jax.Array, T: jax.Array, w: jax.Array) -> jax.Array:
    """The running defect (N, m+1, n) of node values U (N, m+1, n) against integrand values F (N, m (m+2), n) at
    the quadrature points of :func:`_running_rule`."""
    N, m1, n = U.shape
    integral = T * h[:, None, None] * jnp.cumsum(jnp.einsum("q,jiqn->jin", w, F.reshape(N, m1 - 1, -1, n)), axis=1)
    D = U[:, 1:] - U[:, :1] - integral
    return jnp.concatenate([jnp.zeros_like(D[:, :1]), D], axis=1)


@functools.partial(jax.jit, static_argnums=(0,))
def _running(f: Callable, args: Any, U: jax.Array, h: jax.Array, T: jax.Array, lam: jax.Array,
             B: jax.Array, w: jax.Array) -> jax.Array:
    return _defect(U, col._f_batched(f, jnp.einsum("qi,jin->jqn", B, U), lam, args), h, T, w)


@functools.partial(jax.jit, static_argnums=(0,))
def _running_linear(f: Callable, args: Any, U: jax.Array, Y: jax.Array, h: jax.Array, T: jax.Array,
                    lam: jax.Array, B: jax.Array, w: jax.Array) -> jax.Array:
    X, Yq = jnp.einsum("qi,jin->jqn", B, U), jnp.einsum("qi,bjin->bjqn", B, Y)

    def at(x, ys):  # f_x(x) y for the b directions ys (b, n): one linearisation per point
        return jax.vmap(jax.linearize(lambda z: f(z, lam, args), x)[1])(ys)
    F = jax.vmap(jax.vmap(at, in_axes=(0, 1), out_axes=1), in_axes=(0, 1), out_axes=1)(X, Yq)  # (b, N, Q, n)
    return jax.vmap(lambda y, g: _defect(y, g, h, T, w))(Y, F)


def running_defects(f: Callable, args: Any, orbit: col.Orbit, scheme: col.Scheme) -> np.ndarray:
    """(N, m+1, n): the running defect D_j(s_i) of each interval at its nodes (module docstring), state units;
    ``D[:, 0]`` is 0 and ``D[:, m]`` the interval's defect.  ``f(x, lam, args)`` is the problem's vector field."""
    B, w = _running_rule(scheme)
    U = orbit.nodes()
    return np.asarray(_running(f, args, U, jnp.diff(orbit.mesh), orbit.T, orbit.lam, jnp.asarray(B, U.dtype),
                               jnp.asarray(w, U.dtype)), float)


def running_defects_linear(f: Callable, args: Any, orbit: col.Orbit, Y: np.ndarray, scheme: col.Scheme
                           ) -> np.ndarray:
    """(b, N, m+1, n): the running defects of b solutions Y (b, N, m+1, n) (node values) of the orbit's
    variational equation y' = T f_x(x(t), lam) y, by the quadrature of :func:`running_defects`."""
    B, w = _running_rule(scheme)
    U = orbit.nodes()
    return np.asarray(_running_linear(f, args, U, jnp.asarray(Y, U.dtype), jnp.diff(orbit.mesh), orbit.T,
                                      orbit.lam, jnp.asarray(B, U.dtype), jnp.asarray(w, U.dtype)), float)


def defect_errors(f: Callable, args: Any, orbit: col.Orbit, scheme: col.Scheme) -> np.ndarray:
    """(N, n): |delta_j|, the defect of the collocation equations over each interval (module docstring)."""
    return np.abs(running_defects(f, args, orbit, scheme)[:, -1])


def propagated_errors(f: Callable, args: Any, orbit: col.Orbit, scheme: col.Scheme, lin: Any = None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """The orbit's distance from the exact cycle, from its defects carried through the linearisation (module
    docstring): (mesh values (N+1, n), interior nodes (N, m-1, n)), state units; NaN where f is not finite at the
    quadrature points or the linear solve fails.  ``lin``: the orbit's :class:`~._linear.Linearisation`; its
    constraint rows (phase, continuation) say which exact cycle the orbit is compared with.  Default: a dense one
    made here at fixed lam (the exact cycle at the same lam), which costs O(N (mn)^3)."""
    D = running_defects(f, args, orbit, scheme)
    N, n = orbit.N, orbit.n
    failed = np.full((N + 1, n), np.nan), np.full((N, scheme.m - 1, n), np.nan)
    if not np.all(np.isfinite(D)):
        return failed
    if lin is None:
        lin = DenseCondensation().bind(CycleProblem(f, n, args), scheme).linearise(orbit)
    delta = D[:, -1]
    # From one interval to the next only its defect is carried, as a forcing spread evenly over the interval, by
    # the periodic problem (the orbit's own Newton system): unstable directions do not grow from a start point.
    try:
        e = lin.host_solve(np.repeat(delta[:, None, :], scheme.m, axis=1), np.zeros(n), np.zeros(2))
    except LinearSolveError:
        return failed
    # Inside the interval, the rest of the running defect, through the interval's own block: the collocation
    # right-hand sides whose polynomial (0 at the first node) takes its values at the other nodes.  Its value at
    # the interval's end is dropped: there the integral by the finer quadrature (the defect) is the better one.
    rest = D - scheme.nodes[None, :, None] * delta[:, None, :]
    local = lin.local_solves(np.einsum("ki,jin->jkn", scheme.dl, rest).reshape(N, -1))
    return np.asarray(e.xm, float), np.asarray(e.xi, float) + local


def error_estimate(orbit: col.Orbit, scheme: col.Scheme, f: Callable | None = None, args: Any = None,
                   lin: Any = None) -> float:
    """The orbit's estimated distance from the exact cycle relative to ``1 + max |x|`` (module docstring): the
    largest of the interval errors (:func:`interval_errors`), the Gauss mesh-value errors
    (:func:`mesh_value_errors`) and, given the vector field ``f``, the propagated errors
    (:func:`propagated_errors`, with the orbit's linearisation ``lin`` where given; the second and third see kinks
    of f, errors between the nodes of a barely resolved stretch and strongly damped components).  Infinite where
    f is NaN or inf at the quadrature points, or the linear solve fails (an orbit through a region where the field
    is undefined is not resolved, and a NaN would pass every comparison with a tolerance); a region narrower than
    their spacing can be missed."""
    scale = 1.0 + float(np.max(np.abs(np.asarray(orbit.xm))))
    # np.max, not max(): a NaN must survive
    est = float(np.max([np.max(interval_errors(orbit, scheme)), np.max(mesh_value_errors(orbit, scheme))]))
    if f is not None:
        xs, ws = propagated_errors(f, args, orbit, scheme, lin)
        prop = max(float(np.max(np.abs(xs))), float(np.max(np.abs(ws), initial=0.0)))
        est = est if prop <= est else prop  # max() would drop a NaN
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


def halved_mesh(mesh: Any) -> np.ndarray:
    """(2N+1,): every interval of ``mesh`` (N+1,) split at its midpoint."""
    mesh = np.asarray(mesh, float)
    return np.sort(np.concatenate([mesh, 0.5 * (mesh[:-1] + mesh[1:])]))


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
