r"""Linearised dynamic coefficients of one gas foil bearing (film plus foil), the quantities rotordynamics codes
exchange: the 2 x 2 stiffness ``K`` and damping ``C`` of the bearing force about the static equilibrium.

**Condensation.**  Linearise the vector field of :mod:`gfbjax.model` about the static equilibrium at the speed
Omega_bar and split its states into the film and foil states ``z`` (pressures, strip deflections) and the journal
position ``x_j = (x_j, y_j)`` with velocity ``x_j'``:

    z'  = A_ff z + A_fx x_j + A_fv x_j'          (Reynolds equation and foil strips, Eq. 2b, 10)
    F_B = B_f z  + B_x x_j  + B_v x_j'           (bearing force on one journal, Eq. 7)

all blocks taken from ``jax.jacfwd`` of the model's own functions.  For journal motion ``x_j = X e^{i nu tau}`` the
film and foil follow at the same frequency, ``(i nu I - A_ff) z = (A_fx + i nu A_fv) X``, and

    F_B = H(nu) X,   H(nu) = B_x + i nu B_v + B_f (i nu I - A_ff)^{-1} (A_fx + i nu A_fv) = -(K + i nu C),

so ``K(nu) = -Re H(nu)`` and ``C(nu) = -Im H(nu) / nu``: frequency-dependent coefficients, exact for small motion
at the whirl frequency nu (the film's compressibility and the foil make them depend on nu, unlike an
incompressible film).  They are given for synchronous whirl (``nu = Omega_bar``) or a whirl frequency ratio
``nu = r Omega_bar``.  Index order ``K[i, j] = -dF_i / dx_j`` with i, j in (x horizontal, y vertical up), the
convention of ROSS (force ``-K q - C q'``).

**Units.**  Dimensionless: displacements over c, forces over ``p0 R L``, time over ``t* = 6 mu R^2/(p0 c^2)``, so
``K_bar = K c / (p0 R L)`` and ``C_bar = C c / (p0 R L t*)``.  SI: ``K [N/m] = K_bar p0 R L / c``,
``C [N s/m] = C_bar p0 R L t* / c``, whirl frequency ``nu / (2 pi t*)`` [Hz].

**Plain-bearing reference** (:func:`small_eccentricity_coefficients`; the validation of the condensation).  A plain
rigid 360-degree bearing with the journal centred: ``p = 1 + p1``, ``h = 1 - x cos th - y sin th``; the linearised
Reynolds equation of :mod:`gfbjax.model.reynolds` (``(p h)_tau = 1/2 div(p h^3 grad p) - Lambda/2 (p h)_th``) reads

    d/dtau (p1 + h1) = 1/2 (p1_thth + kappa^2 p1_zz) - Lambda/2 d/dth (p1 + h1),   h1 = -x cos th - y sin th,

with ``p1 = 0`` at both bearing edges ``z = 0, 1`` (z over L).  For ``x = X e^{i nu tau}``, ``y = 0`` put
``p1 = (a(z) cos th + b(z) sin th) e^{i nu tau}``; the cos and sin parts give

    kappa^2/2 (a, b)'' = M (a, b) + X (-i nu, Lambda/2),   M = (1/2 + i nu) I + (Lambda/2) [[0, 1], [-1, 0]].

``M`` is diagonal in the combinations ``alpha = (a - i b)/2``, ``beta = (a + i b)/2`` with eigenvalues
``m_pm = 1/2 + i (nu pm Lambda/2)``, forced by ``f_pm = -i X (nu pm Lambda/2)/2``.  Each solves
``kappa^2/2 u'' = m u + f``, ``u(0) = u(1) = 0``, whose mean over the length is
``-(f/m) g(m)`` with ``g(m) = 1 - tanh(q)/q``, ``q = sqrt(2 m) L/D``.  The force on the journal,
``F = -int int p1 (cos th, sin th) dz dth = -pi (mean a, mean b)`` [p0 R L], gives the column of ``x`` motion;
rotational symmetry gives the rest (``K_yy = K_xx``, ``K_yx = -K_xy``, the same for C):

    K_xx + i nu C_xx = pi (A_+ + A_-),   K_yx + i nu C_yx = i pi (A_+ - A_-),   A_pm = (i/2) (nu pm Lambda/2) g(m_pm) / m_pm.

Checks of this formula that do not involve the solver: at ``nu = 0`` it is the static closed form of
:func:`gfbjax.analyses.plain.small_eccentricity_reference` (``F_x = -2 X Re G``, ``F_y = 2 X Im G``); for small
Lambda and nu (incompressible limit, ``m_pm -> 1/2``, ``g -> g0 = 1 - tanh(L/D)/(L/D)``) it tends to
``K_xx = 0``, ``K_xy = pi g0 Lambda``, ``C_xx = 2 pi g0`` — in SI ``C = 12 pi g0 mu R^3 L / c^3``, the classic
squeeze-film damping of a centred full film (``12 pi mu R^3 L / c^3`` long, ``pi mu R L^3 / c^3`` short); and for a
forward circular whirl at ``nu = Lambda/2`` the ``beta`` mode carries the whole motion with ``f_- = 0``, so the
film force vanishes: ``K_xx + nu C_xy = 0`` and ``K_xy - nu C_xx = 0`` (no effective stiffness, no effective
damping at half-frequency whirl; the finite-difference grid shifts this to ``nu = s Lambda/2``,
``s = sin(dth)/dth``, see :func:`gfbjax.analyses.plain.whirl_force`).

**Rotor from the coefficients** (:func:`rotor_eigenvalue`, :func:`coefficient_hopf`).  The Jeffcott rotor of
:mod:`gfbjax.model.rotor` with the bearing force replaced by ``-(K + C d/dtau) x_j``:
``x_j'' = mass_ratio k_s (x_d - x_j) - zeta (K x_j + C x_j')``, ``x_d'' = -k_s (x_d - x_j)`` (rigid rotor:
``x_j'' = -zeta (K x_j + C x_j')``).  Its eigenvalues with ``K(nu), C(nu)`` evaluated at ``nu = Im lambda``
(iterated) are exact where ``Re lambda = 0``: there ``lambda = i nu`` solves ``det(lambda I - J) = 0`` of the
full Jacobian J (Schur complement of the film and foil block).  So the speed where that eigenvalue crosses the
imaginary axis is the full model's Hopf speed.

**Export to ROSS** (optional extra ``gfbjax[ross]``): :func:`ross_bearing` turns a table of coefficients against
speed into a ``ross.BearingElement``; :func:`ross_jeffcott_rotor` builds the model's Jeffcott rotor in ROSS on two of
them; :func:`ross_instability_onset` finds where ROSS's log decrement of the whirl mode crosses zero, iterating the
export's whirl ratio (ROSS evaluates a bearing at the rotor speed, a gas film's coefficients depend on the whirl
frequency).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import limits
from ..limits import NoSolutionError, ParameterError
from ..model import Grid, bearing_force, core_rates, layout, plain_bearing_rates
from ..params import Params, SystemSpec, check_params
from .plain import plain_bearing_steady
from .static import StaticResult, solve_equilibrium

__all__ = [
    "WHIRL_RATIO",
    "Linearisation",
    "BearingCoefficients",
    "CoefficientHopf",
    "gfb_linearisation",
    "impedance",
    "coefficients_at",
    "bearing_coefficients",
    "plain_bearing_coefficients",
    "small_eccentricity_coefficients",
    "rotor_eigenvalue",
    "coefficient_hopf",
    "ross_bearing",
    "ross_jeffcott_rotor",
    "RossOnset",
    "ross_log_decrement",
    "ross_instability_onset",
]

#: Whirl frequency over running speed ``nu / Omega_bar`` of the coefficients (1: synchronous).  Negative values
#: (backward whirl) and zero (no dynamic part: the damping is then undefined) are refused.
WHIRL_RATIO = limits.Range("whirl_ratio", 0.0, 10.0, lo_open=True, what="whirl frequency over running speed")
#: Whirl frequency of the plain-bearing and impedance functions, per tau.
_NU = limits.Range("nu", 0.0, 1000.0, lo_open=True, what="whirl frequency per tau (nu = omega_whirl t*)")


# -- the linearisation --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Linearisation:
    """Blocks of the linearised film-and-foil dynamics and bearing force about an equilibrium (see module doc).

    Attributes (NumPy float arrays; n = film and foil states):
        A_ff: (n, n) per tau.   A_fx: (n, 2) per tau per c.   A_fv: (n, 2) per c.
        B_f: (2, n) force per state [p0 R L].   B_x: (2, 2) [p0 R L / c].   B_v: (2, 2) [p0 R L t* / c].
        omega: running speed Omega_bar at which it was taken.
    """

    A_ff: np.ndarray
    A_fx: np.ndarray
    A_fv: np.ndarray
    B_f: np.ndarray
    B_x: np.ndarray
    B_v: np.ndarray
    omega: float


def impedance(lin: Linearisation, nu: float | Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and damping ``K(nu), C(nu)`` of a :class:`Linearisation` by condensation of the film and foil
    states in the frequency domain (module doc): ``H = B_x + i nu B_v + B_f (i nu I - A_ff)^-1 (A_fx + i nu A_fv)``,
    ``K = -Re H``, ``C = -Im H / nu``.

    Args:
        nu: whirl frequency per tau, > 0 (scalar or 1-d array).

    Returns:
        ``(K, C)``, each of shape (2, 2) for a scalar ``nu`` or (len(nu), 2, 2), dimensionless
        (``K c/(p0 R L)``, ``C c/(p0 R L t*)``).

    Raises:
        ParameterError: a ``nu`` outside (0, 1000].
    """
    nus = np.atleast_1d(np.asarray(nu, dtype=float))
    for v in nus:
        _NU.check(float(v))
    n = lin.A_ff.shape[0]
    eye = np.eye(n)
    K = np.empty((nus.size, 2, 2))
    C = np.empty((nus.size, 2, 2))
    for k, w in enumerate(nus):
        Z = np.linalg.solve(1j * w * eye - lin.A_ff, lin.A_fx + 1j * w * lin.A_fv)
        H = lin.B_x + 1j * w * lin.B_v + lin.B_f @ Z
        K[k], C[k] = -H.real, -H.imag / w
    if np.ndim(nu) == 0:
        return K[0], C[0]
    return K, C


