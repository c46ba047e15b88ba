"""Rotor equations of motion (Eq. 12), unbalance forcing (Eq. 15a/b, 22) and the phase oscillator (Eq. 19).

Jeffcott rotor (4 DoF; both journals move alike by symmetry), state ``[x_j, y_j, x_d, y_d, x_j', y_j', x_d', y_d']``:

    x_j'' = m_d/(2 m_j) k_s (x_d - x_j) + zeta F_BX
    y_j'' = m_d/(2 m_j) k_s (y_d - y_j) + zeta (F_BY - w_ext) - sigma
    x_d'' = -k_s (x_d - x_j) + F_UX
    y_d'' = -k_s (y_d - y_j) + F_UY - sigma

Rigid rotor (2 DoF), state ``[x_j, y_j, x_j', y_j']``: ``x'' = zeta F_BX + F_UX``,
``y'' = zeta (F_BY - w_ext) - sigma + F_UY``.  y points up; gravity and the extra load ``w_ext`` act downwards.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array

__all__ = ["rotor_rates", "unbalance_force", "unbalance_force_runup", "oscillator_rates", "N_ROTOR"]

N_ROTOR = {"jeffcott": 8, "rigid": 4}


def rotor_rates(r: Array, F_B: Array, F_U: Array, params) -> Array:
    """d/dtau of the rotor state, Eq. (12); ``F_B`` gas force per bearing [p0 R L], ``F_U`` unbalance
    acceleration of the disc (rigid rotor: of the journal) as in Eq. (15)."""
    zeta, sigma = params.zeta, params.sigma
    fb = zeta * (F_B - jnp.array([0.0, 1.0]) * params.w_ext) - jnp.array([0.0, sigma])
    if params.rotor == "rigid":
        return jnp.concatenate([r[2:4], fb + F_U])
    xj, xd, vj, vd = r[0:2], r[2:4], r[4:6], r[6:8]
    spring = params.k_s * (xd - xj)
    aj = params.mass_ratio * spring + fb
    ad = -spring + F_U - jnp.array([0.0, sigma])
    return jnp.concatenate([vj, vd, aj, ad])


def unbalance_force(omega: Array, eps: Array, cos_phi: Array, sin_phi: Array) -> Array:
    """Unbalance forcing at constant speed, Eq. (15a)/(22): ``eps Omega^2 (cos phi, sin phi)``."""
    return eps * omega**2 * jnp.stack([cos_phi, sin_phi])


def unbalance_force_runup(omega: Array, accel: Array, eps: Array, phi: Array) -> Array:
    """Unbalance forcing during a run-up at constant angular acceleration ``accel``, Eq. (15b)."""
    c, s = jnp.cos(phi), jnp.sin(phi)
    return eps * jnp.stack([omega**2 * c + accel * s, omega**2 * s - accel * c])


def oscillator_rates(u: Array, v: Array, omega: Array) -> Array:
    """Phase oscillator with the stable limit cycle ``(u, v) = (cos Omega tau, sin Omega tau)``.

    Eq. (19) of the paper as printed rotates the other way (its solution is ``(cos, -sin)``, contradicting
    Eq. 20); the sign of the Omega terms is corrected here so that Eq. (20) and (22) hold.
    """
    r2 = u * u + v * v
    return jnp.stack([u - omega * v - u * r2, omega * u + v - v * r2])
