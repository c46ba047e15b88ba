r"""Maps of the gas-film and foil dissipation, W_cb and W_cf [p0 R L c], over the foil properties (alpha_f, eta) at
one speed (paper Figs. 13-14): one cycle solve per foil of the grid, three ways.

:func:`energy_map` starts every grid point from the cycle of the system's own foil at that speed and runs the
condensed collocation Newton in a single compiled, vmapped kernel (:func:`gfbjax.cont.batched_newton`, the one
corrector under ``jax.vmap``); the works follow from the same batched quadrature.  Points where Newton does not
converge from that start are NaN in the maps (and False in ``converged``): on a grid over the design bounds, the
foils far from the system's own.

``energy_map_loop`` computes the same map point by point (a Python loop over the same dense Newton corrector from
the same start) for comparison: on a 2-core CPU the vmapped step costs about as much per member as the single
step, because XLA:CPU runs the batched LAPACK calls one matrix at a time, and the vmapped loop runs until its
slowest member stops (see benchmarks/energy_maps.py); the batch pays off on an accelerator.

:func:`energy_map_stepped` reaches every foil from a solved neighbour instead (:meth:`FoilDesign.evaluate`,
serially): it converges on the foils far from the system's own that the one-start maps miss.  All three use the
system's own foil's cycle as the phase reference of every solve (the discretised cycle's works change with its
phase at the size of the discretisation error), so where they converge to the same cycle they agree to the
Newton tolerance, whatever path led there.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import cont
from ..analyses.cycles import _f_cycles, _h_min
from ..analyses.energy import orbit_energy
from .evaluate import CycleNotConverged, FoilDesign, check_foil
from ..params import ParameterError, Params

__all__ = ["EnergyMap", "energy_map", "energy_map_loop", "energy_map_stepped"]


@dataclass
class EnergyMap:
    """Figures over the grid ``alpha_f`` x ``eta`` at speed ``omega`` (Omega_bar), arrays of shape
    (len(eta), len(alpha_f)), NaN where no cycle was found: the works per cycle ``W_cb`` (gas films), ``W_cf``
    (foil dampers) and ``W_fu`` (unbalance) [p0 R L c], and ``h_min``, the smallest film thickness over the cycle's
    collocation nodes [c] (<= 0: the film closes, not physical).  ``converged`` mask; ``iterations``: Newton
    iterations of the solve that gave each point; ``seconds``: wall time of the map (including the compilation on
    the first call for a grid size); ``member_steps``: Newton steps computed (the batch: the masked steps of
    finished members included; the stepped map: every solve of its walks, failed ones and the start included).
    ``max_mu``: the largest non-trivial Floquet multiplier modulus, from :func:`energy_map_stepped` only (None from
    the others, which do not analyse stability)."""

    omega: float
    alpha_f: np.ndarray
    eta: np.ndarray
    W_cb: np.ndarray
    W_cf: np.ndarray
    W_fu: np.ndarray
    h_min: np.ndarray
    converged: np.ndarray
    iterations: np.ndarray
    seconds: float
    member_steps: int = 0
    max_mu: np.ndarray | None = None


def _with_foil(theta: jax.Array, base: Params) -> Params:
    """theta = (alpha_f, eta) -> Params."""
    return eqx.tree_at(lambda p: (p.alpha_f, p.eta), base, (theta[0], theta[1]))


def _figures(orbit, theta, base):
    """(W_cb, W_cf, W_fu, h_min) of one orbit at the foil theta: the one definition of a map's figures."""
    p = _with_foil(theta, base)
    E = orbit_energy(orbit, p)
    h = jnp.min(jax.vmap(lambda x: _h_min(x, orbit.lam, p))(orbit.nodes().reshape(-1, orbit.n)))
    return jnp.stack([E.W_cb, E.W_cf, E.W_fu, h])


_works = jax.jit(jax.vmap(_figures, in_axes=(0, 0, None)))
_figures_one = jax.jit(_figures)


def _check_grid(alpha_f: Any, eta: Any) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(alpha_f, float).ravel()
    e = np.asarray(eta, float).ravel()
    if a.size == 0 or e.size == 0:
        raise ParameterError("alpha_f and eta need at least one value each")
    for x in a:
        check_foil(float(x), float(e[0]))
    for x in e:
        check_foil(float(a[0]), float(x))
    return a, e


def _grid(params: Params, omega: float, alpha_f: Any, eta: Any, m: int, N: int):
    a, e = _check_grid(alpha_f, eta)
    base = FoilDesign(params, omega, m=m, N=N, linear_solver=cont.DenseCondensation())
    start = base.evaluate(float(params.alpha_f), float(params.eta)).orbit
    A, E = np.meshgrid(a, e)
    return a, e, A.shape, np.stack([A.ravel(), E.ravel()], axis=1), start