def _journal_indices(params: Params) -> tuple[int, list[int], list[int]]:
    """Number of film and foil states, indices of the journal position and velocity in the core state."""
    lay = layout(params)
    r0 = lay.slices["rotor"].start
    vel = [r0 + 4, r0 + 5] if params.rotor == "jeffcott" else [r0 + 2, r0 + 3]
    return lay.slices["foil"].stop, [r0, r0 + 1], vel


@eqx.filter_jit
def _gfb_jacobian(s0: Any, om: Any, params: Params) -> Any:
    """Jacobian of (film and foil rates, bearing force) with respect to (film and foil states, journal position,
    journal velocity) at the core state ``s0``; compiled once per grid and rotor kind."""
    n_f, pos, vel = _journal_indices(params)
    lay = layout(params)
    grid = lay.grid
    theta = grid.theta(params.theta0)
    ip, iv = jnp.array(pos), jnp.array(vel)

    def rates_and_force(w):
        s = s0.at[:n_f].set(w[:n_f]).at[ip].set(w[n_f:n_f + 2]).at[iv].set(w[n_f + 2:])
        zdot = core_rates(s, om, jnp.zeros(2, s.dtype), params)[:n_f]
        F = bearing_force(lay.pressures(s), theta, grid, params.gumbel_width, gumbel=True)
        return jnp.concatenate([zdot, F])

    return jax.jacfwd(rates_and_force)(jnp.concatenate([s0[:n_f], s0[ip], s0[iv]]))


