r"""Does the mesh resolve the modes of the linearisation?  Where it does not, Floquet multipliers are wrong while
the orbit, its mesh estimate and the trivial multiplier are all accurate.

Collocation integrates the variational equation over each mesh interval with the scheme's stability function R
(:meth:`~._collocation.Scheme.stability`): a mode y' = lam y is multiplied by R(h lam) per interval of length h
(in the problem's time) instead of exp(h lam).  The orbit does not contain these modes (they are not excited), so
its mesh estimate cannot see how well they are resolved.  Two ways it goes wrong:

* **fast modes** (|h lam| >> 1, strongly damped): with Gauss points |R| -> 1, so a mode that decays by
  exp(lam T) ~ 0 over the period keeps a multiplier near the unit circle.  On the GFB reference grid at N = 16 the
  film's modes (lam ~ -600) give a band of spurious multipliers at |mu| 0.33 at the Neimark-Sacker speed and 0.91
  at Omega_bar 0.05.  Radau points (L-stable) put them near 0.
* **modes oscillating within an interval** (|h Im lam| ~ 1 or more, weakly damped): at low speed the period
  T = 2 pi / Omega_bar is long, and the rotor's own oscillation completes about a cycle per interval.  On the
  16x2 grid at Omega_bar 0.1 and N = 16 the leading pair's modulus comes out 0.283 with Gauss points and 0.044
  with Radau points; it is 0.247 (N = 64 and 128 with both, and exp(lam T) of the equilibrium's rotor mode).

Both are estimated by :func:`resolution` from the frozen-coefficient model: the eigenvalues lam of f_x at
:data:`NODES` mesh points spread over the period (the largest estimate of them is kept, so that the result does
not depend on where the orbit's time origin lies), each mode's multiplier prod_i R(h_i lam) on the mesh against
exp(lam T) exactly:

* ``stiff_modulus``: the largest modulus the mesh gives a fast mode (exact multiplier below :data:`FAST`; its
  exact value is about 0): the band of spurious multipliers;
* ``multiplier_error``: the largest error |prod R - exp(lam T)| / max(1, |exp(lam T)|) (modulus and phase) of a
  visible mode (exact multiplier at least :data:`FAST`) or of a fast mode whose spurious multiplier reaches
  :data:`DECIDING` of the leading non-trivial modulus (capped at 1), i.e. pretends to decide stability, events or
  the leading multiplier.  A spurious band further inside changes none of these and is not counted.

The model is exact for a constant Jacobian (tests/cont/test_cont_resolution.py) and a guide otherwise: it says
where the multipliers need a finer mesh (or Radau points for the fast modes), not by how much they are off on a
cycle far from a constant-coefficient one.  Its cost is a dense eigenvalue problem per node and recorded point
(n = 433: about 3 s over the reference branch); above :data:`MAX_DENSE` states it is skipped (NaN: not
estimated).
"""
from __future__ import annotations

import math
from functools import partial
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from . import _collocation as col

__all__ = ["resolution", "DECIDING", "FAST", "NODES", "MAX_DENSE"]

#: a mode whose exact multiplier is below this modulus is a fast mode (:func:`resolution`'s ``stiff_modulus``)
FAST = 1e-3
#: mesh points (evenly spread over the period) at which the Jacobian is frozen
NODES = 2
#: a mode decides (stability, events, the leading multiplier) when its exact or discrete multiplier reaches this
#: fraction of the leading non-trivial modulus (capped at 1): a spurious band further in changes none of them
DECIDING = 0.9
#: the largest state dimension for which the dense eigenvalue problems are solved
MAX_DENSE = 1500


@partial(jax.jit, static_argnums=(0,))
def _jacobians(f: Callable, xs: jax.Array, lam: jax.Array, args: Any) -> jax.Array:
    return jax.vmap(jax.jacfwd(lambda y: f(y, lam, args)))(xs)


def resolution(f: Callable, orbit: col.Orbit, args: Any, scheme: col.Scheme,
               leading: float = 1.0) -> tuple[float, float]:
    """(stiff_modulus, multiplier_error) of a converged orbit on its mesh, both dimensionless (module docstring);
    ``leading``: the largest non-trivial multiplier's modulus at the point.  (NaN, NaN) above
    :data:`MAX_DENSE` states."""
    if orbit.n > MAX_DENSE:
        return math.nan, math.nan
    N = orbit.N
    at = np.unique((np.arange(NODES) * N) // NODES)
    J = np.asarray(_jacobians(f, jnp.asarray(np.asarray(orbit.xm)[at]), orbit.lam, args))
    h = float(orbit.T) * np.diff(np.asarray(orbit.mesh, float))
    T = float(np.sum(h))
    stiff, error = 0.0, 0.0
    for Jk in J:
        lam = np.linalg.eigvals(Jk)
        exact = np.exp(np.clip(lam.real * T, -700.0, 700.0) + 1j * lam.imag * T)
        discrete = np.prod(scheme.stability(h[:, None] * lam[None, :]), axis=0)
        fast = np.abs(exact) < FAST
        stiff = max(stiff, float(np.max(np.abs(discrete[fast]), initial=0.0)))
        deciding = np.maximum(np.abs(exact), np.abs(discrete)) >= DECIDING * min(1.0, leading)
        err = np.abs(discrete - exact) / np.maximum(1.0, np.abs(exact))
        error = max(error, float(np.max(err[deciding | ~fast], initial=0.0)))
    return stiff, error
