"""Bump-foil geometry <-> dimensionless compliance ``alpha_f``, both ways.

The forward relation is :func:`gfbjax.params.bump_foil_compliance` (paper, Abbreviations; Heshmat's bump formula)::

    alpha_f = 2 p0 (l0 / t_b)^3 (1 - nu^2) s0 / (c E)

with ``l0`` the bump half length, ``t_b`` the foil thickness, ``s0`` the bump pitch [m], ``E`` Young's modulus [Pa],
``nu`` Poisson's ratio, ``p0`` the ambient pressure [Pa] and ``c`` the radial clearance [m].  It is monotonic in
each quantity, so any one of ``t_b``, ``l0``, ``s0`` or ``E`` follows from ``alpha_f`` and the others
(:func:`bump_parameter_for_compliance`):

    t_b = l0 (2 p0 (1 - nu^2) s0 / (c E alpha_f))^(1/3)        l0 = t_b (alpha_f c E / (2 p0 (1 - nu^2) s0))^(1/3)
    s0  = alpha_f c E / (2 p0 (l0/t_b)^3 (1 - nu^2))            E  = 2 p0 (l0/t_b)^3 (1 - nu^2) s0 / (c alpha_f)

A solution is refused when it is not a bump foil: the formula is that of a thin curved beam, so the foil must be
thinner than the bump's half length (``t_b < l0``), and bumps do not overlap (``s0 >= 2 l0``).
"""

from __future__ import annotations

from .. import limits
from ..limits import ParameterError
from ..params import bump_foil_compliance

__all__ = ["BUMP_QUANTITIES", "bump_parameter_for_compliance", "bump_foil_compliance"]

#: The quantities :func:`bump_parameter_for_compliance` can solve for, with their units.
BUMP_QUANTITIES = {"t_b": "m", "l0": "m", "s0": "m", "E": "Pa"}


def _fmt(name: str, v: float) -> str:
    if BUMP_QUANTITIES.get(name) == "m":
        return f"{v * 1e3:.6g} mm"
    if name == "E":
        return f"{v / 1e9:.6g} GPa"
    return f"{v:.6g}"


def bump_parameter_for_compliance(alpha_f: float, solve_for: str, *, l0: float | None = None,
                                  t_b: float | None = None, s0: float | None = None, E: float | None = None,
                                  nu: float, p0: float, c: float) -> float:
    """The bump-foil quantity ``solve_for`` (``"t_b"``, ``"l0"``, ``"s0"`` or ``"E"``) that gives the dimensionless
    compliance ``alpha_f`` with the other three (inverse of :func:`gfbjax.params.bump_foil_compliance`; formulas in
    the module doc).

    Args:
        alpha_f: dimensionless compliance per area [-], in (0, 100] (:data:`gfbjax.limits.ALPHA_F`).
        solve_for: which quantity to return.
        l0, t_b, s0: bump half length, foil thickness, bump pitch [m], > 0; the one solved for is left None.
        E: Young's modulus of the foil [Pa], > 0.
        nu: Poisson's ratio [-], in [0, 0.5).
        p0: ambient pressure [Pa], > 0.
        c: radial clearance [m], > 0.

    Returns:
        The quantity in SI units (m or Pa).

    Raises:
        ParameterError: an unknown ``solve_for``; a known quantity missing, given for the solved one, or out of its
            range; or a result that is no bump foil, naming the quantity and its allowed range (``t_b`` in
            ``(0, l0)``, ``l0`` in ``(t_b, s0/2]``, ``s0 >= 2 l0``) and the ``alpha_f`` range the other values allow.
    """
    if solve_for not in BUMP_QUANTITIES:
        raise ParameterError(f"solve_for = {solve_for!r} is not one of {sorted(BUMP_QUANTITIES)}")
    alpha_f = limits.ALPHA_F.check(alpha_f)
    known = {"l0": l0, "t_b": t_b, "s0": s0, "E": E}
    if known[solve_for] is not None:
        raise ParameterError(f"{solve_for} is the quantity solved for: leave it out (got {solve_for} = "
                             f"{known[solve_for]!r})")
    for name, v in known.items():
        if name == solve_for:
            continue
        if v is None:
            raise ParameterError(f"{name} is needed to solve for {solve_for} (give all of l0, t_b, s0, E but the "
                                 "one solved for)")
        known[name] = limits.POSITIVE.check(v, name)
    nu = limits.POISSON.check(nu)
    p0 = limits.POSITIVE.check(p0, "p0")
    c = limits.POSITIVE.check(c, "c")
    a = 2.0 * p0 * (1.0 - nu**2) / c  # alpha_f = a (l0/t_b)^3 s0 / E
    l0, t_b, s0, E = known["l0"], known["t_b"], known["s0"], known["E"]
    if solve_for == "t_b" and s0 < 2.0 * l0:
        raise ParameterError(f"s0 = {_fmt('s0', s0)} is outside the allowed range [2 l0 = {_fmt('s0', 2.0 * l0)}, "
                             "inf) (bumps do not overlap)")
    if solve_for == "t_b":
        value = l0 * (a * s0 / (E * alpha_f)) ** (1.0 / 3.0)
        ok = value < l0
        bound = f"(0, l0 = {_fmt('l0', l0)}) (the foil must be thinner than the bump half length)"
        alpha_range = f"alpha_f > {a * s0 / E:.6g}"
    elif solve_for == "l0":
        value = t_b * (alpha_f * E / (a * s0)) ** (1.0 / 3.0)
        ok = t_b < value <= 0.5 * s0
        bound = (f"(t_b = {_fmt('t_b', t_b)}, s0/2 = {_fmt('l0', 0.5 * s0)}] (thicker than the foil, bumps that do "
                 "not overlap)")
        alpha_range = (f"alpha_f in ({a * s0 / E:.6g}, {a * (0.5 * s0 / t_b) ** 3 * s0 / E:.6g}]")
    elif solve_for == "s0":
        value = alpha_f * E / (a * (l0 / t_b) ** 3)
        ok = value >= 2.0 * l0 and t_b < l0
        bound = f"[2 l0 = {_fmt('s0', 2.0 * l0)}, inf) (bumps do not overlap)"
        alpha_range = f"alpha_f >= {a * (l0 / t_b) ** 3 * 2.0 * l0 / E:.6g}"
        if not t_b < l0:
            raise ParameterError(f"t_b = {_fmt('t_b', t_b)} is outside the allowed range (0, l0 = {_fmt('l0', l0)}) "
                                 "(the foil must be thinner than the bump half length)")
    else:
        value = a * (l0 / t_b) ** 3 * s0 / alpha_f
        ok = t_b < l0 and s0 >= 2.0 * l0
        bound = "(0, inf) with t_b < l0 and s0 >= 2 l0"
        alpha_range = "any alpha_f in (0, 100]"
        if not ok:
            raise ParameterError(f"bump geometry l0 = {_fmt('l0', l0)}, t_b = {_fmt('t_b', t_b)}, s0 = "
                                 f"{_fmt('s0', s0)} is no bump foil: t_b must be below l0 and s0 at least 2 l0")
    if not ok:
        raise ParameterError(f"{solve_for} = {_fmt(solve_for, value)} is outside the allowed range {bound}: "
                             f"alpha_f = {alpha_f:g} is not attainable with the other values ({alpha_range})")
    return float(value)
