"""Physical (SI) description of a rotor on two gas foil bearings and its dimensionless groups.

Everything a user types is SI (or a dimensionless design value that the paper itself quotes, such as
``alpha_f`` or ``k_s_bar``).  :func:`SystemSpec.nondim` turns it into :class:`Params`, the equinox PyTree
that every solver in gfbjax consumes.  Conventions follow docs/model.md (corrected Eq. 14 of the paper):

* time scale ``t* = 6 mu R^2 / (p0 c^2)`` [s]; dimensionless time ``tau = t / t*``;
* speed ``Omega_bar = Omega t*`` — identical to the bearing number ``Lambda = 6 mu Omega R^2 / (p0 c^2)``;
* lengths over the radial clearance ``c``; pressures over ambient ``p0``; forces over ``p0 R L``;
* ``zeta = p0 R L t*^2 / (m_j c)`` (gas force -> journal acceleration);
* ``sigma = g t*^2 / c`` (gravity; the paper prints R^2 where R^4 belongs);
* ``k_s_bar = k_s t*^2 / m_d`` (shaft lateral stiffness at the disc);
* ``alpha_f`` bump-foil compliance per area, ``p0 * (compliance [m/Pa]) / c``; ``k_f_bar = 1 / alpha_f``;
* ``eta`` structural loss factor of the foil, ``c_f_bar = eta k_f_bar / Omega_bar``;
* ``kappa = R / L``; ``eps = e_u / c`` unbalance eccentricity, with ``e_u = G / Omega_r`` (ISO 1940, G in mm/s,
  ``Omega_r = 2500 rad/s`` by default) unless ``e_u`` is given.

Three of these readings of the paper are switches of :class:`SystemSpec`, recorded with every result
(``SystemSpec.to_dict``); :data:`PRESETS` names the two consistent sets, ``"corrected"`` (the defaults) and
``"paper"`` (the paper read literally); docs/model.md explains each one:

* ``foil_damping``: ``"structural"`` (``c_f_bar = eta k_f_bar / Omega_bar``) or ``"paper"``
  (``c_f_bar = eta k_f_bar``, Eq. 10 as printed);
* ``unbalance_mass``: ``"disc"`` (Eq. 15a: the disc's acceleration amplitude is ``e_u Omega^2``) or ``"rotor"``
  (the unbalance ``u = (m_d + 2 m_j) e_u`` of the whole rotor is carried by the disc: ``eps`` grows by
  ``(m_d + 2 m_j) / m_d``);
* ``omega_r_unit``: the unit of ``omega_r`` in ``e_u = G / omega_r``: ``"rad/s"`` or ``"rpm"`` (the paper's worked
  example of Eq. 16: G6.3 at 2500 rpm gives 24.1 um).

Three more switches are model options where the paper's Sect. 2.1 can be built more than one way; they are not
part of the presets, and their defaults are the model that every result of the project was computed with:

* ``gumbel``: ``"forces"`` (the Gumbel ``max(p - 1, 0)`` in the bearing force and the foil drive) or ``"pressure"``
  (the film pressure itself kept at or above ambient, :func:`gfbjax.model.reynolds.ambient_clipped_rates`);
* ``foil_springs``: ``"all"`` (a spring under each of the ``Nx - 1`` strips) or ``"no_first"`` / ``"no_last"``
  (``Nx - 2`` springs as the text counts them, the strip next to the fixed end held at the housing);
* ``axial_domain``: ``"half"`` (half length, mid-plane symmetry) or ``"full"`` (whole length, ambient at both edges).
"""

from __future__ import annotations

import dataclasses
import math
import os
import sys
import tomllib
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import limits
from .limits import ParameterError

__all__ = [
    "SystemSpec",
    "Params",
    "check_params",
    "ParameterError",
    "reference_system",
    "variation",
    "validation_case",
    "VARIATIONS",
    "load_config",
    "system_from_name_or_file",
    "bump_foil_compliance",
    "unbalance_eccentricity",
    "FOIL_DAMPING",
    "UNBALANCE_MASS",
    "OMEGA_R_UNITS",
    "PRESETS",
    "GUMBEL",
    "FOIL_SPRINGS",
    "AXIAL_DOMAINS",
]

