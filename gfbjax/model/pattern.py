"""Sparsity pattern of the GFB-rotor Jacobian, for coloured (compressed) Jacobians and sparse linear algebra."""
from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from ..params import Params, reference_system
from .system import layout, vector_field


@functools.lru_cache(maxsize=16)
def _pattern_cached(Nx: int, Nz: int, rotor: str, gumbel_width: float, axial_domain: str = "half") -> np.ndarray:
    params = reference_system(Nx=Nx, Nz=Nz, rotor=rotor, gumbel_width=gumbel_width,
                              axial_domain=axial_domain).nondim()
    lay = layout(params, oscillator=True)
    rng = np.random.default_rng(12345)
    jac = jax.jit(jax.jacfwd(lambda x, om: vector_field(x, om, params)))
    pat = np.eye(lay.n, dtype=bool)
    for k in range(3):  # union over random states with an open film and every gauge pressure positive
        ph = rng.uniform(0, 2 * math.pi)
        x = np.concatenate([rng.uniform(1.1, 2.0, lay.grid.n_pressure), rng.uniform(0.01, 0.2, lay.n_foil),
                            rng.uniform(-0.3, 0.3, lay.n_rotor), [math.cos(ph), math.sin(ph)]])
        pat |= np.asarray(jac(jnp.asarray(x), jnp.asarray(0.3 + 0.2 * k))) != 0
    pat.setflags(write=False)
    return pat


def jacobian_sparsity(params: Params, oscillator: bool = True) -> np.ndarray:
    """Boolean (n, n) pattern of the Jacobian of the autonomous vector field, per grid and rotor kind
    (``oscillator=False``: of the core system, the oscillator's two states left out).

    Film pressures couple to their grid neighbours, their foil strip and the journal; only the journal
    accelerations (the bearing force integrates every pressure) are dense rows.  Measured as the union of the
    non-zeros at random open-film states where every gauge pressure is positive (the exact Gumbel kink
    ``max(p-1, 0)`` active), so it holds for any state and any physical parameters of that grid.  The options
    ``gumbel="pressure"`` and ``foil_springs`` only remove entries off the diagonal (a clipped node's row keeps its
    diagonal, an unsprung strip's row is its diagonal), so the default options' pattern covers them; the axial
    domain changes the grid and is part of the key.
    """
    pat = _pattern_cached(params.Nx, params.Nz, params.rotor, float(params.gumbel_width), params.axial_domain)
    return pat if oscillator else pat[:-2, :-2]
