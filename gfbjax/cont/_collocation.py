r"""Periodic orbits by orthogonal (Gauss) collocation with condensation of parameters.

Boundary-value problem (Papafragkos et al. 2022, App. A1, Eq. (27)-(29))
-------------------------------------------------------------------------
A periodic orbit of the autonomous field ``f(x, lam, args)`` with unknown period
``T`` is sought on the scaled time ``t in [0, 1]``:

.. math::

    x'(t) = T\, f(x(t), \lambda)                        \quad (27)\\
    x(0) - x(1) = 0                                      \quad (28)\\
    \int_0^1 \langle x(t) - \hat x(t), \hat x'(t)\rangle\,dt = 0   \quad (29)

(29) is the integral phase condition against a reference orbit :math:`\hat x`
(usually the previous point of the branch).  During continuation one more
scalar equation closes the system, either the pseudo-arclength condition
(Eq. (30))

.. math::

    \int_0^1 \langle x - x_0, \dot x_0\rangle dt + (T-T_0)\dot T_0
    + (\lambda-\lambda_0)\dot\lambda_0 - \Delta s = 0

or, for natural-parameter continuation, :math:`\lambda - \lambda_{target} = 0`
(the same equation with :math:`\dot x_0 = 0, \dot T_0 = 0, \dot\lambda_0 = 1`).

Discretisation
--------------
Mesh :math:`0=\tau_0<\dots<\tau_N=1`, :math:`h_j=\tau_{j+1}-\tau_j`.  On each
interval the orbit is a polynomial of degree ``m`` in Lagrange form on the
``m+1`` equally spaced nodes :math:`\tau_j + h_j i/m`, ``i = 0..m``.  The
collocation equations are imposed at the ``m`` Gauss-Legendre points
:math:`z_k` of every interval (scaled by :math:`h_j`):

.. math::

    r_{jk} = \sum_i \ell_i'(z_k)\,u_{j,i} - h_j T f\Big(\sum_i \ell_i(z_k) u_{j,i}, \lambda\Big) = 0 .

Unknown layout (``Orbit`` and the flat vector used by the dense reference
path)::

    [ x_0, ..., x_N            mesh-node values,  (N+1)*n   (x_N = x_0 by (28))
      u_{0,1..m-1}, ...,        interior node values, N*(m-1)*n
      T, lam ]

Condensation of parameters (AUTO-07p; paper Eq. (45)-(47))
------------------------------------------------------------
On interval ``j`` the linearised collocation equations read
:math:`A_L\delta x_j + A_I \delta w_j + A_R\delta x_{j+1} + B_p\delta p = c_j`
with :math:`A_I\in R^{mn\times(m-1)n}` and :math:`p=(T,\lambda)`.  A complete
QR factorisation :math:`A_I = [Q_1\,Q_2] [R_1; 0]` splits them into
(m-1)n equations that give the interior unknowns

.. math:: \delta w_j = R_1^{-1}Q_1^T(c_j - A_L\delta x_j - A_R\delta x_{j+1} - B_p\delta p)

and ``n`` *condensed* equations

.. math:: C_j\delta x_j + D_j\delta x_{j+1} + G_j\delta p = Q_2^T c_j,
          \qquad C_j = Q_2^TA_L,\ D_j = Q_2^TA_R,\ G_j = Q_2^TB_p .

This is done for all intervals at once with batched dense algebra.  The
condensed system is block bidiagonal in the mesh values, bordered by the
periodicity rows and the two scalar rows (phase, continuation).  It is solved
by a sequential block QR elimination of ``x_1 .. x_{N-1}`` (``lax.scan``),
carrying the two bordering rows along, followed by a dense (2n+2) solve for
``(x_0, x_N, T, lam)`` and back-substitution: O(N n^3) time, O(N n^2) memory.
The per-interval transfer matrices :math:`\Gamma_j = -D_j^{-1}C_j` map
:math:`\delta x_j \mapsto \delta x_{j+1}`; their product is the monodromy
matrix (see ``_floquet.py``).
"""
from __future__ import annotations

import functools
from typing import Any, Callable, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.linalg import solve_triangular

from ._scalars import float_array, strong

VectorField = Callable[[jax.Array, jax.Array, Any], jax.Array]