ROTORS = ("jeffcott", "rigid")
#: Foil damping conventions: ``c_f_bar = eta k_f_bar / Omega_bar`` (structural loss factor) or ``eta k_f_bar``.
FOIL_DAMPING = ("structural", "paper")
#: Unbalance conventions: ``eps = e_u / c`` on the disc (Eq. 15a) or ``u = (m_d + 2 m_j) e_u`` carried by the disc.
UNBALANCE_MASS = ("disc", "rotor")
#: Units of ``omega_r`` in ``e_u = G / omega_r`` (Eq. 16).
OMEGA_R_UNITS = ("rad/s", "rpm")
#: Where the Gumbel condition acts: bearing force and foil drive only, or the film pressure itself (Sect. 2.1).
GUMBEL = ("forces", "pressure")
#: Foil springs: one under every strip, or ``Nx - 2`` with the first / last strip from the fixed end held (Sect. 2.1).
FOIL_SPRINGS = ("all", "no_first", "no_last")
#: Axial extent of the film grid: half length with the mid-plane symmetry condition (Eq. 5), or the whole length.
AXIAL_DOMAINS = ("half", "full")
#: Named sets of the three convention switches: the project's corrected reading (the defaults) and the paper's
#: literal one.  ``SystemSpec.with_preset(name)`` applies one.
PRESETS: dict[str, dict[str, str]] = {
    "corrected": {"foil_damping": "structural", "unbalance_mass": "disc", "omega_r_unit": "rad/s"},
    "paper": {"foil_damping": "paper", "unbalance_mass": "rotor", "omega_r_unit": "rpm"},
}


def _check_choice(name: str, value: Any, allowed: tuple[str, ...]) -> None:
    if not isinstance(value, str) or value not in allowed:
        raise ParameterError(f"{name} = {value!r} is not one of {allowed}")


def _check_preset(preset: Any) -> dict[str, str]:
    if not isinstance(preset, str) or preset not in PRESETS:
        raise ParameterError(f"preset = {preset!r} is not one of {tuple(PRESETS)}")
    return PRESETS[preset]


def bump_foil_compliance(l0: float, t_b: float, s0: float, E: float, nu: float, p0: float, c: float) -> float:
    """Dimensionless bump-foil compliance per area (paper, Abbreviations; Heshmat's bump formula [27]).

    ``alpha_f = 2 p0 (l0/t_b)^3 (1 - nu^2) s0 / (c E)``

    Args:
        l0: half length of one bump [m].
        t_b: foil thickness [m], below ``l0``.
        s0: bump pitch [m], at least ``2 l0``.
        E: Young's modulus of the foil [Pa].
        nu: Poisson's ratio [-], in [0, 0.5).
        p0: ambient pressure [Pa].
        c: radial clearance [m].
    """
    for name, v in (("l0", l0), ("t_b", t_b), ("s0", s0), ("E", E), ("p0", p0), ("c", c)):
        limits.POSITIVE.check(v, name)
    limits.POISSON.check(nu)
    # the formula is that of a thin curved beam: a foil thicker than the bump, or bumps that overlap, are no
    # bump foil, and the number it would give means nothing
    if not t_b < l0:
        raise ParameterError(f"t_b = {t_b:g} m is outside the allowed range (0, l0 = {l0:g} m): the foil must be "
                             "thinner than the bump half length")
    if not s0 >= 2.0 * l0:
        raise ParameterError(f"s0 = {s0:g} m is outside the allowed range [2 l0 = {2.0 * l0:g} m, inf): bumps do "
                             "not overlap")
    return 2.0 * p0 * (l0 / t_b) ** 3 * (1.0 - nu**2) * s0 / (c * E)


def unbalance_eccentricity(G: float, omega_r: float = 2500.0, unit: str = "rad/s") -> float:
    """Unbalance eccentricity ``e_u = G / Omega_r`` [m] for ISO 1940 grade ``G`` [mm/s] at service speed
    ``omega_r`` (paper Eq. 16).

    ``unit`` is the unit of ``omega_r``: ``"rad/s"`` (consistent units: G2.5 at 2500 rad/s gives 1.0 um) or
    ``"rpm"`` (the paper's worked example: G2.5 at 2500 rpm = 261.8 rad/s gives 9.55 um, G6.3 24.1 um)."""
    G = limits.BALANCE_GRADE.check(G)
    omega_r = limits.OMEGA_R.check(omega_r)
    _check_choice("omega_r_unit", unit, OMEGA_R_UNITS)
    rad_s = omega_r * 2.0 * math.pi / 60.0 if unit == "rpm" else omega_r
    return G * 1e-3 / rad_s