def gfb_linearisation(params: Params, omega: float, state: Any) -> Linearisation:
    """The blocks of :class:`Linearisation` of the gas foil bearing at the core state ``state`` (an equilibrium of
    :func:`gfbjax.analyses.static.solve_equilibrium`) and speed ``omega``, from ``jax.jacfwd`` of the model's vector
    field (:func:`gfbjax.model.core_rates`: film and foil rows) and bearing force (:func:`gfbjax.model.bearing_force`,
    Gumbel condition included)."""
    n_f = _journal_indices(params)[0]
    J = np.asarray(_gfb_jacobian(jnp.asarray(state), jnp.asarray(float(omega)), params.traced()))
    return Linearisation(A_ff=J[:n_f, :n_f], A_fx=J[:n_f, n_f:n_f + 2], A_fv=J[:n_f, n_f + 2:],
                         B_f=J[n_f:, :n_f], B_x=J[n_f:, n_f:n_f + 2], B_v=J[n_f:, n_f + 2:], omega=float(omega))


# -- coefficients of the gas foil bearing ---------------------------------------------------------------------------

@dataclass
class BearingCoefficients:
    """Linearised coefficients of one gas foil bearing at its static equilibrium, over speeds.

    Attributes (arrays over the speeds, dimensionless; see the module doc for the SI factors):
        omega: running speed Omega_bar, shape (n,).
        nu: whirl frequency per tau at which each row was evaluated, shape (n,).
        K: stiffness ``K_bar = K c / (p0 R L)``, shape (n, 2, 2), ``K[:, i, j] = -dF_i/dx_j``, (x, y) = (horizontal,
            vertical up).
        C: damping ``C_bar = C c / (p0 R L t*)``, shape (n, 2, 2).
        x_j, y_j: journal equilibrium position over c, shape (n,).
        whirl_ratio: ``nu / Omega_bar`` requested (1: synchronous).
    """

    omega: np.ndarray
    nu: np.ndarray
    K: np.ndarray
    C: np.ndarray
    x_j: np.ndarray
    y_j: np.ndarray
    whirl_ratio: float = 1.0
    equilibria: list = field(default_factory=list, repr=False)

    def __len__(self) -> int:
        return int(np.size(self.omega))

    def si(self, spec: SystemSpec) -> dict[str, np.ndarray]:
        """SI values: ``speed_rpm``, ``speed_rad_s``, ``whirl_Hz``, ``K_N_per_m`` (n, 2, 2), ``C_Ns_per_m``
        (n, 2, 2), ``x_j_um``, ``y_j_um``.  ``spec`` must be the system the coefficients were computed for."""
        ts, fs, c = spec.t_star, spec.force_scale, spec.c
        return {"speed_rpm": np.asarray(spec.rpm(np.asarray(self.omega))), "speed_rad_s": self.omega / ts,
                "whirl_Hz": self.nu / ts / (2 * math.pi), "K_N_per_m": self.K * fs / c,
                "C_Ns_per_m": self.C * fs * ts / c, "x_j_um": self.x_j * c * 1e6, "y_j_um": self.y_j * c * 1e6}

    def to_dict(self, spec: SystemSpec | None = None) -> dict[str, Any]:
        """JSON-ready: per speed the dimensionless coefficients (``kxx``, ``kxy``, ``kyx``, ``kyy``, ``cxx``, ...) and,
        with ``spec``, the SI ones under ``SI``."""
        names = {"xx": (0, 0), "xy": (0, 1), "yx": (1, 0), "yy": (1, 1)}
        d: dict[str, Any] = {"whirl_ratio": self.whirl_ratio, "omega_bar": self.omega.tolist(),
                             "nu_per_tau": self.nu.tolist(), "x_j": self.x_j.tolist(), "y_j": self.y_j.tolist(),
                             "units": {"k": "p0 R L / c", "c": "p0 R L t* / c", "position": "c"}}
        for s, (i, j) in names.items():
            d["k" + s] = self.K[:, i, j].tolist()
            d["c" + s] = self.C[:, i, j].tolist()
        if spec is not None:
            si = self.si(spec)
            e: dict[str, Any] = {"speed_rpm": si["speed_rpm"].tolist(), "whirl_Hz": si["whirl_Hz"].tolist(),
                                 "x_j_um": si["x_j_um"].tolist(), "y_j_um": si["y_j_um"].tolist(),
                                 "units": {"k": "N/m", "c": "N s/m"}}
            for s, (i, j) in names.items():
                e["k" + s] = si["K_N_per_m"][:, i, j].tolist()
                e["c" + s] = si["C_Ns_per_m"][:, i, j].tolist()
            d["SI"] = e
        return d


def _system_load(params: Params, w: float | None) -> float:
    """The extra specific load ``W/(p0 L D)`` of the equilibria: ``w`` or the system's own (``w_ext / 2``)."""
    return float(params.w_ext) / 2.0 if w is None else limits.LOAD_W.check(w, "w")


