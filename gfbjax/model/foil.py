"""Bump-foil strips, Eq. (10), with the Gumbel treatment of docs/model.md.

Each of the ``Nx - 1`` top-foil strips is a massless spring ``k_f = 1/alpha_f`` and damper ``c_f``, driven by the
strip mean gauge pressure; a sub-ambient film does not pull the foil.  Two damping conventions
(``SystemSpec.foil_damping``, carried by ``Params.structural_damping`` as 1 or 0):

* ``"structural"`` (1, default): ``c_f = eta k_f / Omega_bar``, a structural loss factor at synchronous motion (the
  paper's ``c_f = eta k_f`` lacks the ``1/Omega``);
* ``"paper"`` (0): ``c_f = eta k_f``, Eq. (10) as printed.

    c_f q' + k_f q = max(p_m - 1, 0)   =>   q' = (alpha_f max(p_m - 1, 0) - q) / eta * (Omega_bar if structural)

Spring count (``SystemSpec.foil_springs``): one spring under every strip (``"all"``, default: ``Nx - 1`` springs,
as Eq. 10 counts them), or ``Nx - 2`` springs as the text of Sect. 2.1 counts them, the strip without one being
held at the housing: the first strip after the fixed end theta0 in the direction of rotation (``"no_first"``) or
the last one before theta0 + 2 pi (``"no_last"``); see :func:`supported_drive`.
"""

from __future__ import annotations

from typing import Any

from jax import Array

__all__ = ["FOIL_DAMPING", "FOIL_SPRINGS", "foil_rates", "foil_damping_coefficient", "static_foil_deflection",
           "supported_drive"]

#: The foil damping conventions by name (same tuple as :data:`gfbjax.params.FOIL_DAMPING`) and their number.
FOIL_DAMPING = ("structural", "paper")
_STRUCTURAL = {"structural": 1.0, "paper": 0.0}
#: The spring counts by name (same tuple as :data:`gfbjax.params.FOIL_SPRINGS`); see :func:`supported_drive`.
FOIL_SPRINGS = ("all", "no_first", "no_last")


def _speed_factor(omega: Array, structural: Any) -> Array:
    """``c_f / (eta k_f)`` inverted: ``Omega_bar`` (structural = 1 or "structural"), 1 (0 or "paper"), a blend
    ``s Omega_bar + 1 - s`` in between."""
    if isinstance(structural, str):
        if structural not in _STRUCTURAL:
            from ..params import ParameterError

            raise ParameterError(f"foil_damping = {structural!r} is not one of {FOIL_DAMPING}")
        structural = _STRUCTURAL[structural]
    return structural * omega + (1.0 - structural)


def foil_damping_coefficient(omega: Array, alpha_f: Array, eta: Array, structural: Any = 1.0) -> Array:
    """Dimensionless strip damping ``c_f_bar`` (Eq. 10) [p0 t* / c]: ``eta / (alpha_f Omega_bar)`` for
    ``structural = 1`` (or ``"structural"``), ``eta / alpha_f`` for ``structural = 0`` (or ``"paper"``)."""
    return eta / (alpha_f * _speed_factor(omega, structural))


def foil_rates(q: Array, drive: Array, omega: Array, alpha_f: Array, eta: Array, structural: Any = 1.0) -> Array:
    """dq/dtau of the strips, Eq. (10); ``drive = max(p_m - 1, 0)`` per strip [p0], ``q`` over c.

    ``q' = (drive - k_f q) / c_f`` with ``k_f = 1/alpha_f`` and ``c_f`` of :func:`foil_damping_coefficient`
    (``structural``: ``Params.structural_damping``, 1 or 0, or the convention's name)."""
    return _speed_factor(omega, structural) * (alpha_f * drive - q) / eta


def static_foil_deflection(drive: Array, alpha_f: Array) -> Array:
    """Static strip deflection ``q = max(p_m - 1, 0) / k_f``."""
    return alpha_f * drive


def supported_drive(drive: Array, foil_springs: str = "all") -> Array:
    """The strip drive ``max(p_m - 1, 0)`` [p0] with the strip that has no spring unloaded (Sect. 2.1).

    ``drive`` has one value per strip, shape (Nx - 1,), ordered from the fixed end theta0 in the direction of
    rotation.  ``"all"`` returns it unchanged; ``"no_first"`` / ``"no_last"`` zero its first / last entry: that strip
    then relaxes to ``q = 0`` and stays there, which is a strip held at the housing (its damper-only equation is
    decoupled, so it adds the eigenvalue ``-Omega_bar / eta`` (structural) and moves no other).

    Raises:
        ParameterError: ``foil_springs`` is not one of :data:`FOIL_SPRINGS`.
    """
    if foil_springs == "all":
        return drive
    if foil_springs == "no_first":
        return drive.at[0].set(0.0)
    if foil_springs == "no_last":
        return drive.at[-1].set(0.0)
    from ..params import ParameterError

    raise ParameterError(f"foil_springs = {foil_springs!r} is not one of {FOIL_SPRINGS}")