@dataclass(frozen=True)
class SystemSpec:
    """A flexible (Jeffcott) or rigid rotor on two identical gas foil bearings, in SI units.

    The defaults are the project's reference system (docs/model.md): ``R = 19.05 mm``, ``L/D = 1``,
    ``R/c = 500``, air at 20 C, ``k_s_bar = 1``, ``alpha_f = 0.1``, ``eta = 0.05``, unbalance G6.3.

    Attributes:
        R: journal radius [m].
        L: bearing length [m].
        c: nominal radial clearance [m].
        mu: gas dynamic viscosity [Pa s].
        p0: ambient pressure [Pa].
        g: gravitational acceleration [m/s^2] (0 for a vertical rotor).
        m_j: mass lumped at each journal [kg] (rigid rotor: rotor mass per bearing).
        m_d: disc mass [kg] (Jeffcott rotor only).
        k_s_bar: dimensionless shaft stiffness ``k_s t*^2 / m_d`` [-] (Jeffcott rotor only).
        alpha_f: dimensionless bump-foil compliance per area [-]; see :func:`bump_foil_compliance`.
        eta: structural loss factor of the bump foil [-].
        G: ISO 1940 balance grade [mm/s]; ignored when ``e_u`` is given.  0 is a balanced rotor.
        e_u: unbalance eccentricity [m]; overrides ``G``.  It is the mass eccentricity of the disc, not bounded by
            the clearance: a value above ``c`` is accepted with a warning.
        omega_r: service speed that defines ``e_u`` from ``G`` [rad/s, or rpm with ``omega_r_unit="rpm"``].
        rotor: ``"jeffcott"`` (4 DoF: journals + disc, Eq. 12) or ``"rigid"`` (2 DoF journal).
        theta0: angle of the foil's fixed end [rad], from the horizontal x axis towards the vertical y axis
            (y points up; the rotor spins from x towards y).  Default pi/2: the foil is clamped at the top.
        load: extra static vertical load per bearing [N], downwards, added to gravity.
        Nx: circumferential finite-difference intervals over the 2 pi of the foil, in [16, 1024].
        Nz: axial intervals over the half length (edge to mid-plane), in [2, 256].  The grid has
            ``(Nx - 1)(Nz + 1)`` film and foil states plus the rotor's; at most
            :data:`gfbjax.limits.MAX_DENSE_UNKNOWNS` (6144) in all, because every analysis builds dense Jacobians.
        gumbel_width: width of the smoothed ``max(p - 1, 0)`` of the Gumbel condition [-]; 0 = exact max.
        foil_damping: ``"structural"`` (default: ``c_f_bar = eta k_f_bar / Omega_bar``, a loss factor at
            synchronous motion) or ``"paper"`` (``c_f_bar = eta k_f_bar``, Eq. 10 as printed).
        unbalance_mass: ``"disc"`` (default, Eq. 15a: ``eps = e_u / c`` is the disc's unbalance) or ``"rotor"``
            (the paper's text: the unbalance ``u = (m_d + 2 m_j) e_u`` of the whole rotor sits on the disc, so the
            disc's forcing is ``(m_d + 2 m_j) / m_d`` times larger; the rigid rotor has no disc and is unaffected).
        omega_r_unit: unit of ``omega_r``: ``"rad/s"`` (default) or ``"rpm"`` (the paper's worked example).
        gumbel: where the Gumbel condition acts (Sect. 2.1): ``"forces"`` (default: ``max(p - 1, 0)`` in the bearing
            force and the foil drive; the film itself may go below ambient) or ``"pressure"`` (the film pressure is
            kept at or above ambient inside the Reynolds equation: steady films satisfy ``p >= 1`` with the
            complementarity of :func:`gfbjax.model.reynolds.ambient_clipped_rates`).
        foil_springs: ``"all"`` (default: one spring under each of the ``Nx - 1`` strips, Eq. 10) or
            ``"no_first"`` / ``"no_last"`` (``Nx - 2`` springs, the count of Sect. 2.1's text: the first strip after
            the fixed end theta0, in the direction of rotation, or the last one before theta0 + 2 pi, is held at
            ``q = 0``).
        axial_domain: ``"half"`` (default: edge to mid-plane with ``dp/dz = 0`` there, Eq. 5) or ``"full"`` (the whole
            length at the same spacing, ``2 Nz`` intervals, ambient at both edges; about twice the pressure states).

    :data:`PRESETS` names two sets of the last three fields: ``"corrected"`` (the defaults) and ``"paper"``;
    :meth:`with_preset` applies one, :attr:`preset` says which one a spec follows.

    Every field is checked on construction against its range in :mod:`gfbjax.limits` (ParameterError naming the
    field, the value and the range); NumPy numbers are accepted and stored as Python numbers.
    """

    R: float = 19.05e-3
    L: float = 38.1e-3
    c: float = 38.1e-6
    mu: float = 1.8e-5
    p0: float = 1.0e5
    g: float = 9.81
    m_j: float = 0.5
    m_d: float = 1.0
    k_s_bar: float = 1.0
    alpha_f: float = 0.1
    eta: float = 0.05
    G: float = 6.3
    e_u: float | None = None
    omega_r: float = 2500.0
    rotor: str = "jeffcott"
    theta0: float = math.pi / 2
    load: float = 0.0
    Nx: int = 48
    Nz: int = 8
    gumbel_width: float = 0.0
    foil_damping: str = "structural"
    unbalance_mass: str = "disc"
    omega_r_unit: str = "rad/s"
    gumbel: str = "forces"
    foil_springs: str = "all"
    axial_domain: str = "half"

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):  # NumPy / 0-d JAX numbers -> Python numbers (JSON, static jit fields)
            v = getattr(self, f.name)
            if isinstance(v, np.generic) or (hasattr(v, "__array__") and np.ndim(v) == 0
                                             and not limits.is_traced(v)):
                object.__setattr__(self, f.name, np.asarray(v).item())
        self.validate()

    # -- checks -------------------------------------------------------------------------------------------
    def validate(self) -> None:
        """Check every field against its range in :mod:`gfbjax.limits`; raise :class:`ParameterError` naming the
        first field out of range.  NumPy numbers are accepted (``Nx=np.int64(16)``)."""
        for name, rng in (("R", limits.R), ("L", limits.L)):
            rng.check(getattr(self, name))
        R = float(self.R)
        limits.CLEARANCE.with_bounds(hi=limits.MAX_CLEARANCE_OVER_R * R).check(self.c)
        for name, rng in (("mu", limits.MU), ("p0", limits.P0), ("g", limits.GRAVITY), ("m_j", limits.M_J)):
            rng.check(getattr(self, name))
        if not isinstance(self.rotor, str) or self.rotor not in ROTORS:
            raise ParameterError(f"rotor = {self.rotor!r} is not one of {ROTORS}")
        if self.rotor == "jeffcott":
            limits.M_D.check(self.m_d)
            limits.K_S_BAR.check(self.k_s_bar)
        limits.ALPHA_F.check(self.alpha_f)
        limits.ETA.check(self.eta)
        _check_choice("foil_damping", self.foil_damping, FOIL_DAMPING)
        _check_choice("unbalance_mass", self.unbalance_mass, UNBALANCE_MASS)
        _check_choice("omega_r_unit", self.omega_r_unit, OMEGA_R_UNITS)
        _check_choice("gumbel", self.gumbel, GUMBEL)
        _check_choice("foil_springs", self.foil_springs, FOIL_SPRINGS)
        _check_choice("axial_domain", self.axial_domain, AXIAL_DOMAINS)
        if self.e_u is None:
            limits.BALANCE_GRADE.check(self.G)
            limits.OMEGA_R.check(self.omega_r)
        else:
            limits.E_U.check(self.e_u)
        e_u = self.eccentricity_u
        if e_u > float(self.c):  # the disc's mass eccentricity is not bounded by the bearing clearance
            warnings.warn(f"unbalance eccentricity e_u = {e_u * 1e6:.4g} um exceeds the radial clearance "
                          f"c = {float(self.c) * 1e6:.4g} um (allowed: it is the disc's mass eccentricity, but the "
                          "journals may then touch the foil)", UserWarning, stacklevel=_outside_stacklevel())
        limits.THETA0.check(self.theta0)
        limits.LOAD.check(self.load)
        limits.check_grid(self.Nx, self.Nz, _n_rotor(self.rotor), self.axial_domain == "full")
        limits.GUMBEL_WIDTH.check(self.gumbel_width)

    # -- derived scales -----------------------------------------------------------------------------------
    @property
    def t_star(self) -> float:
        """Time scale ``t* = 6 mu R^2 / (p0 c^2)`` [s]."""
        return 6.0 * self.mu * self.R**2 / (self.p0 * self.c**2)

    @property
    def eccentricity_u(self) -> float:
        """Unbalance eccentricity ``e_u`` [m] (``e_u`` if given, else ``G / omega_r`` in ``omega_r_unit``)."""
        if self.e_u is not None:
            return self.e_u
        return unbalance_eccentricity(self.G, self.omega_r, self.omega_r_unit)

    @property
    def unbalance_factor(self) -> float:
        """Ratio of the disc's unbalance forcing to ``e_u Omega^2`` [-]: 1 with ``unbalance_mass="disc"``
        (Eq. 15a) or for the rigid rotor, ``(m_d + 2 m_j) / m_d`` with ``unbalance_mass="rotor"``."""
        if self.unbalance_mass == "rotor" and self.rotor == "jeffcott":
            return (self.m_d + 2.0 * self.m_j) / self.m_d
        return 1.0

    @property
    def preset(self) -> str:
        """``"corrected"`` or ``"paper"`` when the three convention switches match that preset, else ``"mixed"``."""
        for name, values in PRESETS.items():
            if all(getattr(self, k) == v for k, v in values.items()):
                return name
        return "mixed"

    def with_preset(self, preset: str) -> "SystemSpec":
        """A copy with the convention switches of :data:`PRESETS` ``[preset]`` (``"corrected"`` or ``"paper"``)."""
        return self.replace(**_check_preset(preset))

    @property
    def force_scale(self) -> float:
        """Force unit ``p0 R L`` [N] of dimensionless bearing forces."""
        return self.p0 * self.R * self.L

    @property
    def bearing_weight(self) -> float:
        """Static gravity load carried by each bearing [N]."""
        m = self.m_j + (self.m_d / 2 if self.rotor == "jeffcott" else 0.0)
        return m * self.g

    def omega_bar(self, rpm: float) -> float:
        """Dimensionless speed ``Omega_bar = Omega t*`` of a shaft speed in rev/min (finite and >= 0; NaN,
        infinity or a negative speed raise :class:`ParameterError`).  Arrays are converted element by element."""
        _check_speed("rpm", rpm)
        return rpm * 2 * math.pi / 60 * self.t_star

    def rpm(self, omega_bar: float) -> float:
        """Shaft speed in rev/min of a dimensionless speed (finite and >= 0; otherwise ParameterError)."""
        _check_speed("omega_bar", omega_bar)
        return omega_bar / self.t_star * 60 / (2 * math.pi)

    def replace(self, **changes: Any) -> "SystemSpec":
        """A copy with some fields changed (checked again)."""
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise ParameterError(f"unknown field(s) {sorted(unknown)}; allowed: {sorted(_FIELDS)}")
        return dataclasses.replace(self, **changes)

    def nondim(self) -> "Params":
        """The dimensionless groups (docs/model.md, corrected Eq. 14) as a :class:`Params` PyTree."""
        ts = self.t_star
        m_j = self.m_j
        jeff = self.rotor == "jeffcott"
        f = lambda v: jnp.asarray(float(v), dtype=jnp.float64)  # noqa: E731  (traced, not static, under jit)
        return Params(
            kappa=f(self.R / self.L),
            zeta=f(self.p0 * self.R * self.L * ts**2 / (m_j * self.c)),
            sigma=f(self.g * ts**2 / self.c),
            k_s=f(self.k_s_bar if jeff else 0.0),
            mass_ratio=f(self.m_d / (2.0 * m_j) if jeff else 0.0),
            alpha_f=f(self.alpha_f),
            eta=f(self.eta),
            eps=f(self.unbalance_factor * self.eccentricity_u / self.c),
            w_ext=f(self.load / self.force_scale),
            theta0=f(self.theta0),
            Nx=self.Nx,
            Nz=self.Nz,
            rotor=self.rotor,
            gumbel_width=self.gumbel_width,
            structural_damping=f(1.0 if self.foil_damping == "structural" else 0.0),
            gumbel=self.gumbel,
            foil_springs=self.foil_springs,
            axial_domain=self.axial_domain,
        )

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