# --------------------------------------------------------------------------
# Collocation scheme constants
# --------------------------------------------------------------------------
def _lagrange_matrices(nodes: np.ndarray, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Values ``l[k, i] = L_i(pts_k)`` and derivatives ``dl[k, i] = L_i'(pts_k)``."""
    p = len(nodes)
    l = np.ones((len(pts), p))
    dl = np.zeros((len(pts), p))
    for i in range(p):
        others = [nodes[q] for q in range(p) if q != i]
        denom = np.prod([nodes[i] - o for o in others])
        l[:, i] = np.prod([pts - o for o in others], axis=0) / denom
        for r in range(len(others)):
            terms = [pts - o for q, o in enumerate(others) if q != r]
            dl[:, i] += (np.prod(terms, axis=0) if terms else np.ones_like(pts)) / denom
    return l, dl


#: Collocation points of a scheme: ``"gauss"`` (Gauss-Legendre, order 2m at the mesh points, AUTO's and the paper's
#: choice) or ``"radau"`` (right Radau, order 2m - 1, L-stable).
COLLOCATION_POINTS = ("gauss", "radau")


class Scheme:
    """Constants of the degree-``m`` collocation scheme on the unit interval.

    ``nodes``: m+1 equally spaced Lagrange nodes; ``points``/``weights``: the m collocation points on [0, 1] and
    the weights of the quadrature on them; ``l``/``dl``: Lagrange basis values and derivatives at the collocation
    points, shape (m, m+1).  ``kind``: one of :data:`COLLOCATION_POINTS`.

    Why two kinds.  Gauss points give the highest order (2m at the mesh points), but the scheme is only A-stable:
    its stability function R(z) (one interval of y' = lam y, z = h lam) tends to (-1)^m as z -> -inf.  A mode much
    faster than an interval (|h lam| >> 1) therefore gets a Floquet multiplier near prod R(h lam), close to the
    unit circle, where the exact one, exp(lam T), is zero.  The orbit is unaffected (such modes are not excited),
    the multipliers are not: on the GFB reference grid at N = 16 the film's fast modes (lam ~ -600) show up at
    Omega_bar 0.3 as a band of multipliers at |mu| 0.37-0.45 (exact ~0) that approaches the circle at low speed.
    Radau points give an L-stable scheme (R(-inf) = 0): those multipliers come out near zero, at one order less
    accuracy.  Neither cures a mesh too coarse for a mode that oscillates within an interval (|h Im lam| ~ 1 or
    more): Gauss points keep its modulus roughly (|R| = 1 on the imaginary axis), Radau points damp it away.
    :meth:`stability` is R for either kind.
    """

    def __init__(self, m: int, kind: str = "gauss"):
        if not (isinstance(m, (int, np.integer)) and 2 <= m <= 7):
            raise ValueError(f"m (collocation points per interval) must be an int in [2, 7], got {m!r}")
        if kind not in COLLOCATION_POINTS:
            raise ValueError(f"collocation must be one of {COLLOCATION_POINTS}, got {kind!r}")
        self.m, self.kind = int(m), kind
        self.nodes = np.linspace(0.0, 1.0, m + 1)
        leg = np.polynomial.legendre.Legendre
        if kind == "gauss":
            g, w = np.polynomial.legendre.leggauss(m)
            self.points, self.weights = 0.5 * (g + 1.0), 0.5 * w
        else:  # right Radau: the zeros of P_m - P_{m-1} on [-1, 1], the last one at +1
            self.points = 0.5 * (np.sort((leg.basis(m) - leg.basis(m - 1)).roots().real) + 1.0)
            self.weights = self._integrals(1.0)
        self.l, self.dl = _lagrange_matrices(self.nodes, self.points)
        self._rk_matrix = self._integrals(self.points)  # A[i, j] = int_0^{c_i} L_j (the Runge-Kutta matrix)

    def _integrals(self, upper: Any) -> np.ndarray:
        """``out[..., j]``: the integral from 0 to ``upper`` of the Lagrange basis on the collocation points."""
        out = []
        for j in range(self.m):
            others = np.delete(self.points, j)
            c = np.polynomial.polynomial.polyfromroots(others) / np.prod(self.points[j] - others)
            out.append(np.polynomial.polynomial.polyval(upper, np.polynomial.polynomial.polyint(c)))
        return np.stack(out, -1)

    def stability(self, z: Any) -> np.ndarray:
        """R(z): the factor by which one interval of collocation multiplies the solution of y' = lam y, z = h lam
        (complex array in, same shape out).  exp(z) to the scheme's order for small |z|; for z -> -inf, (-1)^m
        (Gauss) or 0 (Radau)."""
        z = np.asarray(z, complex)
        A = self._rk_matrix
        flat = z.reshape(-1, 1, 1)
        stage = np.linalg.solve(np.eye(self.m) - flat * A, np.ones((flat.shape[0], self.m, 1)))[..., 0]
        return (1.0 + z.ravel() * (stage @ self.weights)).reshape(z.shape)

    def basis_at(self, pts: np.ndarray) -> np.ndarray:
        """Lagrange basis values at local points ``pts`` in [0,1], shape (len(pts), m+1)."""
        return _lagrange_matrices(self.nodes, np.asarray(pts, float))[0]

    # hash/eq so that jit caches on the scheme by value
    def __hash__(self) -> int:
        return hash(("Scheme", self.m, self.kind))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Scheme) and (other.m, other.kind) == (self.m, self.kind)


