r"""Maps of the gas-film and foil dissipation, W_cb and W_cf [p0 R L c], over the foil properties (alpha_f, eta) at
one speed (paper Figs. 13-14), computed as one batched (vmapped) Newton sweep warm-started from one cycle.

Every grid point starts from the cycle of the system's own foil at that speed and runs the condensed collocation
Newton in a single compiled, vmapped kernel (:func:`gfbjax.cont.batch.batched_newton`); the works follow from
the same batched quadrature.  Points where Newton does not converge from that start are NaN in the maps (and
False in ``converged``).

Known problem (not solved): with jax/jaxlib 0.10 on CPU the vmapped condensed step has dead-locked XLA:CPU
intermittently (0 % CPU, no progress) on repeated calls in one process -- the same family of dead-lock as the scan
kernel noted in :mod:`gfbjax.cont`.  A first call has completed (2 x 2 grid, Nx=16, Nz=2, N=8: 4/4 converged in
5 iterations, agreeing with point-by-point solves); treat this module as experimental.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .cont import collocation as col
from .cont.batch import batched_newton
from .cycles import _f_cycles
from .design import FoilDesign, check_foil
from .energy import orbit_energy
from .params import ParameterError, Params

__all__ = ["EnergyMap", "energy_map"]


@dataclass
class EnergyMap:
    """W_cb and W_cf over the grid ``alpha_f`` x ``eta`` (arrays of shape (len(eta), len(alpha_f))) at speed
    ``omega``; ``converged`` mask, Newton ``iterations`` and wall ``seconds`` of the batched sweep (including
    its compilation on the first call for a grid size)."""

    omega: float
    alpha_f: np.ndarray
    eta: np.ndarray
    W_cb: np.ndarray
    W_cf: np.ndarray
    converged: np.ndarray
    iterations: np.ndarray
    seconds: float


def _with_foil(theta: jax.Array, base: Params) -> Params:
    """theta = (alpha_f, eta) -> Params."""
    return eqx.tree_at(lambda p: (p.alpha_f, p.eta), base, (theta[0], theta[1]))


@jax.jit
def _works(orbits, thetas, base):
    def one(o, th):
        E = orbit_energy(o, _with_foil(th, base))
        return jnp.stack([E.W_cb, E.W_cf])
    return jax.vmap(one)(orbits, thetas)


def energy_map(params: Params, omega: float, alpha_f: Any, eta: Any, *, m: int = 4, N: int = 16,
               max_iter: int = 15, tol: float = 1e-9) -> EnergyMap:
    """W_cb and W_cf at every (alpha_f, eta) of the grid at Omega_bar = ``omega`` (see module docstring)."""
    a = np.asarray(alpha_f, float).ravel()
    e = np.asarray(eta, float).ravel()
    if a.size == 0 or e.size == 0:
        raise ParameterError("alpha_f and eta need at least one value each")
    for x in a:
        check_foil(float(x), float(e[0]))
    for x in e:
        check_foil(float(a[0]), float(x))
    base = FoilDesign(params, omega, m=m, N=N, linear_solver="dense")
    start = base.evaluate(float(params.alpha_f), float(params.eta)).orbit
    A, E = np.meshgrid(a, e)
    thetas = jnp.asarray(np.stack([A.ravel(), E.ravel()], axis=1))
    t0 = time.perf_counter()
    orbits, its, _, ok = batched_newton(_f_cycles, _with_foil, thetas, params, start, col.Scheme(m),
                                        max_iter=max_iter, tol=tol)
    W = np.array(_works(orbits, thetas, params))
    sec = time.perf_counter() - t0
    ok = np.asarray(ok)
    W[~ok] = np.nan
    shape = A.shape
    return EnergyMap(float(omega), a, e, W[:, 0].reshape(shape), W[:, 1].reshape(shape), ok.reshape(shape),
                     np.asarray(its).reshape(shape), sec)