_FIELDS = {f.name for f in dataclasses.fields(SystemSpec)}


def _n_rotor(rotor: str) -> int:
    """Rotor states of a rotor kind (gfbjax.model.rotor.N_ROTOR; imported here, not at the top: the model package
    imports this module)."""
    from .model.rotor import N_ROTOR

    return N_ROTOR[rotor]


def _outside_stacklevel() -> int:
    """The ``stacklevel`` for a warning raised in the caller of this function that names the first frame outside
    gfbjax (and outside the dataclass machinery that calls ``__post_init__``): the user's line."""
    package = os.path.dirname(os.path.abspath(__file__)) + os.sep
    frame, level = sys._getframe(1), 1
    # "<string>": the __init__ that dataclasses generates
    while frame is not None and (frame.f_code.co_filename.startswith(package)
                                 or frame.f_code.co_filename in ("<string>", dataclasses.__file__)):
        frame, level = frame.f_back, level + 1
    return level


def _check_speed(name: str, value: Any) -> None:
    """ParameterError unless every element of ``value`` is a finite speed >= 0 (tracers pass)."""
    _check_finite(name, value)
    if not limits.is_traced(value) and np.any(np.asarray(value, dtype=float) < 0.0):
        raise ParameterError(f"{name} must be >= 0 (a shaft speed; the direction of rotation is fixed by the "
                             f"model), got {value!r}")