# --------------------------------------------------------------------------
# Orbit container
# --------------------------------------------------------------------------
class Orbit(eqx.Module):
    """Discrete periodic orbit.

    mesh: (N+1,) increasing, mesh[0]=0, mesh[-1]=1;  xm: (N+1, n) mesh-node
    values; xi: (N, m-1, n) interior node values;  T: period;  lam: parameter (both stored as strongly typed
    scalars, see :func:`._scalars.strong`).
    """

    mesh: jax.Array
    xm: jax.Array
    xi: jax.Array
    T: jax.Array
    lam: jax.Array

    def __init__(self, mesh: Any, xm: Any, xi: Any, T: Any, lam: Any):
        self.mesh, self.xm, self.xi = float_array(mesh), float_array(xm), float_array(xi)
        self.T, self.lam = strong(T), strong(lam)

    @property
    def N(self) -> int:
        return self.xi.shape[0]

    @property
    def n(self) -> int:
        return self.xm.shape[1]

    def nodes(self) -> jax.Array:
        """Per-interval node values, shape (N, m+1, n)."""
        return _nodes(self.xm, self.xi)

    def to_flat(self) -> jax.Array:
        return _flat(self.xm, self.xi, self.T, self.lam)

    def from_flat(self, v: jax.Array) -> "Orbit":
        a = self.xm.size
        b = a + self.xi.size
        return Orbit(self.mesh, v[:a].reshape(self.xm.shape), v[a:b].reshape(self.xi.shape), v[b], v[b + 1])

    def __add__(self, other: "Orbit") -> "Orbit":
        return Orbit(self.mesh, self.xm + other.xm, self.xi + other.xi, self.T + other.T, self.lam + other.lam)

    def scale(self, c: Any) -> "Orbit":
        return Orbit(self.mesh, c * self.xm, c * self.xi, c * self.T, c * self.lam)


# jitted, like the functionals below: called from the host at every step, where op-by-op dispatch is the cost
@jax.jit
def _nodes(xm: jax.Array, xi: jax.Array) -> jax.Array:
    return jnp.concatenate([xm[:-1, None], xi, xm[1:, None]], axis=1)


@jax.jit
def _flat(xm: jax.Array, xi: jax.Array, T: jax.Array, lam: jax.Array) -> jax.Array:
    return jnp.concatenate([xm.ravel(), xi.ravel(), jnp.stack([T, lam])])


@jax.jit
def add(a: Orbit, b: Orbit) -> Orbit:
    """a + b (same mesh), compiled."""
    return a + b


@jax.jit
def scaled(a: Orbit, c: Any) -> Orbit:
    """c a, compiled."""
    return a.scale(c)


def uniform_mesh(N: int) -> np.ndarray:
    if N < 2:
        raise ValueError(f"N (mesh intervals) must be >= 2, got {N}")
    return np.linspace(0.0, 1.0, N + 1)


def node_times(mesh: Any, scheme: Scheme) -> np.ndarray:
    """Scaled times of all nodes, shape (N, m+1)."""
    mesh = np.asarray(mesh, float)
    h = np.diff(mesh)
    return mesh[:-1, None] + h[:, None] * scheme.nodes[None, :]


def orbit_from_function(x_of_t: Callable[[np.ndarray], np.ndarray], T: float, lam: float,
                        scheme: Scheme, mesh: Any) -> Orbit:
    """Sample ``x_of_t(t)`` (t in [0,1], vectorised, returns (len(t), n)) on the nodes."""
    mesh = np.asarray(mesh, float)
    t = node_times(mesh, scheme)
    N, mp1 = t.shape
    X = np.asarray(x_of_t(t.ravel()), float).reshape(N, mp1, -1)
    xm = np.concatenate([X[:, 0], X[-1:, -1]], axis=0)
    xm[-1] = xm[0]
    return Orbit(jnp.asarray(mesh), jnp.asarray(xm), jnp.asarray(X[:, 1:-1]),
                 jnp.asarray(float(T)), jnp.asarray(float(lam)))


def orbit_from_samples(t: np.ndarray, x: np.ndarray, T: float, lam: float, scheme: Scheme,
                       mesh: Any) -> Orbit:
    """Orbit from samples ``x[i] = x(t[i])`` over one period, ``t`` in [t0, t0+T].

    Periodic linear interpolation in the scaled time ``(t - t[0]) / T``.
    """
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    s = (t - t[0]) / T
    if s[-1] < 1.0 - 1e-12:
        s = np.append(s, 1.0)
        x = np.vstack([x, x[:1]])

    def x_of_t(tt):
        return np.stack([np.interp(np.mod(tt, 1.0), s, x[:, c]) for c in range(x.shape[1])], axis=1)

    return orbit_from_function(x_of_t, T, lam, scheme, mesh)


