"""Bump-foil strips, Eq. (10), with the Gumbel treatment of DESIGN.md.

Each of the ``Nx - 1`` top-foil strips is a massless spring ``k_f = 1/alpha_f`` and damper
``c_f = eta k_f / Omega_bar`` (structural loss factor at synchronous motion; the paper's ``c_f = eta k_f`` lacks the
``1/Omega``), driven by the strip mean gauge pressure; a sub-ambient film does not pull the foil:

    c_f q' + k_f q = max(p_m - 1, 0)   =>   q' = Omega_bar (alpha_f max(p_m - 1, 0) - q) / eta.
"""

from __future__ import annotations

from jax import Array

__all__ = ["foil_rates", "static_foil_deflection"]


def foil_rates(q: Array, drive: Array, omega: Array, alpha_f: Array, eta: Array) -> Array:
    """dq/dtau of the strips, Eq. (10); ``drive = max(p_m - 1, 0)`` per strip."""
    return omega * (alpha_f * drive - q) / eta


def static_foil_deflection(drive: Array, alpha_f: Array) -> Array:
    """Static strip deflection ``q = max(p_m - 1, 0) / k_f``."""
    return alpha_f * drive