def _check_finite(name: str, value: Any) -> None:
    """ParameterError unless every element of ``value`` is a finite real number (tracers pass)."""
    if limits.is_traced(value):
        return
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a real number, got {value!r}") from None
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name} must be finite, got {value!r}")


class Params(eqx.Module):
    """Dimensionless parameters of the GFB-rotor system (a PyTree: ``jax.grad``/``jax.vmap`` reach the floats).

    Float fields (all dimensionless): ``kappa = R/L``; ``zeta``, ``sigma`` (Eq. 14, corrected); ``k_s`` shaft
    stiffness ``k_s_bar``; ``mass_ratio = m_d / (2 m_j)`` (Eq. 12a); ``alpha_f`` foil compliance; ``eta`` foil
    loss factor; ``eps`` the disc's unbalance acceleration over ``c Omega^2`` (``e_u / c``, Eq. 15a, times
    ``SystemSpec.unbalance_factor``); ``w_ext`` extra vertical load per bearing over ``p0 R L``;
    ``theta0`` foil fixed end [rad]; ``structural_damping`` the foil damping convention (``SystemSpec.foil_damping``)
    as a number, so that switching it does not recompile: 1 for ``c_f = eta k_f / Omega_bar`` ("structural"), 0 for
    ``c_f = eta k_f`` ("paper"), values between blending the two as ``c_f = eta k_f / (s Omega_bar + 1 - s)``.
    Static fields (part of the tree structure; changing them recompiles): grid ``Nx``, ``Nz``, ``rotor`` kind,
    ``gumbel_width`` and the model options ``gumbel``, ``foil_springs``, ``axial_domain`` (as in
    :class:`SystemSpec`).  ``SystemSpec.nondim`` stores the floats
    as 0-d float64 arrays so that ``equinox.filter_jit`` traces them (no recompilation when a value changes).
    """

    kappa: Any
    zeta: Any
    sigma: Any
    k_s: Any
    mass_ratio: Any
    alpha_f: Any
    eta: Any
    eps: Any
    w_ext: Any
    theta0: Any
    Nx: int = eqx.field(static=True)
    Nz: int = eqx.field(static=True)
    rotor: str = eqx.field(static=True, default="jeffcott")
    gumbel_width: float = eqx.field(static=True, default=0.0)
    structural_damping: Any = 1.0
    gumbel: str = eqx.field(static=True, default="forces")
    foil_springs: str = eqx.field(static=True, default="all")
    axial_domain: str = eqx.field(static=True, default="half")

    def traced(self) -> "Params":
        """These parameters with every float leaf a 0-d float64 JAX array: ``equinox.filter_jit`` treats Python
        floats as static, so a solver called for many values of a parameter (a load ramp, several alpha_f) would
        recompile each time; array leaves are traced and compile once per grid."""
        return jax.tree_util.tree_map(lambda v: jnp.asarray(v, jnp.float64), self)

    def check(self) -> "Params":
        """Check the physical fields of concrete parameters against :mod:`gfbjax.limits` and return ``self``.

        ``kappa``, ``zeta`` > 0; ``sigma``, ``w_ext`` >= 0; ``alpha_f`` in (0, 100], ``eta`` in (0, 100] (as in
        :class:`SystemSpec`); ``eps`` >= 0; ``structural_damping`` in [0, 1]; ``theta0`` in [-2 pi, 2 pi]; for the
        Jeffcott rotor ``k_s`` and ``mass_ratio`` > 0; the grid and the model options as in :class:`SystemSpec`.  The
        analyses that take Params call it at their entry, so that hand-made Params (``eqx.tree_at``) are checked as
        a SystemSpec is.  Leaves that are JAX tracers (inside ``jit``/``vmap``/``grad``) are skipped; array leaves
        are checked element by element.
        Not run on construction: zero tangents and filter specs are Params too.
        """
        if not isinstance(self.rotor, str) or self.rotor not in ROTORS:
            raise ParameterError(f"rotor = {self.rotor!r} is not one of {ROTORS}")
        fields = [("kappa", limits.KAPPA), ("zeta", limits.ZETA), ("sigma", limits.SIGMA),
                  ("alpha_f", limits.ALPHA_F), ("eta", limits.ETA), ("eps", limits.EPS), ("w_ext", limits.W_EXT),
                  ("theta0", limits.THETA0)]
        if self.rotor == "jeffcott":
            fields += [("k_s", limits.K_S_BAR.with_bounds(name="k_s")),
                       ("mass_ratio", limits.MASS_RATIO)]
        for name, rng in fields:
            rng.check_all(getattr(self, name), f"Params.{name}")
        _check_choice("gumbel", self.gumbel, GUMBEL)
        _check_choice("foil_springs", self.foil_springs, FOIL_SPRINGS)
        _check_choice("axial_domain", self.axial_domain, AXIAL_DOMAINS)
        limits.check_grid(self.Nx, self.Nz, _n_rotor(self.rotor), self.axial_domain == "full")
        limits.GUMBEL_WIDTH.check(self.gumbel_width)
        limits.STRUCTURAL_DAMPING.check_all(self.structural_damping, "Params.structural_damping")
        return self