def coefficients_at(params: Params, omega: float, nu: float | Sequence[float], *, w: float | None = None,
                    equilibrium: StaticResult | None = None) -> tuple[np.ndarray, np.ndarray, StaticResult]:
    """``K(nu), C(nu)`` of one gas foil bearing at the static equilibrium at speed ``omega`` (see module doc).

    Args:
        params: dimensionless system (``SystemSpec.nondim()``); checked.
        omega: running speed Omega_bar in (0, 50].
        nu: whirl frequency per tau, > 0 (scalar or 1-d array): ``omega`` for synchronous coefficients.
        w: extra specific load ``W/(p0 L D)`` per bearing beyond gravity; None: the system's own load.
        equilibrium: the equilibrium at ``omega`` if already solved (saves the solve).

    Returns:
        ``(K, C, equilibrium)``: dimensionless (2, 2) arrays (or (len(nu), 2, 2)) and the StaticResult.

    Raises:
        ParameterError: bad params, speed, load or whirl frequency (before any solve).
        NoSolutionError: no static equilibrium with an open film at this speed and load.
    """
    check_params(params)
    omega = limits.SPEED.check(omega, "omega")
    for v in np.atleast_1d(np.asarray(nu, dtype=float)):
        _NU.check(float(v))
    w = _system_load(params, w)
    eq = equilibrium if equilibrium is not None else solve_equilibrium(params, omega, w)
    if not eq.converged:
        raise NoSolutionError(f"no static equilibrium at Omega_bar = {omega:g}: {eq.message}")
    K, C = impedance(gfb_linearisation(params.traced(), omega, eq.state), nu)
    return K, C, eq


def bearing_coefficients(params: Params, omegas: Sequence[float], whirl_ratio: float = 1.0, *,
                         w: float | None = None,
                         progress: Callable[[int, int], None] | None = None) -> BearingCoefficients:
    """Coefficients of one gas foil bearing against speed, at the whirl frequency ``nu = whirl_ratio * Omega_bar``
    (1: synchronous), each equilibrium warm-started from the previous speed's.

    Args:
        params: dimensionless system; checked.
        omegas: speeds Omega_bar, each in (0, 50] (any order; kept as given).
        whirl_ratio: ``nu / Omega_bar`` in (0, 10].
        w: extra specific load per bearing ``W/(p0 L D)``; None: the system's own.
        progress: called as ``progress(done, total)`` after each speed.

    Returns:
        :class:`BearingCoefficients` (dimensionless; ``.si(spec)`` for N/m and N s/m).

    Raises:
        ParameterError: bad input, before any solve.  NoSolutionError: a speed without an open-film equilibrium
        (the message names it).
    """
    check_params(params)
    ratio = WHIRL_RATIO.check(whirl_ratio)
    om = np.atleast_1d(np.asarray(omegas, dtype=float))
    if om.ndim != 1 or om.size == 0:
        raise ParameterError(f"omegas must be a non-empty 1-d sequence of speeds, got shape {om.shape}")
    for v in om:
        limits.SPEED.check(float(v), "omegas")
    w = _system_load(params, w)
    p = params.traced()
    K = np.empty((om.size, 2, 2))
    C = np.empty((om.size, 2, 2))
    eqs: list[StaticResult] = []
    guess = None
    for k, o in enumerate(om):
        eq = solve_equilibrium(p, float(o), w, guess=guess)
        if not eq.converged:
            raise NoSolutionError(f"no static equilibrium at Omega_bar = {o:g} (omegas[{k}]): {eq.message}")
        guess = eq.state
        K[k], C[k] = impedance(gfb_linearisation(p, float(o), eq.state), ratio * float(o))
        eqs.append(eq)
        if progress is not None:
            progress(k + 1, om.size)
    return BearingCoefficients(omega=om, nu=ratio * om, K=K, C=C, x_j=np.array([e.x_j for e in eqs]),
                               y_j=np.array([e.y_j for e in eqs]), whirl_ratio=ratio, equilibria=eqs)


# -- the plain rigid bearing and its closed form -------------------------------------------------------------------

