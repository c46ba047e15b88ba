r"""Maps of the gas-film and foil dissipation, W_cb and W_cf [p0 R L c], over the foil properties (alpha_f, eta) at
one speed (paper Figs. 13-14), computed as one batched (vmapped) Newton sweep warm-started from one cycle.

Every grid point starts from the cycle of the system's own foil at that speed and runs the condensed collocation
Newton in a single compiled, vmapped kernel (:func:`gfbjax.cont.batched_newton`, the one corrector under
``jax.vmap``); the works follow from the same batched quadrature.  Points where Newton does not converge from that start are NaN in the maps (and
False in ``converged``).

``energy_map_loop`` computes the same map point by point (a Python loop over the same dense Newton corrector from
the same start) for comparison: on a 2-core CPU the vmapped step costs about as much per member as the single
step, because XLA:CPU runs the batched LAPACK calls one matrix at a time, and the vmapped loop runs until its
slowest member stops (see benchmarks/energy_maps.py); the batch pays off on an accelerator.
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
from ..analyses.cycles import _f_cycles
from .evaluate import FoilDesign, check_foil
from ..analyses.energy import cycle_energy, orbit_energy
from ..params import ParameterError, Params

__all__ = ["EnergyMap", "energy_map", "energy_map_loop"]


@dataclass
class EnergyMap:
    """W_cb and W_cf over the grid ``alpha_f`` x ``eta`` (arrays of shape (len(eta), len(alpha_f))) at speed
    ``omega``; ``converged`` mask, Newton ``iterations`` and wall ``seconds`` of the sweep (including the
    compilation on the first call for a grid size); ``member_steps``: Newton steps computed, the masked steps of
    finished members included."""

    omega: float
    alpha_f: np.ndarray
    eta: np.ndarray
    W_cb: np.ndarray
    W_cf: np.ndarray
    converged: np.ndarray
    iterations: np.ndarray
    seconds: float
    member_steps: int = 0


def _with_foil(theta: jax.Array, base: Params) -> Params:
    """theta = (alpha_f, eta) -> Params."""
    return eqx.tree_at(lambda p: (p.alpha_f, p.eta), base, (theta[0], theta[1]))


@jax.jit
def _works(orbits, thetas, base):
    def one(o, th):
        E = orbit_energy(o, _with_foil(th, base))
        return jnp.stack([E.W_cb, E.W_cf])
    return jax.vmap(one)(orbits, thetas)


def _grid(params: Params, omega: float, alpha_f: Any, eta: Any, m: int, N: int):
    a = np.asarray(alpha_f, float).ravel()
    e = np.asarray(eta, float).ravel()
    if a.size == 0 or e.size == 0:
        raise ParameterError("alpha_f and eta need at least one value each")
    for x in a:
        check_foil(float(x), float(e[0]))
    for x in e:
        check_foil(float(a[0]), float(x))
    base = FoilDesign(params, omega, m=m, N=N, linear_solver=cont.DenseCondensation())
    start = base.evaluate(float(params.alpha_f), float(params.eta)).orbit
    A, E = np.meshgrid(a, e)
    return a, e, A.shape, np.stack([A.ravel(), E.ravel()], axis=1), start


def _result(omega, a, e, shape, W, ok, its, sec, steps) -> EnergyMap:
    W = np.array(W, float)
    ok = np.asarray(ok, bool)
    W[~ok] = np.nan
    return EnergyMap(float(omega), a, e, W[:, 0].reshape(shape), W[:, 1].reshape(shape), ok.reshape(shape),
                     np.asarray(its).reshape(shape), sec, int(steps))


def energy_map(params: Params, omega: float, alpha_f: Any, eta: Any, *, m: int = 4, N: int = 16,
               max_iter: int = 10, tol: float = 1e-9) -> EnergyMap:
    """W_cb and W_cf at every (alpha_f, eta) of the grid at Omega_bar = ``omega`` by one batched sweep (see
    module docstring); every point starts from the cycle of ``params``' own foil."""
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
        E = cycle_energy(r.x, p)
        W.append((float(E.W_cb), float(E.W_cf)))
        ok.append(r.converged)
        its.append(int(r.iterations))
        steps += int(r.iterations) + int(r.converged)
    return _result(omega, a, e, shape, W, ok, its, time.perf_counter() - t0, steps)