# -- named systems ----------------------------------------------------------------------------------------

def reference_system(preset: str | None = None, **overrides: Any) -> SystemSpec:
    """The project's reference system (docs/model.md): k_s_bar = 1, alpha_f = 0.1, eta = 0.05, G6.3.

    ``preset``: ``"corrected"`` (the defaults) or ``"paper"`` (the paper's literal conventions, :data:`PRESETS`),
    applied before ``overrides``; None keeps the defaults."""
    return variation("reference", preset=preset, **overrides)


VARIATIONS: dict[str, dict[str, Any]] = {
    "reference": {},
    "ks0.3": {"k_s_bar": 0.3},
    "ks3": {"k_s_bar": 3.0},
    "af0.01": {"alpha_f": 0.01},
    "af1": {"alpha_f": 1.0},
    "eta0.005": {"eta": 0.005},
    "eta0.5": {"eta": 0.5},
    "G0": {"G": 0.0},
    "G1": {"G": 1.0},
    "G2.5": {"G": 2.5},
    "G6.3": {"G": 6.3},
}


def validation_case(load_per_bearing: float = 10.0, preset: str | None = None,
                    mass_per_bearing: float | None = None, **overrides: Any) -> SystemSpec:
    """The paper's validation case (Table 1; Zhou et al. 2021): rigid rotor, balanced, on two GFBs.

    ``k_f = 4.6417 GN/m^3`` gives ``alpha_f = p0 / (k_f c)``; the rotor mass per bearing is ``load / g`` unless
    ``mass_per_bearing`` is given.

    Args:
        load_per_bearing: static load per bearing [N] (10 N in the text, 15 N in Table 1).
        preset: convention preset applied before ``overrides`` (:data:`PRESETS`); None keeps the defaults.
        mass_per_bearing: rotor mass per bearing [kg], > 0.  None (default): ``load_per_bearing / g``, the load
            being the rotor's weight.  Given: a rotor of this mass carrying the static load ``load_per_bearing`` as
            an external force (``g = 0``, ``load = load_per_bearing``).  The model sees only the sum of weight and
            external load, so this is also a rotor of that mass under its own weight plus the external force
            ``load_per_bearing - m g``.  The paper's Table 1 gives no rotor mass.

    Raises:
        ParameterError: a value out of range (naming it) or an unknown field in ``overrides``.
    """
    limits.LOAD_PER_BEARING.check(load_per_bearing)
    p0, c, g = 1.01325e5, 31.8e-6, 9.81
    spec = dict(R=19.05e-3, L=38.1e-3, c=c, mu=1.95e-5, p0=p0, g=g, m_j=load_per_bearing / g, m_d=1.0,
                alpha_f=p0 / (4.6417e9 * c), eta=0.25, G=0.0, rotor="rigid")
    if mass_per_bearing is not None:
        m = limits.M_J.check(mass_per_bearing, "mass_per_bearing")
        spec.update(m_j=m, g=0.0, load=load_per_bearing)
    if preset is not None:
        spec.update(_check_preset(preset))
    unknown = set(overrides) - _FIELDS
    if unknown:
        raise ParameterError(f"unknown field(s) {sorted(unknown)}; allowed: {sorted(_FIELDS)}")
    spec.update(overrides)
    return SystemSpec(**spec)