def _result(omega, a, e, shape, W, ok, its, sec, steps, max_mu=None) -> EnergyMap:
    W = np.array(W, float).reshape(-1, 4)
    ok = np.asarray(ok, bool)
    W[~ok.ravel()] = np.nan
    f = {k: W[:, c].reshape(shape) for c, k in enumerate(("W_cb", "W_cf", "W_fu", "h_min"))}
    return EnergyMap(float(omega), a, e, converged=ok.reshape(shape), iterations=np.asarray(its).reshape(shape),
                     seconds=sec, member_steps=int(steps), max_mu=max_mu, **f)


def energy_map(params: Params, omega: float, alpha_f: Any, eta: Any, *, m: int = 4, N: int = 16,
               max_iter: int = 10, tol: float = 1e-9) -> EnergyMap:
    """W_cb, W_cf, W_fu and h_min at every (alpha_f, eta) of the grid (1-D arrays of foil values inside
    :data:`gfbjax.design.evaluate.FOIL_BOUNDS`) at Omega_bar = ``omega`` by one batched sweep (see module
    docstring); every point starts from the cycle of ``params``' own foil (m, N: collocation points and mesh
    intervals; max_iter, tol: Newton).  ParameterError for an empty grid or a foil outside the bounds (before any
    solve); :class:`CycleNotConverged` when ``params``' own foil has no cycle."""
    a, e, shape, thetas, start = _grid(params, omega, alpha_f, eta, m, N)
    t0 = time.perf_counter()
    res = cont.batched_newton(_f_cycles, _with_foil, jnp.asarray(thetas), params, start, cont.Scheme(m),
                              cont.NewtonSettings(tol=tol, atol_step=tol, rtol_step=tol, max_iter=max_iter))
    W = _works(res.orbits, jnp.asarray(thetas), params)
    return _result(omega, a, e, shape, W, res.converged, res.iterations, time.perf_counter() - t0, res.steps)


def energy_map_loop(params: Params, omega: float, alpha_f: Any, eta: Any, *, m: int = 4, N: int = 16,
                    max_iter: int = 10, tol: float = 1e-9) -> EnergyMap:
    """The same map as :func:`energy_map`, point by point: a Python loop over the dense Newton corrector
    (:func:`gfbjax.cont.correct_cycle`) from the same start (the reference for the batched sweep)."""
    a, e, shape, thetas, start = _grid(params, omega, alpha_f, eta, m, N)
    settings = cont.CycleSettings(m=m, N=N, newton_tol=tol, newton_step_tol=tol, newton_max_iter=max_iter,
                                  fast_iter=min(3, max_iter), linear_solver=cont.DenseCondensation())
    t0 = time.perf_counter()
    W, ok, its, steps = [], [], [], 0
    for th in thetas:
        p = _with_foil(jnp.asarray(th), params)
        problem = cont.CycleProblem(_f_cycles, start.n, p)
        r, _ = cont.correct_cycle(problem, start, settings=settings)
        W.append(np.asarray(_figures_one(r.x, jnp.asarray(th), params)))
        ok.append(r.converged)
        its.append(int(r.iterations))
        steps += int(r.iterations) + int(r.converged)
    return _result(omega, a, e, shape, W, ok, its, time.perf_counter() - t0, steps)


def _log_distance(x: Any, y: Any) -> float:
    # Foil properties span decades: neighbours are close in log(alpha_f), log(eta), the variables the walk steps in.
    return float(np.hypot(*(np.log(np.asarray(x, float)) - np.log(np.asarray(y, float)))))


def _walk(design: FoilDesign, x_from: tuple, orbit: cont.Orbit, x_to: tuple, ref: cont.Orbit, min_step: float):
    """The evaluation at the foil x_to, reached from ``orbit`` (the cycle at x_from) along the straight line in
    (log alpha_f, log eta): after a failed solve the step is halved, after a converged one doubled; None when a
    step of ``min_step`` (a fraction of the line) fails."""
    u0, u1 = np.log(x_from), np.log(x_to)
    s, step = 0.0, 1.0
    while True:
        t = min(1.0, s + step)
        x = x_to if t == 1.0 else tuple(np.exp(u0 + t * (u1 - u0)))  # the grid value itself, not exp(log(x))
        try:
            ev = design.evaluate(*x, guess=orbit, phase_reference=ref)
        except CycleNotConverged:
            if step <= min_step:
                return None
            step /= 2
            continue
        if t == 1.0:
            return ev
        orbit, s, step = ev.orbit, t, min(1.0, 2 * step)