def plain_bearing_coefficients(Lambda: float, nu: float | Sequence[float], kappa: float, Nx: int, Nz: int, *,
                               x: float = 0.0, y: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``K(nu), C(nu)`` of the plain rigid 360-degree gas bearing of :mod:`gfbjax.analyses.plain` (no foil, full
    film: the force integrates ``p - 1``) at the journal position ``(x, y)``, by the same condensation as the foil
    bearing (:func:`impedance`) applied to ``jax.jacfwd`` of :func:`gfbjax.model.plain_bearing_rates`.

    Args:
        Lambda: bearing number (= Omega_bar) in (0, 1000].
        nu: whirl frequency per tau, > 0 (scalar or 1-d array).
        kappa: R / L in (0, 100].
        Nx, Nz: periodic grid (see :func:`gfbjax.analyses.plain.plain_bearing_steady`).
        x, y: journal position over c (default centred: the small-eccentricity limit, exactly).

    Returns:
        ``(K, C)`` dimensionless, (2, 2) or (len(nu), 2, 2).  Compare :func:`small_eccentricity_coefficients`.

    Raises:
        ParameterError: bad input.  NoSolutionError: the steady Newton solve failed.
    """
    limits.Range("Lambda", 0.0, 1000.0, lo_open=True, what="bearing number").check(Lambda)
    for v in np.atleast_1d(np.asarray(nu, dtype=float)):
        _NU.check(float(v))
    st = plain_bearing_steady(Lambda, x, y, kappa, Nx, Nz)  # checks kappa, the grid and the position
    if not bool(st.converged):
        raise NoSolutionError(f"plain bearing: no steady pressure at Lambda = {Lambda:g}, (x, y) = ({x:g}, {y:g})")
    grid = Grid(int(Nx), int(Nz), periodic=True)
    shape = (grid.n_theta, grid.Nz)
    n = grid.n_pressure
    theta = grid.theta(0.0)
    lam, kap = jnp.asarray(float(Lambda)), jnp.asarray(float(kappa))

    def rates_and_force(v):
        P = v[:n].reshape(shape)
        pdot = plain_bearing_rates(P, v[n], v[n + 1], v[n + 2], v[n + 3], lam, kap, grid).reshape(-1)
        return jnp.concatenate([pdot, bearing_force(P, theta, grid, 0.0, gumbel=False)])

    P0 = jnp.asarray(st.pressure)[:, 1:].reshape(-1)  # unknowns: the edge column z = 0 is the boundary
    v0 = jnp.concatenate([P0, jnp.array([float(x), float(y), 0.0, 0.0])])
    J = np.asarray(jax.jacfwd(rates_and_force)(v0))
    lin = Linearisation(A_ff=J[:n, :n], A_fx=J[:n, n:n + 2], A_fv=J[:n, n + 2:], B_f=J[n:, :n],
                        B_x=J[n:, n:n + 2], B_v=J[n:, n + 2:], omega=float(Lambda))
    return impedance(lin, nu)


def small_eccentricity_coefficients(Lambda: float | np.ndarray, nu: float | np.ndarray,
                                    L_over_D: float) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form ``K(nu), C(nu)`` of the centred plain 360-degree gas bearing (linearised compressible Reynolds
    equation, finite length; derived in the module doc), independent of the finite-difference model.

    ``K_xx + i nu C_xx = pi (A_+ + A_-)``, ``K_yx + i nu C_yx = i pi (A_+ - A_-)``,
    ``A_pm = (i/2)(nu pm Lambda/2) g(m_pm)/m_pm``, ``m_pm = 1/2 + i(nu pm Lambda/2)``, ``g(m) = 1 - tanh(q)/q``,
    ``q = sqrt(2 m) L/D``; ``K_yy = K_xx``, ``K_xy = -K_yx`` (and the same for C).

    Args:
        Lambda: bearing number, >= 0 (scalar or array, broadcast with ``nu``).
        nu: whirl frequency per tau, > 0.
        L_over_D: length over diameter, > 0.

    Returns:
        ``(K, C)`` dimensionless (units ``p0 R L / c`` and ``p0 R L t* / c``), shape ``broadcast + (2, 2)``.
    """
    lam, w = np.broadcast_arrays(np.asarray(Lambda, dtype=float), np.asarray(nu, dtype=float))
    if not (np.all(np.isfinite(lam)) and np.all(lam >= 0)):
        raise ParameterError(f"Lambda = {Lambda!r} is outside the allowed range [0, inf)")
    if not (np.all(np.isfinite(w)) and np.all(w > 0)):
        raise ParameterError(f"nu = {nu!r} is outside the allowed range (0, inf)")
    limits.Range("L_over_D", 0.0, None, lo_open=True).check(L_over_D)

    def A(sign):
        a = w + sign * lam / 2
        m = 0.5 + 1j * a
        q = np.sqrt(2 * m) * L_over_D
        return 0.5j * a * (1 - np.tanh(q) / q) / m

    Ap, Am = A(+1), A(-1)
    col_x = np.pi * (Ap + Am)        # K_xx + i nu C_xx
    col_y = 1j * np.pi * (Ap - Am)   # K_yx + i nu C_yx
    K = np.empty(lam.shape + (2, 2))
    C = np.empty(lam.shape + (2, 2))
    K[..., 0, 0] = K[..., 1, 1] = col_x.real
    C[..., 0, 0] = C[..., 1, 1] = col_x.imag / w
    K[..., 1, 0] = col_y.real
    K[..., 0, 1] = -col_y.real
    C[..., 1, 0] = col_y.imag / w
    C[..., 0, 1] = -col_y.imag / w
    return K, C


# -- the rotor assembled from the coefficients ----------------------------------------------------------------------

def _rotor_matrix(params: Params, K: np.ndarray, C: np.ndarray) -> np.ndarray:
    """State matrix of the rotor with the bearing force ``-(K x_j + C x_j')`` (module doc); states
    ``[positions, velocities]`` with positions ``x_j, y_j (, x_d, y_d)``."""
    zeta = float(params.zeta)
    if params.rotor == "rigid":
        Ks, Cs = zeta * K, zeta * C
    else:
        ks, mr = float(params.k_s), float(params.mass_ratio)
        I2 = np.eye(2)
        Ks = np.block([[mr * ks * I2 + zeta * K, -mr * ks * I2], [-ks * I2, ks * I2]])
        Cs = np.block([[zeta * C, np.zeros((2, 2))], [np.zeros((2, 2)), np.zeros((2, 2))]])
    n = Ks.shape[0]
    return np.block([[np.zeros((n, n)), np.eye(n)], [-Ks, -Cs]])


def rotor_eigenvalue(params: Params, lin: Linearisation, nu0: float | None = None, *, tol: float = 1e-12,
                     max_iter: int = 100) -> tuple[complex, int]:
    """Least stable eigenvalue (largest real part, positive imaginary part) of the rotor assembled from the
    frequency-dependent coefficients, iterating ``nu = Im lambda`` until ``K(nu), C(nu)`` and lambda agree.

    Exact where ``Re lambda = 0`` (then ``i nu`` is an eigenvalue of the full Jacobian); elsewhere the coefficients
    are taken on the imaginary axis at ``Im lambda``, the usual approximation of a coefficient-based rotor model.

    Args:
        params: the system (rotor kind, zeta, k_s, mass_ratio).
        lin: :func:`gfb_linearisation` at the speed of interest.
        nu0: first whirl frequency per tau (default ``Omega_bar / 2``).
        tol: convergence of ``|Delta nu|`` per tau.

    Returns:
        ``(lambda per tau, iterations)``.

    Raises:
        NoSolutionError: the iteration did not settle within ``max_iter``.
    """
    nu = 0.5 * lin.omega if nu0 is None else float(nu0)
    for it in range(1, max_iter + 1):
        K, C = impedance(lin, nu)
        ev = np.linalg.eigvals(_rotor_matrix(params, K, C))
        ev = ev[ev.imag > 0]
        lam = complex(ev[np.argmax(ev.real)])
        if abs(lam.imag - nu) <= tol * max(1.0, nu):
            return lam, it
        nu = lam.imag
    raise NoSolutionError(f"rotor eigenvalue: the whirl frequency did not settle in {max_iter} iterations at "
                          f"Omega_bar = {lin.omega:g} (last nu = {nu:.6g})")


@dataclass
class CoefficientHopf:
    """Hopf point of the rotor assembled from the coefficients (:func:`coefficient_hopf`).

    Attributes:
        omega: speed Omega_bar where the least stable eigenvalue crosses the imaginary axis.
        nu: whirl frequency there, per tau (``nu / omega``: the whirl ratio).
        K, C: the bearing's dimensionless coefficients at that speed and whirl frequency, (2, 2).
        evaluations: equilibria solved.
    """

    omega: float
    nu: float
    K: np.ndarray
    C: np.ndarray
    evaluations: int

    @property
    def whirl_ratio(self) -> float:
        return self.nu / self.omega


def coefficient_hopf(params: Params, omega_lo: float, omega_hi: float, *, xtol: float = 1e-10,
                     w: float | None = None) -> CoefficientHopf:
    """Speed where the rotor assembled from the bearing coefficients loses stability (``Re lambda = 0``, see
    :func:`rotor_eigenvalue`), by Brent's method on ``Re lambda(Omega_bar)`` in ``[omega_lo, omega_hi]``; each
    evaluation solves the static equilibrium (warm-started) and iterates the whirl frequency.

    Args:
        params: the system (Jeffcott or rigid rotor).
        omega_lo, omega_hi: a bracket in Omega_bar, each in (0, 50], ``omega_lo < omega_hi``, with a stable rotor at
            one end and an unstable one at the other.
        xtol: tolerance on Omega_bar.
        w: extra specific load per bearing; None: the system's own.

    Raises:
        ParameterError: bad input.  NoSolutionError: no sign change of ``Re lambda`` in the bracket, or no
        equilibrium at a speed of it.
    """
    from scipy.optimize import brentq

    check_params(params)
    lo = limits.SPEED.check(omega_lo, "omega_lo")
    hi = limits.SPEED.check(omega_hi, "omega_hi")
    if not lo < hi:
        raise ParameterError(f"omega_hi = {hi:g} must exceed omega_lo = {lo:g}")
    w = _system_load(params, w)
    p = params.traced()
    memo: dict[str, Any] = {"state": None, "nu": None, "n": 0, "last": None}

    def re_lambda(o: float) -> float:
        eq = solve_equilibrium(p, o, w, guess=memo["state"])
        memo["n"] += 1
        if not eq.converged:
            raise NoSolutionError(f"no static equilibrium at Omega_bar = {o:g}: {eq.message}")
        memo["state"] = eq.state
        lin = gfb_linearisation(p, o, eq.state)
        lam, _ = rotor_eigenvalue(params, lin, memo["nu"])
        memo["nu"] = lam.imag
        memo["last"] = (o, lam, lin)
        return lam.real

    f_lo, f_hi = re_lambda(lo), re_lambda(hi)
    if f_lo * f_hi > 0:
        raise NoSolutionError(f"Re lambda has the same sign at Omega_bar = {lo:g} ({f_lo:+.3e}) and {hi:g} "
                              f"({f_hi:+.3e}): no stability change of the coefficient rotor in the bracket")
    omega = brentq(re_lambda, lo, hi, xtol=xtol, rtol=4 * np.finfo(float).eps)
    o, lam, lin = memo["last"]
    if o != omega:
        re_lambda(omega)
        o, lam, lin = memo["last"]
    K, C = impedance(lin, lam.imag)
    return CoefficientHopf(omega=float(omega), nu=float(lam.imag), K=K, C=C, evaluations=memo["n"])


# -- export to ROSS ---------------------------------------------------------------------------------------------------

def _ross():
    """Import ROSS (optional extra ``gfbjax[ross]``) with a message that says how to get it.

    ROSS imports ccp, whose CoolProp library prints a page about a missing REFPROP licence from C on the first
    import (irrelevant to rotordynamics); file descriptors 1 and 2 are pointed at /dev/null meanwhile."""
    import os
    import sys
    import warnings

    if "ross" in sys.modules:
        return sys.modules["ross"]
    sys.stdout.flush()
    sys.stderr.flush()
    saved = (os.dup(1), os.dup(2))
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        with warnings.catch_warnings():  # ccp's Python-level twin of the same REFPROP notice
            warnings.simplefilter("ignore", UserWarning)
            import ross
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("the ROSS export needs ross-rotordynamics: pip install 'gfbjax[ross]' "
                          f"({exc})") from exc
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, null):
            os.close(fd)
    return ross