def variation(name: str, preset: str | None = None, **overrides: Any) -> SystemSpec:
    """A named system: ``reference``, a design variation of the paper (``ks0.3``, ``ks3``, ``af0.01``, ``af1``,
    ``eta0.005``, ``eta0.5``, ``G0``, ``G1``, ``G2.5``, ``G6.3``) or ``validation10N`` / ``validation15N``.

    ``preset``: ``"corrected"`` or ``"paper"`` (:data:`PRESETS`), applied before ``overrides``; None: defaults."""
    conventions = _check_preset(preset) if preset is not None else {}
    if name in VARIATIONS:
        unknown = set(overrides) - _FIELDS
        if unknown:
            raise ParameterError(f"unknown field(s) {sorted(unknown)}; allowed: {sorted(_FIELDS)}")
        return SystemSpec(**{**VARIATIONS[name], **conventions, **overrides})
    if name in ("validation10N", "validation15N"):
        return validation_case(10.0 if name == "validation10N" else 15.0, preset=preset, **overrides)
    allowed = sorted(VARIATIONS) + ["validation10N", "validation15N"]
    raise ParameterError(f"system = {name!r} is not a named system; allowed: {allowed} or a .toml file")


def load_config(path: str | Path) -> SystemSpec:
    """Read a TOML file of :class:`SystemSpec` fields (SI units).  An optional ``base`` key names a built-in
    system to start from, an optional ``preset`` key (``"corrected"`` or ``"paper"``) its conventions.  Unknown keys
    are an error naming them."""
    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"config file {str(path)!r} does not exist")
    with path.open("rb") as fh:
        try:
            data = tomllib.load(fh)
        except tomllib.TOMLDecodeError as exc:
            raise ParameterError(f"config file {str(path)!r} is not valid TOML: {exc}") from exc
    base = data.pop("base", "reference")
    preset = data.pop("preset", None)
    if not isinstance(base, str):
        raise ParameterError(f"base = {base!r} in {str(path)!r} must be the name of a built-in system (a string), "
                             "e.g. base = \"reference\"")
    unknown = set(data) - _FIELDS
    if unknown:
        raise ParameterError(f"unknown key(s) {sorted(unknown)} in {str(path)!r}; allowed: {sorted(_FIELDS)}, and "
                             "base (a built-in system) and preset (\"corrected\" or \"paper\")")
    return variation(base, preset=preset, **data)


def system_from_name_or_file(name: str) -> SystemSpec:
    """A named system (see :func:`variation`) or, for a path ending in ``.toml``, :func:`load_config`."""
    if name.endswith(".toml"):
        return load_config(name)
    return variation(name)


def check_params(params: Any, name: str = "params") -> Params:
    """``params`` checked (:meth:`Params.check`) and returned; the entry check of every analysis that takes the
    dimensionless parameters.  A :class:`SystemSpec` (SI) or anything else gets a ParameterError that says what
    to pass instead, not an AttributeError from deep inside."""
    if isinstance(params, SystemSpec):
        raise ParameterError(f"{name} must be the dimensionless Params, got a SystemSpec (SI): pass spec.nondim()")
    if not isinstance(params, Params):
        raise ParameterError(f"{name} must be gfbjax Params (SystemSpec(...).nondim()), got {type(params).__name__}")
    return params.check()