def energy_map_stepped(params: Params, omega: float, alpha_f: Any, eta: Any, *, m: int = 4, N: int = 16,
                       max_iter: int = 10, tol: float = 1e-9, linear_solver: cont.LinearSolver | None = None,
                       tries: int = 3, min_step: float = 1 / 64) -> EnergyMap:
    """The map of :func:`energy_map` (same arguments, same :class:`EnergyMap`, ``max_mu`` added), every foil
    reached from a solved neighbour: it converges on foils far from ``params``' own that the one-start maps miss.

    The walk starts at the cycle of ``params``' own foil (where that foil has no cycle at this speed: at the grid
    foil nearest to it that has one from its own unbalance response) and visits the grid foils in order of
    distance from it in (log alpha_f, log eta).  Each foil is solved from the nearest solved foil, the step
    halved along the line between them down to ``min_step`` of it after a failed solve, and from the next of the
    ``tries`` nearest solved foils when that walk stalls; a foil left unsolved is tried again whenever a new foil
    joins its ``tries`` nearest.  Every solve (:meth:`FoilDesign.evaluate`; ``linear_solver`` as there, default
    automatic) has the start cycle as its phase reference, so where a foil's cycle is also reached by
    :func:`energy_map` the two agree to the Newton tolerance.  Serial, and the walks that stall cost most
    (``member_steps``; measured on the coarse 5 x 5 grid over the foil bounds at Omega_bar 0.2: about 13 Newton
    steps per foil where every walk arrives, 140 where several stall).  ParameterError for an empty grid, a
    foil outside the bounds, ``tries`` < 1 or ``min_step`` outside (0, 1], before any solve; a grid without any
    cycle found gives a map with ``converged`` all False."""
    a, e = _check_grid(alpha_f, eta)
    if isinstance(tries, bool) or not isinstance(tries, (int, np.integer)) or tries < 1:
        raise ParameterError(f"tries must be an integer >= 1, got {tries!r}")
    if not 0.0 < float(min_step) <= 1.0:
        raise ParameterError(f"min_step must lie in (0, 1], got {min_step!r}")
    t0 = time.perf_counter()
    shape = (e.size, a.size)
    foil = {(i, j): (float(a[j]), float(e[i])) for i in range(e.size) for j in range(a.size)}
    own = (float(params.alpha_f), float(params.eta))
    kw = dict(m=m, N=N, linear_solver=linear_solver, newton_tol=tol, newton_max_iter=max_iter)
    designs, solved, found = [], {}, {}
    # The start: the own foil's cycle, else the nearest grid foil's that converges from its own unbalance response.
    for key, x in [(None, own)] + sorted(foil.items(), key=lambda kx: _log_distance(kx[1], own)):
        try:
            designs.append(FoilDesign(params if key is None else _with_foil(jnp.asarray(x), params), omega, **kw))
            ev = designs[-1].evaluate(*x)
        except CycleNotConverged:
            continue
        solved[key] = (x, ev.orbit)
        if key is not None:
            found[key] = ev
        break
    if solved:
        design = designs[-1]
        (root, ref), = solved.values()
        pending = sorted((k for k in foil if k not in found), key=lambda k: _log_distance(foil[k], root))
        tried = {k: set() for k in pending}
        progress = True
        while pending and progress:
            progress = False
            for k in list(pending):
                near = sorted(solved, key=lambda s: _log_distance(solved[s][0], foil[k]))[:tries]
                for s in near:
                    if s in tried[k]:
                        continue
                    tried[k].add(s)
                    ev = _walk(design, solved[s][0], solved[s][1], foil[k], ref, float(min_step))
                    if ev is not None:
                        solved[k], found[k] = (foil[k], ev.orbit), ev
                        pending.remove(k)
                        progress = True
                        break
    W = np.full((e.size * a.size, 4), np.nan)
    ok, its, mu = np.zeros(W.shape[0], bool), np.zeros(W.shape[0], int), np.full(shape, np.nan)
    for (i, j), ev in found.items():
        r = i * a.size + j
        W[r] = np.asarray(_figures_one(ev.orbit, jnp.asarray(foil[(i, j)]), params))
        ok[r], its[r], mu[i, j] = True, ev.newton_iterations, ev.max_mu
    steps = sum(d.n_newton_steps for d in designs)
    return _result(omega, a, e, shape, W, ok, its, time.perf_counter() - t0, steps, max_mu=mu)