def ross_bearing(coefficients: BearingCoefficients, spec: SystemSpec, n: int, *, tag: str | None = None,
                 **kwargs: Any):
    """A ``ross.BearingElement`` at node ``n`` with the SI coefficients (N/m, N s/m) of ``coefficients`` tabulated
    against the running speed in rad/s (ROSS's ``frequency`` array; ROSS evaluates a bearing at the rotor speed).
    Between the speeds the element interpolates by a cubic spline through the table (ROSS's own smoothing spline,
    whose residual is about 1 N s/m per point, is replaced: that is 0.4 % of a gas bearing's damping); beyond them
    the spline extrapolates.

    The coefficients are those of the whirl ratio they were computed for (``coefficients.whirl_ratio``): synchronous
    ones for unbalance response; for a stability (log decrement) analysis, those at the whirl ratio of the mode in
    question, since a gas film's coefficients depend on the whirl frequency.

    Args:
        coefficients: from :func:`bearing_coefficients`, at least 2 speeds, increasing.
        spec: the system they were computed for (SI scales).
        n: ROSS node of the bearing.
        tag: ROSS tag; kwargs go to ``ross.BearingElement``.

    Raises:
        ParameterError: fewer than 2 speeds or speeds not increasing.  ImportError: ROSS is not installed.
    """
    om = np.asarray(coefficients.omega, float)
    if om.size < 2 or np.any(np.diff(om) <= 0):
        raise ParameterError(f"coefficients.omega must hold at least 2 increasing speeds for ROSS's interpolation, "
                             f"got {om.tolist()}")
    from scipy.interpolate import make_interp_spline

    rs = _ross()
    si = coefficients.si(spec)
    K, C = si["K_N_per_m"], si["C_Ns_per_m"]
    w = si["speed_rad_s"]
    table = {"kxx": K[:, 0, 0], "kxy": K[:, 0, 1], "kyx": K[:, 1, 0], "kyy": K[:, 1, 1],
             "cxx": C[:, 0, 0], "cxy": C[:, 0, 1], "cyx": C[:, 1, 0], "cyy": C[:, 1, 1]}
    elem = rs.BearingElement(n=n, frequency=w, tag=tag, **table, **kwargs)
    # ROSS fits a smoothing spline whose residual is about 1 in SI units per point: nothing against N/m, but ~0.4 %
    # of a gas bearing's few hundred N s/m.  Interpolating splines through the table instead (same call signature).
    k = min(3, w.size - 1)
    for name, values in table.items():
        if hasattr(elem, f"{name}_interpolated"):
            setattr(elem, f"{name}_interpolated", make_interp_spline(w, np.asarray(values, float), k=k))
    return elem


