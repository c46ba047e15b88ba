"""Compressible Reynolds equation on the finite-difference grid: pressure rates (Eq. 2b, as corrected in
docs/model.md), film thickness (Eq. 3), bearing forces (Eq. 7) and strip mean pressure (Eq. 9).

All quantities are dimensionless: ``p = p/p0``, ``h = h/c``, time ``tau = t/t*``, speed ``Omega_bar`` (= the
bearing number Lambda).  The discretisation is conservative and second order: Poiseuille fluxes on cell faces with
the face coefficient ``p h^3`` averaged from the two nodes, and a central difference for the Couette term.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jax import Array

from .grid import Grid

__all__ = ["gauge", "film_thickness", "pressure_rates", "bearing_force", "mean_gauge_pressure"]


def gauge(x: Array, width: float = 0.0) -> Array:
    """Gumbel's condition ``max(x, 0)`` for a gauge pressure x; with ``width > 0`` the smooth
    ``width * softplus(x / width)`` (exceeds max(x, 0) by at most ``width * ln 2``, at x = 0)."""
    if width == 0.0:
        return jnp.maximum(x, 0.0)
    return width * jax.nn.softplus(x / width)


def film_thickness(theta: Array, x: Array, y: Array, q: Array | float = 0.0) -> Array:
    """Film thickness ``h = 1 - x cos(theta) - y sin(theta) + q``, Eq. (3), for a journal at (x, y)/c."""
    return 1.0 - x * jnp.cos(theta) - y * jnp.sin(theta) + q


def _pad(P: Array, h: Array, grid: Grid) -> tuple[Array, Array]:
    """Pressure with boundary and mirror nodes: theta (ends p=1 or periodic), z (edge p=1, mid-plane mirror).

    ``h`` must already include the end nodes for the foil bearing (length Nx+1) or be periodic (length Nx).
    Returns the padded pressure (n_theta+2, Nz+2) and film (n_theta+2,) with one neighbour on each side.
    """
    ones = jnp.ones((P.shape[0], 1), P.dtype)
    Pz = jnp.concatenate([ones, P, P[:, -2:-1]], axis=1)  # edge j=0, unknowns 1..Nz, mirror of Nz-1
    if grid.periodic:
        Pp = jnp.concatenate([Pz[-1:], Pz, Pz[:1]], axis=0)
        hp = jnp.concatenate([h[-1:], h, h[:1]])
    else:
        row = jnp.ones((1, Pz.shape[1]), P.dtype)
        Pp = jnp.concatenate([row, Pz, row], axis=0)
        hp = h
    return Pp, hp


def pressure_rates(P: Array, h: Array, hdot: Array, omega: Array, kappa: Array, grid: Grid) -> Array:
    """dp/dtau at the unknowns, Eq. (2b) (corrected, docs/model.md):

    ``p' = [ 1/2 d/dth(p h^3 dp/dth) + kappa^2/2 d/dz(p h^3 dp/dz) - Omega/2 d/dth(p h) ] / h - p h'/h``.

    Args:
        P: pressures at the unknowns, shape (n_theta, Nz).
        h: film thickness at all circumferential nodes: (Nx+1,) for the foil bearing (ends included),
            (Nx,) for the periodic bearing.
        hdot: dh/dtau at the unknowns, shape (n_theta,).
        omega: speed Omega_bar.
        kappa: R / L.
        grid: the grid.
    """
    Pp, hp = _pad(P, h, grid)
    dth, dz = grid.dtheta, grid.dz
    h3 = hp[:, None] ** 3
    a = Pp * h3  # p h^3 at every padded node
    # circumferential Poiseuille flux on faces i+1/2, then its divergence at the unknowns
    a_face = 0.5 * (a[1:, 1:-1] + a[:-1, 1:-1])
    flux_t = a_face * (Pp[1:, 1:-1] - Pp[:-1, 1:-1]) / dth
    div_t = (flux_t[1:] - flux_t[:-1]) / dth
    # axial flux on faces j+1/2 (h does not vary along z)
    az_face = 0.5 * (a[1:-1, 1:] + a[1:-1, :-1])
    flux_z = az_face * (Pp[1:-1, 1:] - Pp[1:-1, :-1]) / dz
    div_z = (flux_z[:, 1:] - flux_z[:, :-1]) / dz
    # Couette term, central difference of p h
    ph = Pp[:, 1:-1] * hp[:, None]
    conv = (ph[2:] - ph[:-2]) / (2.0 * dth)
    hc = hp[1:-1, None]
    return (0.5 * div_t + 0.5 * kappa**2 * div_z - 0.5 * omega * conv) / hc - P * hdot[:, None] / hc


def bearing_force(P: Array, theta: Array, grid: Grid, width: float = 0.0, gumbel: bool = True) -> Array:
    """Gas force on the journal over the whole bearing length, Eq. (7), in units of ``p0 R L``.

    ``F = -int_0^2pi int_0^1 g(p - 1) (cos th, sin th) dz dth`` with g the Gumbel ``max(., 0)`` (or the identity
    when ``gumbel`` is False, for the plain bearing).  Trapezoid rule; the half domain counts twice.
    """
    gp = gauge(P - 1.0, width) if gumbel else P - 1.0
    col = 2.0 * gp @ grid.z_weights()  # integral over the full length, per circumferential node
    w = grid.dtheta * col
    return -jnp.stack([jnp.sum(w * jnp.cos(theta)), jnp.sum(w * jnp.sin(theta))])


def mean_gauge_pressure(P: Array, grid: Grid) -> Array:
    """Strip mean gauge pressure ``p_m - 1`` over the bearing length, Eq. (9), trapezoid rule."""
    return 2.0 * (P - 1.0) @ grid.z_weights()