def evaluate(orbit: Orbit, scheme: Scheme, per_interval: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Evaluate the piecewise polynomial on ``per_interval`` points per interval.

    Returns scaled times (N*per_interval + 1,) and states (.., n).
    """
    loc = np.linspace(0.0, 1.0, per_interval, endpoint=False)
    B = scheme.basis_at(loc)
    U = np.asarray(orbit.nodes())
    X = np.einsum("qi,jin->jqn", B, U).reshape(-1, U.shape[-1])
    mesh = np.asarray(orbit.mesh)
    t = (mesh[:-1, None] + np.diff(mesh)[:, None] * loc[None]).ravel()
    return np.append(t, 1.0), np.vstack([X, np.asarray(orbit.xm[-1])[None]])


#: An orbit whose amplitude (:func:`amplitude`), or whose distance from its own half-period shift
#: (:func:`half_period_defect`), is at most this fraction of a reference orbit's has shrunk onto an equilibrium or
#: onto a cycle of half its period (:func:`shrunk`): a fold of cycles located at such a point is the family's end
#: at a Hopf or period-doubling point (:meth:`~._cycles.CycleCurve.family_ends`).  On a family born at such a point
#: the amplitude (distance) grows like sqrt|lam - lam_0|, so 1e-3 of the reference's is within ~1e-6 of the
#: reference's distance to that point.
AMPLITUDE_END = 1e-3


def amplitude(orbit: Orbit) -> np.ndarray:
    """The largest peak-to-peak value over the period among the components, at the mesh and interior nodes, in
    the states' units; a float for one orbit, shape (k,) for k orbits stacked on a leading axis (a vmapped
    correction's result)."""
    xm, xi = np.asarray(orbit.xm), np.asarray(orbit.xi)
    nodes = np.concatenate([xm, xi.reshape(*xi.shape[:-3], -1, xi.shape[-1])], axis=-2)
    return np.max(np.ptp(nodes, axis=-2), axis=-1)


def half_period_odd(orbit: Orbit) -> np.ndarray:
    """x(t) - x(t + 1/2) at the node times t (t in units of the period), shape (N (m+1), n), in the states'
    units: the part of the orbit that changes sign under a shift by half its period.  Zero for an orbit that
    repeats itself after half its period (a cycle of period T/2 traversed twice, and the constant orbit); it
    changes sign where a family passes through such an orbit (the small cycles near a Hopf point, the doubled ones
    near a period doubling: x = x_0 + eps w with w(t + 1/2) = -w(t), and eps changes sign).  One orbit."""
    mesh = np.asarray(orbit.mesh, float)
    U = np.asarray(orbit.nodes())  # (N, m+1, n)
    nodes = np.linspace(0.0, 1.0, U.shape[1])
    t = np.mod((mesh[:-1, None] + np.diff(mesh)[:, None] * nodes[None, :]).ravel() + 0.5, 1.0)
    j = np.clip(np.searchsorted(mesh, t, side="right") - 1, 0, len(mesh) - 2)
    B = _lagrange_matrices(nodes, (t - mesh[j]) / (mesh[j + 1] - mesh[j]))[0]
    return U.reshape(-1, U.shape[-1]) - np.einsum("qi,qin->qn", B, U[j])


def half_period_defect(orbit: Orbit) -> float:
    """The largest |x(t + 1/2) - x(t)| over the node times and the components (:func:`half_period_odd`)."""
    return float(np.max(np.abs(half_period_odd(orbit))))


def passed_through(a: Orbit, b: Orbit, step_tol: float) -> str | None:
    """Whether the family went from ``a`` to ``b`` (consecutive on a branch, phase aligned by the phase condition,
    on the same mesh) through an orbit that repeats itself after half its period: their :func:`half_period_odd`
    parts point in opposite directions (cosine below -1/2).  Such a step passed the point where the family was
    born and ran on along its mirror image, the same cycles shifted by half a period.  Then the kind of that point
    by what ``a`` is near: ``"equilibrium"`` (a Hopf point: the part even under the shift varies less than the
    odd part, as for small cycles x_0 + eps w + O(eps^2)) or ``"half period"`` (a period doubling), else None.
    No verdict (None) where either odd part is within :data:`COLLAPSE_TOLS` step tolerances of zero (a start at
    the Hopf or PD point itself: its odd part is interpolation noise) or the meshes differ."""
    if not np.array_equal(np.asarray(a.mesh), np.asarray(b.mesh)):
        return None
    da, db = half_period_odd(a), half_period_odd(b)
    floor = COLLAPSE_TOLS * step_tol * max(state_scale(a), state_scale(b))
    if da.shape != db.shape or np.max(np.abs(da)) <= floor or np.max(np.abs(db)) <= floor:
        return None
    if float(np.vdot(da, db)) >= -0.5 * float(np.linalg.norm(da) * np.linalg.norm(db)):
        return None
    even = np.asarray(a.nodes()).reshape(da.shape) - 0.5 * da  # (x(t) + x(t + 1/2)) / 2
    return "equilibrium" if np.max(np.ptp(even, axis=0)) < np.max(np.ptp(da, axis=0)) else "half period"


def state_scale(orbit: Orbit) -> float:
    """1 + max|x| over the nodes: the scale of the Newton step tolerance (a step is small when |dx| <= tol times
    this)."""
    return 1.0 + max(float(np.max(np.abs(np.asarray(orbit.xm)))), float(np.max(np.abs(np.asarray(orbit.xi)))))


def shrunk(orbit: Orbit, reference: Orbit) -> str | None:
    """What ``orbit`` has shrunk onto against ``reference``, or None: ``"equilibrium"`` when its amplitude is at
    most :data:`AMPLITUDE_END` of the reference's (which moves), ``"half period"`` when its distance from its own
    half-period shift (:func:`half_period_defect`) is at most that fraction of the reference's."""
    a0 = float(amplitude(reference))
    if a0 > 0.0 and float(amplitude(orbit)) <= AMPLITUDE_END * a0:
        return "equilibrium"
    d0 = half_period_defect(reference)
    if d0 > 0.0 and half_period_defect(orbit) <= AMPLITUDE_END * d0:
        return "half period"
    return None


#: A converged orbit within this many Newton step tolerances (times 1 + max|x|) of the constant orbit, or of its
#: own half-period shift, is that orbit as far as the corrector can tell (the collapsed corrections seen end at
#: rounding level, 1e-15 of their states, and at most ~1e-10 absolute).
COLLAPSE_TOLS = 10.0


def collapsed(orbit: Orbit, guess: Orbit, step_tol: float) -> str | None:
    """What ``orbit``, a converged correction of ``guess`` with Newton step tolerance ``step_tol``, is instead of a
    cycle of period T, or None when it is one: ``"equilibrium"`` (the constant orbit) or ``"half period"`` (a
    cycle of period T/2 traversed twice), when it has :func:`shrunk` onto that against the guess and is that
    orbit to within :data:`COLLAPSE_TOLS` step tolerances.  A constant orbit solves the collocation equations
    (27)-(28) with any period, and a cycle of period T/2 traversed twice solves them with period T; the phase
    condition (29) does not exclude them, so Newton can converge there from a guess near (or past) the point where
    a family shrinks onto them: a Hopf point, where cycles shrink to an equilibrium, and a period doubling, where
    the doubled cycles shrink onto the cycle of half their period.  A genuine cycle far smaller than its guess
    (a correction from a distant guess) is not collapsed."""
    onto = shrunk(orbit, guess)
    if onto is None:
        return None
    left = float(amplitude(orbit)) if onto == "equilibrium" else half_period_defect(orbit)
    return onto if left <= COLLAPSE_TOLS * step_tol * state_scale(orbit) else None


# --------------------------------------------------------------------------
# Functionals:  integral inner products  int_0^1 <a(t), b(t)> dt
# --------------------------------------------------------------------------
def _at_gauss(U: jax.Array, scheme: Scheme) -> jax.Array:
    return jnp.einsum("ki,jin->jkn", scheme.l, U)


def integral_coeffs(g: jax.Array, h: jax.Array, scheme: Scheme) -> jax.Array:
    """Coefficients c (N, m+1, n) with  int <x, g> dt = sum c * nodes(x).

    ``g`` is given at the Gauss points (N, m, n); Gauss quadrature is exact for
    the piecewise polynomial products that occur.
    """
    return jnp.einsum("j,k,ki,jkn->jin", h, scheme.weights, scheme.l, g)


# jitted: the continuation loop calls these from the host at every step, where op-by-op dispatch of the einsums
# cost ~2.5 ms a call (the larger part of a point's cost at small n)
@functools.partial(jax.jit, static_argnums=(2,))
def inner(a: Orbit, b: Orbit, scheme: Scheme) -> jax.Array:
    """<a, b> = int_0^1 <a(t), b(t)> dt + a.T b.T + a.lam b.lam  (norm of Eq. (30))."""
    h = jnp.diff(a.mesh)
    ga = _at_gauss(a.nodes(), scheme)
    gb = _at_gauss(b.nodes(), scheme)
    return jnp.einsum("j,k,jkn,jkn->", h, scheme.weights, ga, gb) + a.T * b.T + a.lam * b.lam


@functools.partial(jax.jit, static_argnums=(1,))
def l2_norm(orbit: Orbit, scheme: Scheme) -> jax.Array:
    """sqrt( int_0^1 |x(t)|^2 dt )."""
    h = jnp.diff(orbit.mesh)
    g = _at_gauss(orbit.nodes(), scheme)
    return jnp.sqrt(jnp.einsum("j,k,jkn,jkn->", h, scheme.weights, g, g))


class Constraint(eqx.Module):
    """Data of the two scalar rows: phase reference (29) and continuation row (30).

    Continuation row: int <x - base.x, v.x> + (T - base.T) v.T + (lam - base.lam) v.lam - ds.
    """

    ref: Orbit
    base: Orbit
    v: Orbit
    ds: jax.Array

    def __init__(self, ref: Orbit, base: Orbit, v: Orbit, ds: Any):
        self.ref, self.base, self.v, self.ds = ref, base, v, strong(ds)


def natural_constraint(ref: Orbit, lam_target: Any) -> Constraint:
    """Continuation row lam - lam_target = 0 (natural parameter / fixed lam)."""
    zero = ref.scale(0.0)
    v = Orbit(ref.mesh, zero.xm, zero.xi, jnp.asarray(0.0), jnp.asarray(1.0))
    base = Orbit(ref.mesh, ref.xm, ref.xi, ref.T, jnp.asarray(lam_target, dtype=ref.xm.dtype))
    return Constraint(ref, base, v, jnp.asarray(0.0))


def palc_constraint(base: Orbit, tangent: Orbit, ds: Any, ref: Orbit | None = None) -> Constraint:
    """Pseudo-arclength row (30) around ``base`` along ``tangent``."""
    return Constraint(base if ref is None else ref, base, tangent, jnp.asarray(ds, dtype=base.xm.dtype))


def functional_coeffs(orbit: Orbit, con: Constraint, scheme: Scheme):
    """Node coefficients (2, N, m+1, n), parameter coefficients (2, 2) and values (2,)."""
    h = jnp.diff(orbit.mesh)
    Uref = con.ref.nodes()
    dref = jnp.einsum("ki,jin->jkn", scheme.dl, Uref) / h[:, None, None]  # x_hat'(t)
    c_phase = integral_coeffs(dref, h, scheme)
    c_cont = integral_coeffs(_at_gauss(con.v.nodes(), scheme), h, scheme)
    U = orbit.nodes()
    phase = jnp.sum(c_phase * (U - Uref))
    cont = (jnp.sum(c_cont * (U - con.base.nodes())) + (orbit.T - con.base.T) * con.v.T
            + (orbit.lam - con.base.lam) * con.v.lam - con.ds)
    cp = jnp.array([[0.0, 0.0], [con.v.T, con.v.lam]], dtype=U.dtype)
    return jnp.stack([c_phase, c_cont]), cp, jnp.stack([phase, cont])


# --------------------------------------------------------------------------
# Residual and linearisation
# --------------------------------------------------------------------------
def _f_batched(f: VectorField, X: jax.Array, lam: jax.Array, args: Any) -> jax.Array:
    g = jax.vmap(lambda x: f(x, lam, args))
    return jax.vmap(g)(X)


def collocation_residual(f: VectorField, args: Any, orbit: Orbit, scheme: Scheme) -> jax.Array:
    """r_{jk} = sum_i dl_{ki} u_{j,i} - h_j T f(x_{jk}, lam), shape (N, m, n)."""
    U = orbit.nodes()
    h = jnp.diff(orbit.mesh)
    X = _at_gauss(U, scheme)
    dU = jnp.einsum("ki,jin->jkn", scheme.dl, U)
    return dU - (h * orbit.T)[:, None, None] * _f_batched(f, X, orbit.lam, args)


def residual(f: VectorField, args: Any, orbit: Orbit, con: Constraint, scheme: Scheme):
    """All residuals: (collocation (N,m,n), periodicity (n,), scalar rows (2,))."""
    rc = collocation_residual(f, args, orbit, scheme)
    rper = orbit.xm[0] - orbit.xm[-1]
    _, _, rs = functional_coeffs(orbit, con, scheme)
    return rc, rper, rs


class Blocks(NamedTuple):
    """Per-interval collocation Jacobian blocks (N leading axis)."""

    AL: jax.Array  # (N, mn, n)
    AI: jax.Array  # (N, mn, (m-1)n)
    AR: jax.Array  # (N, mn, n)
    Bp: jax.Array  # (N, mn, 2)  columns d/dT, d/dlam


def collocation_blocks(f: VectorField, args: Any, orbit: Orbit, scheme: Scheme) -> Blocks:
    """Jacobian of the collocation equations, per interval.

    A[k, i] = dl_{ki} I - h T l_{ki} J(x_{jk}), with J = df/dx by ``jax.jacfwd``
    vmapped over all N*m Gauss points.
    """
    m, n, N = scheme.m, orbit.n, orbit.N
    U = orbit.nodes()
    h = jnp.diff(orbit.mesh)
    X = _at_gauss(U, scheme)
    jac = jax.jacfwd(lambda x, lam: f(x, lam, args), argnums=(0, 1))
    Fx = jax.vmap(jax.vmap(lambda x: f(x, orbit.lam, args)))(X)
    J, Jl = jax.vmap(jax.vmap(lambda x: jac(x, orbit.lam)))(X)  # (N,m,n,n), (N,m,n)
    eye = jnp.eye(n, dtype=U.dtype)
    hT = (h * orbit.T)[:, None, None, None, None]
    A = (scheme.dl[None, :, None, :, None] * eye[None, None, :, None, :]
         - hT * scheme.l[None, :, None, :, None] * J[:, :, :, None, :])
    A = A.reshape(N, m * n, (m + 1) * n)
    Bp = jnp.stack([-(h[:, None, None] * Fx), -(h * orbit.T)[:, None, None] * Jl], axis=-1)
    Bp = Bp.reshape(N, m * n, 2)
    return Blocks(A[:, :, :n], A[:, :, n:m * n], A[:, :, m * n:], Bp)


class Condensed(NamedTuple):
    """Condensed per-interval equations C dx_j + D dx_{j+1} + G dp = cc and the
    interior recovery dw = w0 + WL dx_j + WR dx_{j+1} + Wp dp."""

    C: jax.Array
    D: jax.Array
    G: jax.Array
    cc: jax.Array
    w0: jax.Array
    WL: jax.Array
    WR: jax.Array
    Wp: jax.Array


def condense(blocks: Blocks, c: jax.Array) -> Condensed:
    """Condensation of parameters (paper Eq. (45)-(46)), batched over intervals.

    ``c``: right-hand sides of the collocation rows, shape (N, mn, k).
    """
    AL, AI, AR, Bp = blocks
    k = AI.shape[-1]  # (m-1) n
    Q, R = jnp.linalg.qr(AI, mode="complete")
    R1 = R[:, :k, :]
    Qt = jnp.swapaxes(Q, -1, -2)
    Q1t, Q2t = Qt[:, :k], Qt[:, k:]
    # One triangular solve for all four right-hand sides: four independent batched LAPACK calls can run
    # concurrently and then dead-lock jaxlib's CPU kernels, which wait on the same thread pool they schedule to.
    n, kc = AL.shape[-1], c.shape[-1]
    W = jax.vmap(lambda R_, B_: solve_triangular(R_, B_, lower=False))(
        R1, Q1t @ jnp.concatenate([c, AL, AR, Bp], axis=-1))
    w0, WL, WR, Wp = W[..., :kc], -W[..., kc:kc + n], -W[..., kc + n:kc + 2 * n], -W[..., kc + 2 * n:]
    return Condensed(Q2t @ AL, Q2t @ AR, Q2t @ Bp, Q2t @ c, w0, WL, WR, Wp)


def _dot2(A: jax.Array, b: jax.Array) -> jax.Array:
    """A @ b for a contraction over the 2 parameters (T, lam), written elementwise.

    Works around an XLA:CPU hang (jax 0.10) observed for the broadcast dot
    (N, k, 2) @ (2, 2) inside this program."""
    return A[..., :, 0:1] * b[0] + A[..., :, 1:2] * b[1]


def _solve_reduced(cond: Condensed, Phi: jax.Array, phip: jax.Array, fb: jax.Array, cper: jax.Array):
    """Solve the bordered block-bidiagonal reduced system.

    Rows:  C_j dx_j + D_j dx_{j+1} + G_j dp = cc_j  (j=0..N-1);
           dx_0 - dx_N = cper;   sum_j Phi_j dx_j + phip dp = fb  (2 rows).
    Sequential block-QR elimination of dx_1..dx_{N-1} with ``lax.scan``.
    Right-hand sides carry a trailing axis k (several systems at once).
    """
    C, D, G, cc = cond.C, cond.D, cond.G, cond.cc
    n = C.shape[-1]

    def step(carry, xs):
        A0, Aj, Ap, b, F0, Fj, Fp, fbb = carry
        Cj, Dj, Gj, ccj, Phinext = xs
        Mj = jnp.concatenate([Aj, Cj], axis=0)
        Q, R = jnp.linalg.qr(Mj, mode="complete")
        Qt = Q.T
        z = jnp.zeros_like(A0)
        X0 = Qt @ jnp.concatenate([A0, z], axis=0)
        X1 = Qt @ jnp.concatenate([z, Dj], axis=0)
        Xp = Qt @ jnp.concatenate([Ap, Gj], axis=0)
        Xb = Qt @ jnp.concatenate([b, ccj], axis=0)
        Rt = R[:n]
        piv = (Rt, X0[:n], X1[:n], Xp[:n], Xb[:n])
        K = solve_triangular(Rt, Fj.T, lower=False, trans="T").T  # Fj Rt^{-1}
        new = (X0[n:], X1[n:], Xp[n:], Xb[n:],
               F0 - K @ X0[:n], Phinext - K @ X1[:n], Fp - K @ Xp[:n], fbb - K @ Xb[:n])
        return new, piv

    init = (C[0], D[0], G[0], cc[0], Phi[0], Phi[1], phip, fb)
    carry, piv = jax.lax.scan(step, init, (C[1:], D[1:], G[1:], cc[1:], Phi[2:]))
    A0, AN, Ap, b, F0, FN, Fp, fbb = carry
    eye = jnp.eye(n, dtype=C.dtype)
    top = jnp.concatenate([A0, AN, Ap], axis=1)
    mid = jnp.concatenate([eye, -eye, jnp.zeros((n, 2), C.dtype)], axis=1)
    bot = jnp.concatenate([F0, FN, Fp], axis=1)
    z = jnp.linalg.solve(jnp.concatenate([top, mid, bot], axis=0), jnp.concatenate([b, cper, fbb], axis=0))
    dx0, dxN, dp = z[:n], z[n:2 * n], z[2 * n:]

    def back(dxnext, pv):
        Rt, P0, P1, Pp, pb = pv
        dxj = solve_triangular(Rt, pb - P0 @ dx0 - P1 @ dxnext - _dot2(Pp, dp), lower=False)
        return dxj, dxj

    _, dxs = jax.lax.scan(back, dxN, piv, reverse=True)
    dxm = jnp.concatenate([dx0[None], dxs, dxN[None]], axis=0)
    return dxm, dp


def linear_solve_multi(f: VectorField, args: Any, orbit: Orbit, con: Constraint, scheme: Scheme,
                       rc: jax.Array, rper: jax.Array, rs: jax.Array):
    """Solve  J delta = (rc, rper, rs)  for k right-hand sides at once (condensed path).

    rc (N, m, n, k), rper (n, k), rs (2, k).  Returns mesh (N+1, n, k),
    interior (N, m-1, n, k) and (T, lam) (2, k) components of the solutions.
    """
    N, m, n = orbit.N, scheme.m, orbit.n
    k = rc.shape[-1]
    blocks = collocation_blocks(f, args, orbit, scheme)
    cond = condense(blocks, rc.reshape(N, m * n, k))
    coef, cp, _ = functional_coeffs(orbit, con, scheme)  # (2, N, m+1, n)
    aL = jnp.moveaxis(coef[:, :, 0], 0, 1)  # (N, 2, n)
    aI = jnp.moveaxis(coef[:, :, 1:m].reshape(2, N, (m - 1) * n), 0, 1)
    aR = jnp.moveaxis(coef[:, :, m], 0, 1)
    phiL = aL + aI @ cond.WL
    phiR = aR + aI @ cond.WR
    phip = cp + jnp.sum(aI @ cond.Wp, axis=0)
    fb = rs - jnp.einsum("jab,jbk->ak", aI, cond.w0)
    Phi = jnp.zeros((N + 1, 2, n), orbit.xm.dtype).at[:-1].add(phiL).at[1:].add(phiR)
    dxm, dp = _solve_reduced(cond, Phi, phip, fb, rper)
    dw = (cond.w0 + jnp.einsum("jab,jbk->jak", cond.WL, dxm[:-1])
          + jnp.einsum("jab,jbk->jak", cond.WR, dxm[1:]) + _dot2(cond.Wp, dp))
    return dxm, dw.reshape(N, m - 1, n, k), dp


def linear_solve(f: VectorField, args: Any, orbit: Orbit, con: Constraint, scheme: Scheme,
                 rc: jax.Array, rper: jax.Array, rs: jax.Array) -> Orbit:
    """Solve  J delta = (rc, rper, rs)  with J the Jacobian of ``residual``; condensed path."""
    dxm, dw, dp = linear_solve_multi(f, args, orbit, con, scheme, rc[..., None], rper[:, None], rs[:, None])
    return Orbit(orbit.mesh, dxm[..., 0], dw[..., 0], dp[0, 0], dp[1, 0])


def transfer_blocks(f: VectorField, args: Any, orbit: Orbit, scheme: Scheme) -> tuple[jax.Array, jax.Array]:
    """Condensed blocks (C_j, D_j) at ``orbit``; Gamma_j = -D_j^{-1} C_j."""
    N, m, n = orbit.N, scheme.m, orbit.n
    blocks = collocation_blocks(f, args, orbit, scheme)
    cond = condense(blocks, jnp.zeros((N, m * n, 1), orbit.xm.dtype))
    return cond.C, cond.D


def transfer_matrices(f: VectorField, args: Any, orbit: Orbit, scheme: Scheme) -> jax.Array:
    """Gamma_j = -D_j^{-1} C_j, (N, n, n): linearised map x_j -> x_{j+1} at fixed T, lam."""
    C, D = transfer_blocks(f, args, orbit, scheme)
    return -jnp.linalg.solve(D, C)


def interior_response(f: VectorField, args: Any, orbit: Orbit, scheme: Scheme, dxm: jax.Array) -> jax.Array:
    """Interior values of the linearised (homogeneous) solution with mesh values dxm."""
    N, m, n = orbit.N, scheme.m, orbit.n
    blocks = collocation_blocks(f, args, orbit, scheme)
    cond = condense(blocks, jnp.zeros((N, m * n, 1), orbit.xm.dtype))
    dw = jnp.einsum("jab,jb->ja", cond.WL, dxm[:-1]) + jnp.einsum("jab,jb->ja", cond.WR, dxm[1:])
    return dw.reshape(N, m - 1, n)


# --------------------------------------------------------------------------
# Dense reference path (small problems / tests only)
# --------------------------------------------------------------------------
def dense_jacobian(f: VectorField, args: Any, orbit: Orbit, con: Constraint, scheme: Scheme) -> jax.Array:
    """Full Jacobian of the flattened residual w.r.t. ``orbit.to_flat()`` (dense!)."""

    def F(v):
        rc, rper, rs = residual(f, args, orbit.from_flat(v), con, scheme)
        return jnp.concatenate([rc.ravel(), rper, rs])

    return jax.jacfwd(F)(orbit.to_flat())


def dense_newton_step(f: VectorField, args: Any, orbit: Orbit, con: Constraint, scheme: Scheme) -> Orbit:
    """Reference Newton step by a dense solve (O((Nmn)^3)); for verification only."""
    rc, rper, rs = residual(f, args, orbit, con, scheme)
    r = jnp.concatenate([rc.ravel(), rper, rs])
    J = dense_jacobian(f, args, orbit, con, scheme)
    return orbit.from_flat(-jnp.linalg.solve(J, r))


# --------------------------------------------------------------------------
# One linearisation, two right-hand sides: the Newton step and the tangent
# --------------------------------------------------------------------------
def step_and_tangent(f: VectorField, args: Any, orbit: Orbit, con: Constraint, scheme: Scheme):
    """Newton iterate, residual/step max-norms and the normalised tangent at ``orbit`` (paper Eq. (34): the
    augmented Jacobian times the tangent is the last unit vector, so the continuation row of ``con`` fixes its
    orientation): one condensed linearisation for both.  Pure JAX; the dense corrector's ``linearise``."""
    N, m, n = orbit.N, scheme.m, orbit.n
    z = orbit.xm.dtype
    rc, rper, rs = residual(f, args, orbit, con, scheme)
    rnorm = jnp.maximum(jnp.max(jnp.abs(rc)), jnp.maximum(jnp.max(jnp.abs(rper)), jnp.max(jnp.abs(rs))))
    RC = jnp.stack([-rc, jnp.zeros((N, m, n), z)], axis=-1)
    RP = jnp.stack([-rper, jnp.zeros((n,), z)], axis=-1)
    RS = jnp.stack([-rs, jnp.array([0.0, 1.0], z)], axis=-1)
    dxm, dw, dp = linear_solve_multi(f, args, orbit, con, scheme, RC, RP, RS)
    d = Orbit(orbit.mesh, dxm[..., 0], dw[..., 0], dp[0, 0], dp[1, 0])
    t = Orbit(orbit.mesh, dxm[..., 1], dw[..., 1], dp[0, 1], dp[1, 1])
    t = t.scale(1.0 / jnp.sqrt(inner(t, t, scheme)))
    dnorm = jnp.max(jnp.abs(d.to_flat()))
    return orbit + d, rnorm, dnorm, t
