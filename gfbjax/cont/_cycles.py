r"""Continuation of periodic orbits in lam: the cycle :class:`~._driver.Curve`, starts, and Floquet analysis.

Points are :class:`~._collocation.Orbit` (collocation unknowns with T and lam); the inner product is that of the
pseudo-arclength row (30).  Each correction is the one Newton corrector (:mod:`._newton`) on the linear solver of
the settings (:mod:`._linear`); each converged point gets its Floquet multipliers (:mod:`._floquet`) from the
corrector's own linearisation, its stability from the non-trivial ones, and the distance of the trivial
multiplier from +1.  Test functions of LPC, PD and NS: :mod:`._events`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial
from typing import Any, Callable, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import _collocation as col
from ._branch import Branch, PointRecord
from ._checks import (check_field_at_nodes, check_finite, check_index, check_located_state, check_mesh, check_nodes,
                      check_range, check_start)
from ._checkpoint import as_checkpoint, fingerprint
from ._driver import Curve, continue_curve
from ._events import (classify, crossed_multipliers, cycle_test_functions, detect, double_orbit_pd, EVENT_WEIGHTS,
                      multiplier_crossings, name_crossings, untracked_multipliers)
from ._floquet import FloquetMethod, nontrivial, trivial_error
from ._mesh import equidistributed_mesh, error_estimate, halved_mesh, interval_errors, remesh
from ._linear import BoundSolver, Linearisation, SparseSweep, choose_solver
from ._newton import LinearSolveError, with_finite_tangent
from ._results import Outcome, SpecialPoint
from ._problem import CycleProblem
from ._settings import CycleSettings, Natural
from ._resolution import multiplier_estimates

__all__ = ["CycleStart", "continue_cycles", "analyse", "correct_cycle", "check_cycle_inputs", "check_cycle_size", "bind_solver", "start_from_samples", "start_from_function",
           "start_from_hopf", "start_from_branch", "start_from_pd"]


@dataclass(frozen=True)
class CycleStart:
    """Where a branch starts.  ``tangent=None``: ``orbit`` is a guess corrected at fixed lam, the first tangent
    points to increasing lam * direction.  Otherwise ``orbit`` is a bifurcation point (Hopf / PD) and ``tangent``
    the direction of the emanating branch (the start itself is not recorded)."""

    orbit: col.Orbit
    tangent: Optional[col.Orbit] = None
    label: str = "start"


# ---------------------------------------------------------------- starts
def _start_mesh(settings: CycleSettings, mesh: Any, T: Any, lam: Any) -> tuple[np.ndarray, float, float]:
    """The checked mesh (uniform with ``settings.N`` intervals when None), period and parameter of a start."""
    T = check_range("T (period)", T, 0.0, np.inf, lo_open=True, hi_open=True)
    lam = check_range("lam", lam, -np.inf, np.inf, lo_open=True, hi_open=True)
    return check_mesh("mesh", col.uniform_mesh(settings.N) if mesh is None else mesh), T, lam


def start_from_samples(t: np.ndarray, x: np.ndarray, T: float, lam: float,
                       settings: CycleSettings, mesh: Any = None) -> CycleStart:
    """From a time-integrated orbit: samples ``x[i] = x(t[i])`` over one period T."""
    sch = col.Scheme(settings.m, settings.collocation)
    mesh, T, lam = _start_mesh(settings, mesh, T, lam)
    return CycleStart(col.orbit_from_samples(t, x, T, lam, sch, mesh), None, "samples")


def start_from_function(x_of_t: Callable[[np.ndarray], np.ndarray], T: float, lam: float,
                        settings: CycleSettings, mesh: Any = None) -> CycleStart:
    """From a function of the scaled time t in [0,1] (vectorised, returns (len(t), n))."""
    sch = col.Scheme(settings.m, settings.collocation)
    mesh, T, lam = _start_mesh(settings, mesh, T, lam)
    return CycleStart(col.orbit_from_function(x_of_t, T, lam, sch, mesh), None, "function")


def start_from_hopf(hopf: Any, settings: CycleSettings) -> CycleStart:
    """From a Hopf point (``lam, x, omega, v``): x(t) = x0 + a Re(v e^{2 pi i t}).

    The start is the stationary orbit x0 with T = 2 pi / omega; the tangent is the normalised first harmonic
    Re(v e^{2 pi i t}) (lam, T components 0, the Hopf bifurcation being a pitchfork in the amplitude a).
    ``ValueError`` naming the field when ``omega`` is not a positive number, ``lam`` not finite, ``x`` not a finite
    vector, or ``v`` not finite, not of the shape of ``x``, or zero."""
    if not isinstance(settings, CycleSettings):
        raise ValueError(f"settings must be CycleSettings, got {type(settings).__name__}")
    missing = [k for k in ("lam", "x", "omega", "v") if not hasattr(hopf, k)]
    if missing:
        raise ValueError(f"hopf must be a Hopf point with lam, x, omega and v (see hopf_point); this "
                         f"{type(hopf).__name__} has no {', '.join(missing)}")
    omega = check_range("hopf.omega", hopf.omega, 0, np.inf, lo_open=True, hi_open=True)
    lam = check_range("hopf.lam", hopf.lam, -np.inf, np.inf, lo_open=True, hi_open=True)
    x0 = check_finite("hopf.x", hopf.x)
    if x0.ndim != 1 or x0.size == 0:
        raise ValueError(f"hopf.x must be a vector (the equilibrium's state), got shape {x0.shape}")
    v = check_finite("hopf.v", hopf.v).astype(complex)
    if v.shape != x0.shape:
        raise ValueError(f"hopf.v must have the shape of hopf.x, {x0.shape}, got {v.shape}")
    if not np.any(v):  # its normalisation would divide by zero: a start without a direction
        raise ValueError("hopf.v must not be zero (the critical eigenvector gives the direction of the cycles)")
    sch = col.Scheme(settings.m, settings.collocation)
    mesh = col.uniform_mesh(settings.N)
    T = 2 * np.pi / omega
    base = col.orbit_from_function(lambda t: np.tile(x0, (len(t), 1)), T, lam, sch, mesh)
    phi = col.orbit_from_function(lambda t: np.real(v[None, :] * np.exp(2j * np.pi * t)[:, None]),
                                  0.0, 0.0, sch, mesh)
    phi = phi.scale(1.0 / float(jnp.sqrt(col.inner(phi, phi, sch))))
    return CycleStart(base, phi, "hopf")


def _orbit_of(st: dict[str, np.ndarray], index: int | None = None) -> col.Orbit:
    pick = (lambda a: a[index]) if index is not None else (lambda a: a)
    mesh = np.asarray(st["mesh"])
    mesh = mesh[index] if index is not None and mesh.ndim == 2 else mesh  # per point (adapted) or shared (older)
    return col.Orbit(jnp.asarray(mesh), jnp.asarray(pick(st["xm"])), jnp.asarray(pick(st["xi"])),
                     jnp.asarray(pick(st["T"])), jnp.asarray(pick(st["lam"])))


def _check_cycle_branch(branch: Any) -> None:
    if not isinstance(branch, Branch):
        raise ValueError(f"branch must be a Branch, got {type(branch).__name__}")
    if branch.kind != "cycles":  # an equilibrium's state has no mesh, period or orbit to start from
        raise ValueError(f"branch must be a branch of cycles, got a branch of kind {branch.kind!r}")


def start_from_branch(branch: Branch, index: int) -> CycleStart:
    """From the stored point ``index`` of a branch of cycles computed with ``save_states=True``; a negative
    ``index`` counts from the end, as in Python (-1: the last point).  ``ValueError`` for a branch of equilibria,
    one without stored states, and an index that is not an int in [-len(branch), len(branch) - 1]."""
    _check_cycle_branch(branch)
    if branch.states is None:
        raise ValueError("branch has no stored states (use CycleSettings(save_states=True))")
    index = check_index("index", index, len(branch), "point")
    return CycleStart(_orbit_of(branch.states, index), None, f"branch[{index}]")


def _pd_point(branch: Branch, special: Any) -> SpecialPoint:
    """The PD record that ``special`` designates, checked to be located and to have its state in ``branch``."""
    if isinstance(special, SpecialPoint):
        sp = special
        if sp.type != "PD":
            raise ValueError(f"special must be a PD point, got a point of type {sp.type!r} (near lam = {sp.lam:.6g})")
        # its state is an index into the branch it came from: a point of another branch would pick a wrong orbit
        if not any(s is sp or (s.type, s.lam, s.state) == (sp.type, sp.lam, sp.state) for s in branch.special):
            raise ValueError(f"special (the PD point near lam = {sp.lam:.6g}) is not a special point of this branch "
                             f"(its PD points: {[round(s.lam, 6) for s in branch.special_of('PD')]})")
    elif np.ndim(special) == 0 and np.issubdtype(np.asarray(special).dtype, np.integer):  # bools are not integers
        pds = branch.special_of("PD")
        sp = pds[check_index("special", special, len(pds), "PD point")]
    else:
        raise ValueError(f"special must be an int index among the branch's PD points or a SpecialPoint, got "
                         f"{special!r}")
    check_located_state(branch, sp, "the switch would start off the new branch; refine the steps")
    return sp


def start_from_pd(problem: CycleProblem, branch: Branch, special: Any,
                  settings: CycleSettings | None = None) -> CycleStart:
    """Switch onto the period-doubled branch at a located PD point of ``branch`` (``special``: index among the
    branch's PD points, negative from the end, or the :class:`SpecialPoint`); transfer matrices from the linear
    solver of ``settings``.  ``ValueError`` before any work for a branch of equilibria, an index outside the
    branch's PD points, a point that is not a located PD point with a stored state, and a problem whose state
    count is not the branch's."""
    if not isinstance(problem, CycleProblem):
        raise ValueError(f"problem must be a CycleProblem, got {type(problem).__name__}")
    if settings is not None and not isinstance(settings, CycleSettings):
        raise ValueError(f"settings must be CycleSettings or None, got {type(settings).__name__}")
    _check_cycle_branch(branch)
    sp = _pd_point(branch, special)
    o = _orbit_of(branch.special_states[sp.state])
    if o.n != problem.n:
        raise ValueError(f"problem.n = {problem.n}, but the branch's cycles have {o.n} states: pass the problem "
                         "the branch was computed with")
    if branch.m is None:
        raise ValueError("branch.m (the collocation degree of its cycles) is not recorded: the PD orbit cannot be "
                         "read back")
    sch = col.Scheme(int(branch.m), branch.collocation or "gauss")
    G = bind_solver(problem, sch, settings).linearise(o).transfer_matrices()
    doubled, direction = double_orbit_pd(problem.f, problem.args, o, sch, np.asarray(G))
    return CycleStart(doubled, direction, "PD switch")


# ---------------------------------------------------------------- analysis
def bind_solver(problem: CycleProblem, scheme: col.Scheme, settings: CycleSettings | None = None) -> BoundSolver:
    """The linear solver of ``settings`` (automatic choice when None) bound to ``problem`` and ``scheme``."""
    s = settings or CycleSettings()
    return choose_solver(s.linear_solver, problem).bind(problem, scheme)


#: Estimated working memory above which a cycle computation is refused before it starts (bytes).
MEMORY_LIMIT = 4 * 2**30


def _effective_floquet(problem: CycleProblem, settings: CycleSettings) -> FloquetMethod:
    from ._floquet import BlockKrylov, PeriodicQR
    solver = choose_solver(settings.linear_solver, problem)
    return settings.floquet or (BlockKrylov() if isinstance(solver, SparseSweep) else PeriodicQR())


def check_cycle_size(problem: CycleProblem, N: int, m: int, settings: CycleSettings) -> None:
    """ValueError, before any work, when the Floquet method cannot see past the trivial multipliers or when the
    collocation system of N intervals of degree m would not fit in :data:`MEMORY_LIMIT`."""
    n = problem.n
    floquet = _effective_floquet(problem, settings)
    from ._floquet import _Leading
    if isinstance(floquet, _Leading) and min(floquet.k, n - 2) <= problem.n_trivial:
        advice = ("use a larger k, or " if n - 2 > problem.n_trivial else
                  f"n - 2 = {n - 2} caps it whatever k is: use ")
        raise ValueError(f"{type(floquet).__name__}(k={floquet.k}) computes min(k, n - 2) = {min(floquet.k, n - 2)} "
                         f"multipliers for n = {n}, not more than the {problem.n_trivial} trivial one(s): stability "
                         f"could not be judged; {advice}floquet=PeriodicQR() with the dense solver "
                         "(linear_solver=DenseCondensation())")
    solver = choose_solver(settings.linear_solver, problem)
    if isinstance(solver, SparseSweep):
        nnz = int(np.count_nonzero(np.asarray(problem.jac_sparsity, bool) | np.eye(n, dtype=bool)))
        need = 8 * 4 * N * m * m * nnz  # Jacobian values and interval blocks at every Gauss point
    else:
        need = 8 * 6 * N * (m * n) ** 2  # dense interval blocks, their complete QR and the condensed blocks
    if need > MEMORY_LIMIT:
        raise ValueError(f"N = {N} mesh intervals with m = {m} and n = {n} states need about {need / 2**30:.1f} "
                         f"GiB for the collocation system (limit {MEMORY_LIMIT / 2**30:.0f} GiB); use fewer "
                         "intervals" + ("" if isinstance(solver, SparseSweep) else
                                        " or the sparse solver (a Jacobian pattern)"))


def check_cycle_inputs(problem: CycleProblem, orbit: col.Orbit, settings: CycleSettings) -> None:
    """ValueError, before any work, when ``orbit`` does not fit ``problem`` (state count, f's output shape), and
    the checks of :func:`check_cycle_size` for its mesh."""
    n = problem.n
    _check_orbit_shapes(orbit, "the start orbit")
    if orbit.n != n:
        raise ValueError(f"the start orbit has {orbit.n} states but problem.n = {n}")
    out = jax.eval_shape(problem.f, jax.ShapeDtypeStruct((n,), orbit.xm.dtype), orbit.lam, problem.args)
    if getattr(out, "shape", None) != (n,):
        raise ValueError(f"f(x, lam, args) returned shape {getattr(out, 'shape', type(out).__name__)} for x of "
                         f"shape ({n},); it must return ({n},)")
    check_cycle_size(problem, orbit.N, int(orbit.xi.shape[1]) + 1, settings)


def _check_orbit_shapes(orbit: col.Orbit, what: str) -> None:
    """ValueError naming ``what`` and the array unless mesh, xm and xi are real arrays of shapes (N+1,), (N+1, n)
    and (N, m-1, n) (else JAX fails later, deep in a concatenation, with no name)."""
    arrays = {"mesh": orbit.mesh, "xm": orbit.xm, "xi": orbit.xi}
    for name, a in arrays.items():
        dtype = getattr(a, "dtype", None)
        if getattr(a, "shape", None) is None or dtype is None or not (
                jnp.issubdtype(dtype, jnp.floating) or jnp.issubdtype(dtype, jnp.integer)):
            raise ValueError(f"{what}'s {name} must be a real array, got {type(a).__name__}"
                             + (f" of dtype {dtype}" if dtype is not None else ""))
    mesh, xm, xi = (tuple(a.shape) for a in arrays.values())
    ok = len(mesh) == 1 and len(xm) == 2 and len(xi) == 3
    ok = ok and xm[0] == mesh[0] and xi[0] == mesh[0] - 1 and xi[2] == xm[1] and xi[1] >= 1
    if not ok:
        raise ValueError(f"{what} must have mesh (N+1,), xm (N+1, n) and xi (N, m-1, n), with N mesh intervals, m "
                         f"collocation points and n states; got mesh {mesh}, xm {xm}, xi {xi}")


def _check_orbit(problem: CycleProblem, orbit: col.Orbit, scheme: col.Scheme, what: str) -> None:
    """ValueError naming ``what`` when the orbit is no place to start Newton from: a mesh that is not one, a
    period that is not positive, a parameter that is not finite, a state that is NaN or inf at any node, or a
    vector field that is NaN or inf at any node or collocation point (all in one compiled call; at the first node
    only, a field that fails on part of the orbit would end the correction with no reason given).  After
    :func:`check_cycle_inputs` (the shapes)."""
    mesh = check_mesh(f"{what}'s mesh", orbit.mesh)
    check_range(f"{what}'s T (period)", orbit.T, 0.0, np.inf, lo_open=True, hi_open=True)
    check_finite(f"{what}'s lam", orbit.lam)
    n = orbit.n
    inner = col.node_times(mesh, scheme)[:, 1:-1].ravel()
    xi = orbit.xi.reshape(-1, n)
    check_nodes(f"{what}'s xm", orbit.xm, mesh, mesh)
    check_nodes(f"{what}'s xi", xi, inner, mesh)
    # f is evaluated at the collocation points, between the nodes: check it there too
    at_points = jnp.einsum("ki,jin->jkn", scheme.l, orbit.nodes()).reshape(-1, n)
    t_points = (mesh[:-1, None] + np.diff(mesh)[:, None] * scheme.points[None, :]).ravel()
    check_field_at_nodes(problem.f, jnp.concatenate([orbit.xm, xi, at_points]),
                         np.concatenate([mesh, inner, t_points]), mesh, float(orbit.lam), problem.args, what)


def _end_lam(A: col.Orbit, B: col.Orbit) -> float | None:
    """Where a family ends (a Hopf point, a period doubling) from two of its cycles A and B near the end: lam is
    even in the signed size a of the odd part x(t) - x(t + 1/2) there, lam = L + c a^2 + O(a^4), so the two give
    L.  None when the two sizes are too close to separate L from c (within 0.1 % in a^2)."""
    a2, b2 = col.half_period_defect(A) ** 2, col.half_period_defect(B) ** 2
    if not abs(a2 - b2) > 1e-3 * max(a2, b2):
        return None
    return (float(B.lam) * a2 - float(A.lam) * b2) / (a2 - b2)


def _check_moves(orbit: col.Orbit, what: str) -> None:
    """ValueError when ``orbit``, a guess to correct, is constant: a constant orbit is an equilibrium with any
    period, and as its own phase reference it makes the phase condition (the integral of x . x_ref') vanish;
    Newton's matrix is singular and the correction would end "nonfinite" or "diverged" without saying why."""
    if col.amplitude(orbit) <= 1e-14 * col.state_scale(orbit):
        raise ValueError(f"{what} is constant (every node equals xm[0]): a cycle needs a guess that moves; start "
                         "from a Hopf point (start_from_hopf), a period-doubling point (start_from_pd), a branch "
                         "(start_from_branch) or samples of a time integration (start_from_samples)")


def correct_cycle(problem: CycleProblem, orbit: col.Orbit, con: col.Constraint | None = None, *,
                  settings: CycleSettings | None = None) -> tuple[Any, Linearisation | None]:
    """Correct one orbit with the linear solver and Newton tolerances of ``settings`` (default
    ``CycleSettings()``): at fixed lam = ``orbit.lam`` with phase reference ``orbit`` unless ``con`` is given.
    Returns the :class:`NewtonSolution` (``x`` the orbit, ``aux`` the unit tangent) and the linearisation at
    the converged orbit (None when not converged), for :func:`analyse` and the implicit derivatives.  A
    correction that converged to an equilibrium (the constant orbit) or to a cycle of half the period traversed
    twice, from a guess that was neither (:func:`._collocation.collapsed`), found no cycle: its outcome is
    ``NO_SOLUTION``.
    Raises ``ValueError`` before any work when the inputs do not fit together (:func:`check_cycle_inputs`) or the
    orbit is not finite (mesh, T, lam, states) or f is NaN or inf at any of its nodes (the message names the
    node's scaled time and components)."""
    if not isinstance(problem, CycleProblem):
        raise ValueError(f"problem must be a CycleProblem, got {type(problem).__name__}")
    if not isinstance(orbit, col.Orbit):
        raise ValueError(f"orbit must be an Orbit, got {type(orbit).__name__}")
    if settings is not None and not isinstance(settings, CycleSettings):
        raise ValueError(f"settings must be CycleSettings or None, got {type(settings).__name__}")
    if con is not None and not isinstance(con, col.Constraint):
        raise ValueError(f"con must be a Constraint or None, got {type(con).__name__}")
    if con is not None and any(o.xm.shape != orbit.xm.shape or o.xi.shape != orbit.xi.shape
                               for o in (con.ref, con.base, con.v)):
        raise ValueError(f"con was built on another mesh or state count (its reference has xm {con.ref.xm.shape}, "
                         f"the orbit {orbit.xm.shape}): build it from this orbit (natural_constraint(orbit, lam))")
    s = settings or CycleSettings()
    check_cycle_inputs(problem, orbit, s)
    scheme = col.Scheme(int(orbit.xi.shape[1]) + 1, s.collocation)
    _check_orbit(problem, orbit, scheme, "the orbit")
    _check_moves(orbit, "the orbit")
    con = col.natural_constraint(orbit, orbit.lam) if con is None else con
    sol, lin = bind_solver(problem, scheme, s).correct(orbit, con, s.newton)
    if bool(sol.converged) and col.collapsed(sol.x, orbit, s.newton_step_tol) is not None:
        code = jnp.asarray(Outcome.NO_SOLUTION.code, jnp.asarray(sol.code).dtype)
        return eqx.tree_at(lambda r: r.code, sol, code), None
    return sol, lin


def analyse(problem: CycleProblem, lin: Linearisation, floquet: FloquetMethod | None = None,
            memo: dict | None = None) -> dict[str, Any]:
    """Floquet multipliers (``spectrum``, decreasing modulus), stability (``stable``: the non-trivial multipliers
    inside the unit circle), ``trivial_error`` (distance of the multiplier closest to +1 from +1) and ``modes``
    (the leading multipliers with their eigenvectors (n, k) where the method computed them, else None; for
    :func:`~._resolution.mode_error`) of a converged orbit, from its linearisation ``lin``.  ``floquet``: the
    method (default: the linearisation's own, all multipliers when dense, the leading ones by a block Krylov
    method when sparse); ``memo``: a dict kept along a branch (warm starts)."""
    floquet = floquet or lin.default_floquet()
    memo = {} if memo is None else memo
    memo.pop("modes", None)
    mu = np.asarray(floquet.multipliers(lin, memo))
    nt = nontrivial(mu, problem.n_trivial)
    return {"spectrum": mu, "stable": bool(np.all(np.abs(nt) < 1.0)), "trivial_error": trivial_error(mu),
            "modes": memo.pop("modes", None)}  # (multipliers, Ritz vectors) where the method made them


@partial(jax.jit, static_argnums=(1,))
def _norm_and_extrema(orbit: col.Orbit, scheme: col.Scheme, comps: jax.Array):
    U = orbit.nodes()[..., comps]
    return col.l2_norm(orbit, scheme), jnp.max(U, axis=(0, 1)), jnp.min(U, axis=(0, 1))


@partial(jax.jit, static_argnums=(0,))
def _monitor_min(fn: Callable, orbit: col.Orbit, args: Any) -> jax.Array:
    """Smallest value of a monitor over every collocation node of the orbit."""
    X = orbit.nodes().reshape(-1, orbit.n)
    return jnp.min(jax.vmap(lambda x: fn(x, orbit.lam, args))(X))


def _orbit_state(orbit: col.Orbit) -> dict[str, np.ndarray]:
    return {"mesh": np.asarray(orbit.mesh), "xm": np.asarray(orbit.xm), "xi": np.asarray(orbit.xi),
            "T": np.asarray(orbit.T), "lam": np.asarray(orbit.lam)}


class CycleCurve(Curve):
    """Periodic orbits of ``problem`` for the driver."""

    kind = "cycles"
    event_weights = EVENT_WEIGHTS

    def __init__(self, problem: CycleProblem, settings: CycleSettings, scheme: col.Scheme, mesh: np.ndarray):
        self.problem, self.settings, self.scheme, self._mesh = problem, settings, scheme, mesh
        self.solver = bind_solver(problem, scheme, settings)  # a bad choice raises here, before any work
        self.floquet = settings.floquet
        self.memo: dict[str, Any] = {}
        self._lpc_scale = 0.0  # typical size of the fold test (see adapt)
        self.monitor = problem.monitor
        self.components = problem.components
        self._comps = jnp.asarray(self.components)

    def add(self, a, b):
        return col.add(a, b)

    def scale(self, a, c):
        return col.scaled(a, c)

    def inner(self, a, b):
        return float(col.inner(a, b, self.scheme))

    def lam(self, a):
        return float(a.lam)

    def palc_constraint(self, base, tangent, ds, ref):
        return col.palc_constraint(base, tangent, ds, ref=ref)

    def natural_constraint(self, ref, lam):
        return col.natural_constraint(ref, lam)

    def correct(self, pred, con):
        # the last point's leading Floquet subspace (the block Krylov method's warm start) preconditions the solves
        sol, lin = self.solver.correct(pred, con, self.settings.newton, subspace=self.memo.get("krylov_start"))
        sol = with_finite_tangent(sol)
        return sol, (lin if sol.converged else None)

    def null_tangent(self, X):
        # At a fold of cycles the Jacobian at fixed lam is singular, but that of the collocation equations and
        # the phase condition in (orbit, T, lam) keeps a one-dimensional null space, the curve's tangent: bordered
        # with any row r not orthogonal to it the system is regular, and its solution with r . t = 1 is t.
        rng = np.random.default_rng(0)
        r = col.Orbit(X.mesh, jnp.asarray(rng.standard_normal(X.xm.shape)),
                      jnp.asarray(rng.standard_normal(X.xi.shape)), jnp.asarray(rng.standard_normal()),
                      jnp.asarray(rng.standard_normal()))
        try:
            lin = self.solver.linearise(X, col.palc_constraint(X, r, 0.0, X))
            t = lin.solve(np.zeros((X.N, self.scheme.m, X.n)), np.zeros(X.n), np.array([0.0, 1.0]))
        except LinearSolveError:
            return None
        norm = float(jnp.sqrt(col.inner(t, t, self.scheme)))
        if not np.isfinite(norm) or norm == 0.0:
            return None
        flat = np.asarray(t.to_flat())
        return t.scale(float(np.sign(flat[np.argmax(np.abs(flat))])) / norm)

    def analyse(self, X, lin, tangent):
        an = analyse(self.problem, lin, self.floquet, self.memo)
        an["linearisation"] = lin  # for the mesh error of the points that are recorded (record)
        if self.monitor is not None:
            an["monitor"] = float(_monitor_min(self.monitor.fn, X, self.problem.args))
        return an

    def tests(self, analysis, tangent_lam):
        out = cycle_test_functions(analysis["spectrum"], self.problem.n_trivial, tangent_lam)
        if self.monitor is not None:
            out["MONITOR"] = analysis["monitor"] - float(self.monitor.minimum)
        return out

    def events(self, prev, cur, kinds):
        return detect(prev, cur, kinds)

    def crossings(self, before, after):
        """Multipliers that crossed the unit circle between two points, by matching."""
        return multiplier_crossings(before, after)

    def untracked(self, before, after):
        return untracked_multipliers(before, after)

    def crossing_kinds(self, an, count, before=None):
        """``count`` crossings named from the non-trivial multipliers that crossed the unit circle since
        ``before`` (matched), then those nearest it: a complex pair an NS (two crossings, with its own angle), a
        real negative one a PD, a real positive one a BPC."""
        mu = nontrivial(an["spectrum"], self.problem.n_trivial)
        crossed = [] if before is None else crossed_multipliers(before, mu)
        named = name_crossings(mu, count, lambda z: abs(abs(z) - 1.0), "NS",
                               lambda z: "PD" if z.real < 0 else "BPC", crossed)
        return [(k, {"angle": abs(float(np.angle(z)))} if k == "NS" else {}) for k, z in named]

    def record(self, X, an, iterations, ds, tangent_lam) -> PointRecord:
        l2, xmax, xmin = _norm_and_extrema(X, self.scheme, self._comps)
        # only for recorded points: the localisation's many evaluations need no resolution estimate
        stiff, mu_error = multiplier_estimates(self.problem.f, self.problem.args, X, self.scheme, an["linearisation"],
                                               an["spectrum"], an.get("modes"), self.problem.n_trivial,
                                               self.solver.linearise)
        state = _orbit_state(X) if self.settings.save_states else None
        mesh_error = error_estimate(X, self.scheme, self.problem.f, self.problem.args, an["linearisation"])
        return PointRecord(float(X.lam), float(X.T), float(l2), np.asarray(xmax), np.asarray(xmin), an["spectrum"],
                           an["stable"], an["trivial_error"], int(iterations), float(ds), float(tangent_lam), state,
                           an.get("monitor", float("nan")), mesh_error, stiff, mu_error)

    def plotted(self, X):
        _, xmax, xmin = _norm_and_extrema(X, self.scheme, self._comps)
        return np.concatenate([[float(X.lam)], np.asarray(xmax), np.asarray(xmin)])

    def state(self, X):
        return _orbit_state(X)

    def from_state(self, state):
        return col.Orbit(*(jnp.asarray(state[k], float) for k in ("mesh", "xm", "xi", "T", "lam")))

    def family_ends(self, X, left, right):
        # the fold against the step's ends: a family that shrinks to its Hopf point passes through zero amplitude,
        # a period-doubled family that shrinks onto the cycle of half its period through zero distance from its
        # half-period shift (and runs back along itself, the same cycles shifted); a true fold keeps its size
        onto = next((k for k in (col.shrunk(X, end) for end in (left, right)) if k is not None), None)
        return None if onto is None else self._end_data(X, onto)

    def collapsed(self, X, guess, before=None):
        # the period of the last genuine cycle: a constant orbit has any period (the arclength row sets it)
        onto = col.collapsed(X, guess, self.settings.newton_step_tol)
        if onto is None:
            return None
        lx, ly = float(guess.lam), float(X.lam)
        # the end lies on the path from the last cycle (guess) to X, but lam need not be monotone along it (lam
        # turns at the end, and X lies on what the family was born from): the fit through the last two cycles
        # places it, and the interval about it covers the step's span as well
        L = None if before is None else _end_lam(before, guess)
        if L is None:
            return {**self._end_data(guess, onto), "lam": ly, "lam_error": abs(ly - lx)}
        return {**self._end_data(guess, onto), "lam": L, "lam_error": max(abs(L - lx), abs(L - ly))}

    def passed_end(self, X, Xn):
        onto = col.passed_through(X, Xn, self.settings.newton_step_tol)
        if onto is None:
            return None
        lx, ly = float(X.lam), float(Xn.lam)
        L = _end_lam(X, Xn)  # the same cycles on both sides of the end
        if L is None:
            return {**self._end_data(X, onto), "lam": 0.5 * (lx + ly), "lam_error": math.nan}
        return {**self._end_data(X, onto), "lam": L, "lam_error": max(abs(L - lx), abs(L - ly))}

    @staticmethod
    def _end_data(X, onto):
        T = float(X.T)
        if onto == "equilibrium":  # a Hopf point, whose frequency is the family's there
            return {"type": "HOPF", "period": T, "omega": 2.0 * math.pi / T}
        return {"type": "PD", "period": T}

    def special(self, kind, X, an, located=True, ends=None):
        c = classify(kind, an["spectrum"], self.problem.n_trivial)
        return None if c is None else {"period": float(X.T), **c}

    def adapt(self, X, tau, X_prev, tests, count):
        """Every ``settings.adapt`` points: the orbit corrected on an equidistributed mesh, its tangent there
        (oriented like ``tau``), the previous point carried over, and the fold test (the tangent's lam
        component) of the new discretisation, so that the next step compares like with like: a stale value
        would let the small change of the discrete branch near a fold show as spurious folds.  Unchanged when
        the correction fails."""
        every = self.settings.adapt
        if tests is not None:  # the typical size of the fold test, with a fading memory
            self._lpc_scale = max(0.9 * self._lpc_scale, abs(tests["LPC"]))
        if not every or count % every:
            return X, tau, X_prev, tests
        if tests is not None and abs(tests["LPC"]) < 0.2 * self._lpc_scale:
            return X, tau, X_prev, tests  # the branch is turning (near a fold): keep the mesh until it has
        err = interval_errors(X, self.scheme)
        # re-mesh only when the errors have become unequal (the largest twice the mean): a mesh that still fits
        # is kept, so that near folds, where the orbit hardly changes, the discretisation stays the same
        if np.max(err) <= 2.0 * np.mean(err):
            return X, tau, X_prev, tests
        mesh = equidistributed_mesh(X, self.scheme)
        Xr = remesh(X, self.scheme, mesh)
        sol, _ = self.correct(Xr, col.natural_constraint(Xr, X.lam))
        if not sol.converged:
            return X, tau, X_prev, tests
        t = sol.aux
        if self.inner(t, remesh(tau, self.scheme, mesh)) < 0:
            t = t.scale(-1.0)
        if tests is not None:
            if np.sign(float(t.lam)) != np.sign(tests["LPC"]):
                return X, tau, X_prev, tests  # at a fold: the new mesh would hide its crossing; adapt later
            tests = {**tests, "LPC": float(t.lam)}
        return sol.x, t, None if X_prev is None else remesh(X_prev, self.scheme, mesh), tests

    def border_solve(self, X, lin):
        rng = np.random.default_rng(1)  # the same b at every point of a branch (same shapes)
        try:  # on the host: a dense linearisation would compile its condensation once more for this one solve
            w = lin.host_solve(rng.standard_normal((X.N, self.scheme.m, X.n)), rng.standard_normal(X.n),
                          rng.standard_normal(2))
        except LinearSolveError:
            return None
        return np.asarray(w.to_flat())

    def other_discretisations(self, X, tau):
        # Two, because each misses what the other sees.
        # - Every interval halved (the solver's kernels compile once more for 2N).  Where the error does not
        #   depend on where the mesh nodes fall on the orbit (a symmetric orbit, a smooth field), the staggered
        #   mesh below is the same discretisation and would report nothing.
        # - The mesh staggered by half an interval (nodes at the old midpoints, the orbit moved with them; same
        #   N, same kernels).  With a kink in f (the bearing's max(p - 1, 0)) the error depends on where the
        #   kinks fall between the nodes and falls erratically with N, so halving can report a fraction of it:
        #   the reference NS on N = 32 moved 7e-6 on the halved mesh and 4e-5 on the staggered one, 2.5e-5
        #   from its N = 64 value (the leading pair's |mu| varies by 1e-4 along the discrete phase family).
        mesh = np.asarray(X.mesh, float)
        mid = 0.5 * (mesh[:-1] + mesh[1:])
        fine = halved_mesh(mesh)
        staggered = np.append(mid - mid[0], 1.0)
        return [(remesh(X, self.scheme, fine), remesh(tau, self.scheme, fine)),
                (remesh(X, self.scheme, staggered, mid[0]), remesh(tau, self.scheme, staggered, mid[0]))]

    def branch(self, points, special, special_states, outcome, message, settings) -> Branch:
        return Branch.from_points("cycles", self.components, points, special, special_states, outcome, message,
                                  m=self.scheme.m, accuracy_tol=settings.trivial_tol,
                                  monitor_info=None if self.monitor is None else self.monitor.describe(),
                                  mesh_tol=settings.mesh_tol, stiff_tol=settings.stiff_tol,
                                  multiplier_tol=settings.multiplier_tol, collocation=self.scheme.kind)


def continue_cycles(problem: CycleProblem, settings: CycleSettings, start: CycleStart, *,
                    callback: Optional[Callable[[int, PointRecord], Any]] = None,
                    progress: bool = False, checkpoint: Any = None) -> Branch:
    """Continue a branch of periodic orbits of ``problem`` from ``start`` (see :mod:`._driver`).

    ``checkpoint``: a folder (or :class:`~._checkpoint.Checkpoint`) that every accepted step is appended to; a
    call with a folder that holds steps of the same continuation resumes after the last one (``start`` is then
    only used for its shapes) or, if that branch had ended, returns it as stored.

    Returns a :class:`Branch` (points so far and the :class:`Outcome`, whatever ended the continuation).
    Raises ``ValueError`` before any work for inputs that do not fit together (:func:`check_cycle_inputs`: the
    start's array shapes and state count, f's output; a start of another degree than ``settings.m``; a linear
    solver the problem cannot use; a natural-parameter algorithm from a bifurcation point), and for a start orbit
    that is not finite or at any of whose nodes f is NaN or inf (naming the node's scaled time).  The start's own
    mesh is kept (its N need not be ``settings.N``)."""
    if not isinstance(problem, CycleProblem):
        raise ValueError(f"problem must be a CycleProblem, got {type(problem).__name__}")
    if not isinstance(settings, CycleSettings):
        raise ValueError(f"settings must be CycleSettings, got {type(settings).__name__}")
    if not isinstance(start, CycleStart):
        raise ValueError(f"start must be a CycleStart (see start_from_*), got {type(start).__name__}")
    if start.tangent is not None and isinstance(settings.algorithm, Natural):
        raise ValueError(f"a {start.label} start leaves its bifurcation point along a direction of its own; "
                         "natural-parameter steps cannot follow it: use PseudoArclength()")
    check_cycle_inputs(problem, start.orbit, settings)
    m_start = int(start.orbit.xi.shape[1]) + 1
    if m_start != settings.m:  # the start's own degree would silently override the settings'
        raise ValueError(f"the start orbit has m = {m_start} collocation points per interval (xi of shape "
                         f"{tuple(start.orbit.xi.shape)}) but settings.m = {settings.m}: build the start with "
                         f"m = {settings.m}, or continue with CycleSettings(m={m_start}, ...)")
    check_start(settings, start.orbit.lam, "the start's lam")
    scheme = col.Scheme(int(start.orbit.xi.shape[1]) + 1, settings.collocation)
    _check_orbit(problem, start.orbit, scheme, "the start orbit")
    if start.tangent is None:  # a Hopf start is the constant equilibrium with the first harmonic as tangent
        _check_moves(start.orbit, "the start orbit (a guess without a tangent)")
    curve = CycleCurve(problem, settings, scheme, np.asarray(start.orbit.mesh))
    ck = as_checkpoint(checkpoint, n=problem.n, start=start.label,
                       problem=fingerprint(problem.f, problem.args, problem.n_trivial),
                       start_data=fingerprint(start.orbit, start.tangent))
    return continue_curve(curve, settings, start.orbit, start.tangent, callback=callback, progress=progress,
                          desc="cycles", checkpoint=ck)