def ross_jeffcott_rotor(spec: SystemSpec, coefficients: BearingCoefficients, *, n_elements: int = 4,
                        span: float | None = None, shaft_mass_fraction: float = 1e-4):
    """The system's Jeffcott rotor in ROSS: a slender Euler-Bernoulli shaft between two bearings (this bearing at
    both ends), the disc ``m_d`` at mid-span, the journal masses ``m_j`` as thin discs at the bearings.

    The shaft's modulus is set so that its mid-span stiffness relative to the journals, ``48 E I / l^3`` (free end
    rotations), is the model's ``k_s = k_s_bar m_d / t*^2``; its density so that its mass is
    ``shaft_mass_fraction`` of the disc's (ROSS needs a mass; the model's shaft has none).  Diameter ``2 R``, span
    ``l`` (default ``4 L``).  The disc's moments of inertia are those of a thin steel-like disc of radius 4 R (they
    only act in the conical modes, which the model's symmetric Jeffcott rotor does not have).

    Raises:
        ParameterError: a rigid-rotor spec, an odd or too small ``n_elements``, a bad span or mass fraction.
    """
    if spec.rotor != "jeffcott":
        raise ParameterError(f"rotor = {spec.rotor!r}: the ROSS Jeffcott rotor needs rotor = 'jeffcott'")
    limits.Range("n_elements", 2, 200, integer=True, what="an even number of shaft elements").check(n_elements)
    if n_elements % 2:
        raise ParameterError(f"n_elements = {n_elements} must be even (the disc sits at mid-span)")
    span = 4.0 * spec.L if span is None else limits.Range("span", 0.0, 100.0, lo_open=True, unit="m").check(span)
    limits.Range("shaft_mass_fraction", 0.0, 0.1, lo_open=True).check(shaft_mass_fraction)
    rs = _ross()
    d = 2.0 * spec.R
    I_area = math.pi * d**4 / 64.0
    k_s = spec.k_s_bar * spec.m_d / spec.t_star**2
    E = k_s * span**3 / (48.0 * I_area)
    rho = shaft_mass_fraction * spec.m_d / (math.pi * d**2 / 4.0 * span)
    mat = rs.Material(name="gfbjax_equivalent_shaft", rho=rho, E=E, Poisson=0.3)
    le = span / n_elements
    shaft = [rs.ShaftElement(L=le, idl=0.0, odl=d, material=mat, n=i, shear_effects=False)
             for i in range(n_elements)]
    r_disc = 4.0 * spec.R
    Id, Ip = spec.m_d * r_disc**2 / 4.0, spec.m_d * r_disc**2 / 2.0
    # the journals are thin rigid discs on the shaft's end nodes (ROSS's point masses belong on support nodes)
    Ij = spec.m_j * spec.R**2 / 4.0
    discs = [rs.DiskElement(n=0, m=spec.m_j, Id=Ij, Ip=2.0 * Ij, tag="journal_0"),
             rs.DiskElement(n=n_elements // 2, m=spec.m_d, Id=Id, Ip=Ip, tag="disc"),
             rs.DiskElement(n=n_elements, m=spec.m_j, Id=Ij, Ip=2.0 * Ij, tag="journal_1")]
    bearings = [ross_bearing(coefficients, spec, 0, tag="gfb_0"),
                ross_bearing(coefficients, spec, n_elements, tag="gfb_1")]
    return rs.Rotor(shaft, disk_elements=discs, bearing_elements=bearings)


def ross_log_decrement(rotor: Any, speed: float, whirl: float, num_modes: int = 24) -> tuple[float, float]:
    """Log decrement and damped natural frequency [rad/s] of the least damped mode of a ROSS rotor whose damped
    frequency lies within a factor 2 of ``whirl`` [rad/s], at ``speed`` [rad/s] (``rotor.run_modal``, all
    eigenvalues).  NoSolutionError when no mode lies in that band."""
    m = rotor.run_modal(float(speed), num_modes=num_modes, sparse=False)
    wd, ld = np.asarray(m.wd, float), np.asarray(m.log_dec, float)
    band = np.flatnonzero((wd >= 0.5 * whirl) & (wd <= 2.0 * whirl))
    if band.size == 0:
        raise NoSolutionError(f"ROSS: no mode with a damped frequency within a factor 2 of {whirl:.6g} rad/s at "
                              f"{speed:.6g} rad/s (modes: {np.round(wd, 1).tolist()})")
    k = band[np.argmin(ld[band])]
    return float(ld[k]), float(wd[k])


@dataclass
class RossOnset:
    """Onset of instability of the ROSS Jeffcott rotor on the exported bearings (:func:`ross_instability_onset`).

    Attributes:
        speed_rad_s: rotor speed where the whirl mode's log decrement crosses zero [rad/s].
        whirl_rad_s: that mode's damped natural frequency there [rad/s].
        whirl_ratio: the whirl ratio the bearing coefficients were exported at (converged: whirl / speed).
        iterations: exports of the bearing (one coefficient sweep each).
        rotor: the last ROSS rotor built.
    """

    speed_rad_s: float
    whirl_rad_s: float
    whirl_ratio: float
    iterations: int
    rotor: Any = field(repr=False, default=None)

    def omega_bar(self, spec: SystemSpec) -> float:
        return self.speed_rad_s * spec.t_star

    def rpm(self) -> float:
        return self.speed_rad_s * 60.0 / (2.0 * math.pi)

    @property
    def whirl_Hz(self) -> float:
        return self.whirl_rad_s / (2.0 * math.pi)


def ross_instability_onset(spec: SystemSpec, omega_lo: float, omega_hi: float, *, n_speeds: int = 9,
                           whirl_ratio: float = 0.5, rtol: float = 1e-6, max_iter: int = 12,
                           **rotor_kw: Any) -> RossOnset:
    """Speed where ROSS finds the Jeffcott rotor (:func:`ross_jeffcott_rotor`) on two exported gas foil bearings
    unstable, and the whirl frequency there: the round trip gfbjax -> ROSS.

    ROSS evaluates a bearing at the rotor speed, but a gas film's coefficients depend on the whirl frequency; so
    the bearings are exported at a whirl ratio r (coefficients at ``nu = r Omega``, ``n_speeds`` speeds evenly in
    ``[omega_lo, omega_hi]``), ROSS's log decrement of the mode nearest ``r Omega`` is driven to zero by Brent's
    method in the speed, and r is updated from ROSS's frequency there by the secant method on
    ``r -> whirl / speed`` until it changes by less than ``rtol``.

    Args:
        spec: a Jeffcott system; its balanced equilibria give the coefficients.
        omega_lo, omega_hi: speed bracket in Omega_bar (stable at the low end, unstable at the high end).
        n_speeds: speeds of the exported tables, in [4, 200] (ROSS's cubic spline needs 4).
        whirl_ratio: first whirl ratio, in (0, 10].
        rotor_kw: passed to :func:`ross_jeffcott_rotor`.

    Raises:
        ParameterError: bad input.  NoSolutionError: no sign change of the log decrement in the bracket, or r not
        settled within ``max_iter``.  ImportError: ROSS not installed.
    """
    from scipy.optimize import brentq

    lo = limits.SPEED.check(omega_lo, "omega_lo")
    hi = limits.SPEED.check(omega_hi, "omega_hi")
    if not lo < hi:
        raise ParameterError(f"omega_hi = {hi:g} must exceed omega_lo = {lo:g}")
    limits.Range("n_speeds", 4, 200, integer=True).check(n_speeds)
    r = WHIRL_RATIO.check(whirl_ratio)
    params = spec.nondim()
    omegas = np.linspace(lo, hi, n_speeds)
    ts = spec.t_star

    def onset(ratio: float) -> tuple[float, float, Any]:
        rotor = ross_jeffcott_rotor(spec, bearing_coefficients(params, omegas, ratio), **rotor_kw)
        f = lambda sp: ross_log_decrement(rotor, sp, ratio * sp)[0]  # noqa: E731
        a, b = lo / ts, hi / ts
        fa, fb = f(a), f(b)
        if fa * fb > 0:
            raise NoSolutionError(f"ROSS: the log decrement of the whirl mode at ratio {ratio:.4g} has the same "
                                  f"sign at Omega_bar = {lo:g} ({fa:+.3e}) and {hi:g} ({fb:+.3e})")
        sp = brentq(f, a, b, xtol=1e-9 * b, rtol=1e-12)
        return sp, ross_log_decrement(rotor, sp, ratio * sp)[1], rotor

    sp, wd, rotor = onset(r)
    g_prev, r_prev = wd / sp - r, r
    r = wd / sp
    for it in range(2, max_iter + 1):
        sp, wd, rotor = onset(r)
        g = wd / sp - r
        if abs(g) <= rtol * r:
            return RossOnset(speed_rad_s=sp, whirl_rad_s=wd, whirl_ratio=r, iterations=it, rotor=rotor)
        r_next = r - g * (r - r_prev) / (g - g_prev) if g != g_prev else wd / sp
        r_prev, g_prev, r = r, g, float(np.clip(r_next, 1e-3, 10.0))
    raise NoSolutionError(f"ROSS: the whirl ratio did not settle in {max_iter} exports (last {r:.6g})")
