"""Limit cycles of the unbalanced GFB-rotor system and equilibria of the balanced one, on the generic engine
:mod:`gfbjax.cont` (paper Sect. 2.3, 3.2, Appendix A1).

The cycles are those of the autonomous system of Eq. (21)-(22): the phase oscillator makes the unbalance forcing
autonomous, so a synchronous (1X) response is a periodic orbit of period ``T = 2 pi / Omega_bar`` and the Floquet
multipliers carry one trivial multiplier at +1.  The continuation parameter is the speed Omega_bar.

A branch starts at a low speed from the *linear forced response* around the static equilibrium,

    x(tau) = x_eq + Re( (i Omega I - J)^-1 B eps Omega^2 (1, -i) e^{i Omega tau} ),

with J the Jacobian of the balanced system and B the input matrix of the unbalance force, a first-order harmonic
balance that puts collocation Newton well inside its basin.  At a large unbalance (the paper's literal 24.1 um
carried by the disc, docs/model.md) that guess can sweep the journal through the foil (the linearised film
thickness goes negative), and Newton diverges from it.  :func:`unbalance_response_start` then ramps the unbalance
up instead: it corrects the cycle at a fraction of ``eps`` small enough for the linear guess to keep the film open,
and raises the fraction to 1, each cycle the start of the next.
"""

from __future__ import annotations

import dataclasses
import math
import os
from typing import Any, Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import cont
from ..model import core_rates, layout, vector_field
from ..model.system import film
from ..model.pattern import jacobian_sparsity
from .. import limits
from ..params import ParameterError, Params, SystemSpec, check_params
from ..limits import NoSolutionError
from .static import StaticResult, solve_equilibrium

__all__ = ["JOURNAL_AND_DISC", "CYCLE_DEFAULTS", "default_cycle_settings", "gfb_cycle_problem",
           "gfb_equilibrium_problem", "gfb_self_excited_problem", "jacobian_sparsity", "linear_response_start", "unbalance_response_start",
           "rotor_components",
           "continue_gfb_cycles", "continue_gfb_equilibria", "continue_gfb_hopf_cycles", "hopf_criticality",
           "film_monitor", "CONTACT_ACTIONS",
           "CONVENTIONS", "branch_meta", "branch_units", "describe_branch"]

JOURNAL_AND_DISC = ("x_j", "y_j", "x_d", "y_d")


def _f_cycles(x, lam, args):
    return vector_field(x, lam, args)


def _f_equilibria(x, lam, args):
    return core_rates(x, lam, jnp.zeros(2, x.dtype), args)


def rotor_components(params: Params, oscillator: bool = True) -> list[int]:
    """State indices of the rotor positions (journal x, y, then disc x, y for the Jeffcott rotor)."""
    lay = layout(params, oscillator)
    start = lay.slices["rotor"].start
    npos = 4 if params.rotor == "jeffcott" else 2
    return list(range(start, start + npos))


CONTACT_ACTIONS = ("stop", "flag")


def _h_min(x: jax.Array, lam: jax.Array, params: Params) -> jax.Array:
    return jnp.min(film(x, params))


def film_monitor(h_rub: float = 0.0, on_contact: str = "stop") -> cont.Monitor:
    """The minimum film thickness h_min / c as the physical bound of a GFB branch (:class:`gfbjax.cont.Monitor`).

    Why: the model's film is the gap between journal and foil; where it closes (h_min <= 0) the Reynolds equation
    no longer describes the bearing (the journal rubs the foil), yet the equations still have converged
    solutions there.  ``h_rub`` [over c] is the thickness at which contact is declared (0: the film closes; a
    rub allowance or the surface roughness, > 0).  ``on_contact``: "stop" ends the branch at the located contact
    (``Outcome.CONTACT``), "flag" continues and flags the points below ``h_rub`` (``Branch.flagged``).  Every
    point's h_min is in ``Branch.monitor``.  ParameterError for a bad ``h_rub`` or ``on_contact``.
    """
    h_rub = limits.Range("h_rub", -1.0, 1.0, hi_open=True, what="contact film thickness over c").check(h_rub)
    if on_contact not in CONTACT_ACTIONS:
        raise ParameterError(f"on_contact must be one of {CONTACT_ACTIONS}, got {on_contact!r}")
    return cont.Monitor("h_min", _h_min, float(h_rub), stop=on_contact == "stop", unit="c")


def gfb_cycle_problem(params: Params, monitor: cont.Monitor | None = None) -> cont.CycleProblem:
    """Periodic orbits of the autonomous unbalanced system, Eq. (21), in Omega_bar (one trivial multiplier).

    The problem carries the Jacobian's sparsity pattern: on fine grids the continuation uses the sparse
    per-interval LU of sparse linear solver of :mod:`gfbjax.cont` (``CycleSettings.linear_solver=None``, automatic)."""
    lay = layout(params, oscillator=True)
    return cont.CycleProblem(f=_f_cycles, n=lay.n, args=params, n_trivial=1,
                             record=rotor_components(params, True), jac_sparsity=jacobian_sparsity(params),
                             monitor=monitor)


def gfb_self_excited_problem(params: Params, monitor: cont.Monitor | None = None) -> cont.CycleProblem:
    """Periodic orbits of the *balanced* core system (no oscillator): the self-excited whirl cycles that emanate
    from a Hopf point of the equilibria (paper Table 1), in Omega_bar; period unknown, one trivial multiplier."""
    lay = layout(params, oscillator=False)
    return cont.CycleProblem(f=_f_equilibria, n=lay.n, args=params, n_trivial=1,
                             record=rotor_components(params, False), jac_sparsity=jacobian_sparsity(params, False),
                             monitor=monitor)


def gfb_equilibrium_problem(params: Params, monitor: cont.Monitor | None = None) -> cont.EquilibriumProblem:
    """Equilibria of the balanced system (G0) in Omega_bar: Hopf points start self-excited cycles."""
    lay = layout(params, oscillator=False)
    return cont.EquilibriumProblem(f=_f_equilibria, n=lay.n, args=params, record=rotor_components(params, False),
                                   monitor=monitor)


#: d(core rates)/d(state) and d/d(unbalance force), compiled once per grid.  Evaluated op by op, every primitive
#: is compiled on its first call in each process, which the persistent cache does not keep: 6.6 s for the pair on
#: 48x8 in a fresh process, against 0.6 s for this kernel (0.01 s once compiled or loaded).
_core_jacobians = eqx.filter_jit(jax.jacfwd(core_rates, argnums=(0, 2)))


def linear_response_start(params: Params, omega: float, equilibrium: StaticResult | None = None
                          ) -> tuple[Callable[[np.ndarray], np.ndarray], float, StaticResult]:
    """The linear forced response to unbalance around the static equilibrium at ``omega`` (see module doc).

    Returns ``(x_of_t, T, equilibrium)`` with ``x_of_t`` a vectorised function of the scaled time t in [0, 1]
    giving the full autonomous state (oscillator included) and ``T = 2 pi / omega``.
    """
    eq = equilibrium if equilibrium is not None else solve_equilibrium(params, omega)
    if not eq.converged:
        raise NoSolutionError(f"no static equilibrium at Omega_bar = {omega}: {eq.message}")
    x_eq = jnp.asarray(eq.state)
    om = jnp.asarray(float(omega))
    J, B = (np.asarray(a) for a in _core_jacobians(x_eq, om, jnp.zeros(2), params.traced()))
    F = float(params.eps) * float(omega) ** 2 * np.array([1.0, -1.0j])
    X = np.linalg.solve(1j * float(omega) * np.eye(J.shape[0]) - J, B @ F)
    T = 2.0 * math.pi / float(omega)
    xe = np.asarray(x_eq)

    def x_of_t(t: np.ndarray) -> np.ndarray:
        ph = 2.0 * math.pi * np.asarray(t)
        core = xe[None, :] + np.real(X[None, :] * np.exp(1j * ph)[:, None])
        return np.concatenate([core, np.cos(ph)[:, None], np.sin(ph)[:, None]], axis=1)

    return x_of_t, T, eq


def _guess_films(params: Params, x_of_t: Callable[[np.ndarray], np.ndarray], x_eq: np.ndarray, samples: int = 64
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Film thickness h/c of the equilibrium ``x_eq`` (core states) at every circumferential node, shape (Nx+1,), and
    the change the guess ``x_of_t`` makes to it at ``samples`` times of one period, shape (samples, Nx+1).  The film
    is linear in the state, so the guess scaled by s changes it by s times as much."""
    from ..model import film

    t = np.linspace(0.0, 1.0, samples, endpoint=False)
    h = np.asarray(jax.vmap(lambda x: film(x, params))(jnp.asarray(x_of_t(t)[:, :-2])))
    h_eq = np.asarray(film(jnp.asarray(x_eq), params))
    return h_eq, h - h_eq[None, :]


def unbalance_response_start(params: Params, omega: float, settings: cont.CycleSettings | None = None, *,
                             equilibrium: StaticResult | None = None, open_fraction: float = 0.5,
                             max_stages: int = 40) -> tuple[cont.Orbit, str]:
    """A start for the unbalance-response cycle at speed ``omega`` (Omega_bar), on the mesh of ``settings``.

    Returns ``(orbit, how)``.  ``how = "linear"``: the linear forced response (:func:`linear_response_start`),
    uncorrected, when its film stays open (h > 0 at every node over the period).  Otherwise ``how =
    "unbalance ramp"`` and ``orbit`` is a converged cycle: the unbalance ``eps`` is scaled by ``s``, starting where
    the linear guess keeps at least ``open_fraction`` of the equilibrium's film at every node (the linearised film
    is linear in ``s``), and ``s`` is raised to 1 in steps that grow by 1.5 after a converged cycle and halve after
    a failed one, each cycle warm-starting the next (at most ``max_stages`` corrections).

    Raises :class:`gfbjax.NoSolutionError` when the ramp stalls (step below 1e-3) or no static equilibrium exists.
    """
    settings = settings or default_cycle_settings()
    x_of_t, T, eq = linear_response_start(params, omega, equilibrium)
    scheme = cont.Scheme(settings.m, settings.collocation)
    mesh = cont.uniform_mesh(settings.N)
    xe_core = np.asarray(eq.state)
    h_eq, dh = _guess_films(params, x_of_t, xe_core)
    if float(np.min(h_eq[None, :] + dh)) > 0.0:
        return cont.orbit_from_function(x_of_t, T, float(omega), scheme, mesh), "linear"
    closing = dh < 0.0
    s0 = float(np.min(((1.0 - open_fraction) * np.broadcast_to(h_eq, dh.shape))[closing] / -dh[closing]))
    s0 = min(max(s0, 1e-3), 1.0)

    def scaled_guess(s: float):
        def x_s(t):
            x = x_of_t(t)
            core = xe_core[None, :] + s * (x[:, :-2] - xe_core[None, :])
            return np.concatenate([core, x[:, -2:]], axis=1)
        return cont.orbit_from_function(x_s, T, float(omega), scheme, mesh)

    newton = dataclasses.replace(settings, newton_max_iter=max(settings.newton_max_iter, 12))
    eps = params.eps
    orbit, s_done, s, step = None, 0.0, s0, s0
    for _ in range(max_stages):
        p_s = eqx.tree_at(lambda q: q.eps, params, jnp.asarray(float(eps) * s, dtype=jnp.float64))
        guess = scaled_guess(s) if orbit is None else orbit
        sol, _ = cont.correct_cycle(gfb_cycle_problem(p_s), guess, settings=newton)
        if sol.converged:
            orbit, s_done = sol.x, s
            if s_done >= 1.0:
                return orbit, "unbalance ramp"
            step *= 1.5
        else:
            step *= 0.5
            if orbit is None:  # not even the first, small unbalance: shrink it
                s0 = s = s * 0.5
                if s < 1e-3:
                    break
                continue
            if step < 1e-3:
                break
        s = min(1.0, s_done + step)
    raise NoSolutionError(f"no unbalance-response cycle at Omega_bar = {omega}: the ramp in the unbalance stalled at "
                          f"{s_done:.3g} of eps = {float(eps):.4g}")


#: The GFB cycle branch's settings where :func:`default_cycle_settings` is not told otherwise (the ``cycles`` and
#: ``sweep`` commands take their defaults from here).  Points are placed by ``chord_tol``: straight lines between
#: them stay within 1 % of the plotted ranges of the branch, so they gather at the resonance and thin out where the
#: response is smooth (30 points from Omega_bar 0.05 to 1.0 on the reference system, where a fixed speed step of
#: 0.02 took 52 for the same curve to 0.7 %; benchmarks/README.md).  ``dlam_max`` is then only a guard.
CYCLE_DEFAULTS: dict[str, Any] = dict(m=4, N=16, ds=10.0, ds_min=1e-4, ds_max=20.0, dlam_max=0.1, chord_tol=1e-2,
                                      max_points=200)


def default_cycle_settings(**changes: Any) -> cont.CycleSettings:
    """Cycle-continuation settings tuned for the GFB system (:data:`CYCLE_DEFAULTS`, updated by ``changes``).

    The arclength metric includes the period ``T = 2 pi / Omega_bar``, which changes by ``2 pi / Omega_bar^2`` per
    unit speed (2500 at Omega_bar = 0.05): steps are large in that metric (``ds`` up to 20) and the speed change
    per step is capped by ``dlam_max`` instead.
    """
    return cont.CycleSettings(**{**CYCLE_DEFAULTS, **changes})


def _check_speed_range(params: Params, omega_start: float, omega_end: float) -> tuple[float, float]:
    """The checked speeds (Python floats); ParameterError for a bad Params or speed, before any work."""
    check_params(params)
    omega_start = limits.SPEED.check(omega_start, "omega_start")
    omega_end = limits.SPEED.check(omega_end, "omega_end")
    if omega_start == omega_end:
        raise ParameterError("omega_start and omega_end must differ")
    return omega_start, omega_end


def _check_settings(settings: Any, kind: type) -> Any:
    """``settings`` itself; ParameterError naming it when it is not a ``kind`` (cont.CycleSettings or
    cont.EquilibriumSettings), before an attribute of another kind fails somewhere inside."""
    if not isinstance(settings, kind):
        raise ParameterError(f"settings must be {kind.__name__} or None, got {type(settings).__name__}")
    return settings


def _within_range(settings: Any, omega_start: float, omega_end: float) -> Any:
    """``settings`` (cycles or equilibria) bounded by the speed range and heading from ``omega_start`` to
    ``omega_end``.  Bounds of the settings inside the range stay in force (the branch ends at them); ParameterError
    when ``omega_start`` lies outside them or on the one it would head past, before any work."""
    lo_s, hi_s = settings.lam_min, settings.lam_max
    ahead = hi_s if omega_end > omega_start else lo_s
    if not lo_s <= omega_start <= hi_s or omega_start == ahead:
        raise ParameterError(f"omega_start = {omega_start:g} leaves no room towards omega_end = {omega_end:g} inside "
                             f"the settings' speed bounds [lam_min, lam_max] = [{lo_s:g}, {hi_s:g}]; start inside "
                             "them or widen them")
    lo, hi = sorted((omega_start, omega_end))
    return dataclasses.replace(settings, lam_min=max(lo_s, lo), lam_max=min(hi_s, hi),
                               direction=1 if omega_end > omega_start else -1)


def _check_size(problem: cont.CycleProblem, settings: cont.CycleSettings) -> None:
    """The engine's size checks (memory of the collocation system, Floquet method) as a ParameterError."""
    try:
        cont.check_cycle_size(problem, settings.N, settings.m, settings)
    except ValueError as exc:
        raise ParameterError(str(exc)) from None


def continue_gfb_cycles(params: Params, omega_start: float, omega_end: float,
                        settings: cont.CycleSettings | None = None, *, progress: bool = False,
                        callback: Callable[[int, Any], Any] | None = None,
                        spec: SystemSpec | None = None, checkpoint: str | os.PathLike | None = None,
                        h_rub: float = 0.0, on_contact: str = "stop") -> cont.Branch:
    """Branch of unbalance-response limit cycles from ``omega_start`` towards ``omega_end`` (Omega_bar).

    The start is the linear forced response at ``omega_start`` (corrected by collocation Newton); the branch
    follows pseudo-arclength continuation with Floquet multipliers and LPC/PD/NS detection.  ``settings`` may
    omit the speed bounds: they are set from the range.  Whatever ends the branch, the finished points are
    returned with the reason (``Branch.outcome``, ``Branch.message``).

    The branch describes itself (:func:`branch_meta`): ``meta`` holds the dimensionless groups, the grid, the
    state layout and the conventions, and with ``spec`` (the SystemSpec ``params`` came from) also the SI system
    and the rpm conversion; ``component_names`` are x_j, y_j (, x_d, y_d); ``units`` those of each array.
    ParameterError when ``spec`` is not the system of ``params``.

    ``checkpoint``: a folder that every accepted point is appended to, with the state the next step starts from
    (:class:`gfbjax.cont.Checkpoint`); calling again with the same folder and arguments resumes after the last
    point and gives the branch an uninterrupted run gives (``CheckpointError`` for a folder of another run).

    Film contact: the minimum film thickness over each cycle is watched (``Branch.monitor``, over c); where it
    falls to ``h_rub`` the branch ends there (``on_contact="stop"``, outcome ``CONTACT``) or goes on with the
    points flagged (``"flag"``), see :func:`film_monitor`.
    """
    omega_start, omega_end = _check_speed_range(params, omega_start, omega_end)
    monitor = film_monitor(h_rub, on_contact)
    if float(params.eps) <= 0.0:
        raise ParameterError("eps = 0 (balanced rotor): there is no forced cycle; use continue_gfb_equilibria "
                             "and start cycles from its Hopf point (continue_gfb_hopf_cycles; on the command line: "
                             "gfbjax equilibria --hopf-cycles)")
    settings = _within_range(_check_settings(settings or default_cycle_settings(), cont.CycleSettings), omega_start,
                             omega_end)
    meta = branch_meta(params, "unbalance_response", spec)  # before the work: a spec of another system fails fast
    problem = gfb_cycle_problem(params, monitor)
    _check_size(problem, settings)
    orbit, how = unbalance_response_start(params, omega_start, settings)
    start = cont.CycleStart(orbit, None, how)
    branch = cont.continue_cycles(problem, settings, start, progress=progress, callback=callback,
                                  checkpoint=_checkpoint(checkpoint, meta, omega_start, omega_end,
                                                         monitor.describe()))
    return describe_branch(branch, meta)


def _checkpoint(folder: str | os.PathLike | None, meta: dict[str, Any], *args: Any) -> cont.Checkpoint | None:
    """The checkpoint of a GFB branch: its identity is the system (``meta``) and the arguments of the call."""
    return None if folder is None else cont.Checkpoint(folder, {"system": meta, "arguments": list(args)})


def continue_gfb_hopf_cycles(params: Params, equilibria: cont.Branch, which: int = 0,
                             settings: cont.CycleSettings | None = None, *, progress: bool = False,
                             callback: Callable[[int, Any], Any] | None = None,
                             spec: SystemSpec | None = None,
                             checkpoint: str | os.PathLike | None = None,
                             h_rub: float = 0.0, on_contact: str = "stop") -> cont.Branch:
    """Self-excited cycles from the ``which``-th Hopf point of an equilibrium branch (:func:`continue_gfb_equilibria`).

    The branch leaves the Hopf point along its first harmonic; toward higher speed with stable cycles when the
    Hopf bifurcation is supercritical, toward lower speed with unstable ones when it is subcritical (the sign of
    ``Branch.tangent_lam`` on the first points tells which).  ``settings.lam_min``/``lam_max`` bound the speed.
    The branch describes itself as in :func:`continue_gfb_cycles` (``spec``: the SystemSpec of ``params``), and
    ``checkpoint``, ``h_rub`` and ``on_contact`` work as there."""
    settings = _check_settings(settings or default_cycle_settings(m=4, N=16, ds=0.02, ds_max=0.5, dlam_max=0.01,
                                                                  max_points=80), cont.CycleSettings)
    meta = branch_meta(params, "self_excited", spec)
    _check_equilibria_of(params, equilibria)
    monitor = film_monitor(h_rub, on_contact)
    hp = cont.hopf_point(gfb_equilibrium_problem(params), equilibria, which)
    problem = gfb_self_excited_problem(params, monitor)
    _check_size(problem, settings)
    start = cont.start_from_hopf(hp, settings)
    branch = cont.continue_cycles(problem, settings, start, progress=progress, callback=callback,
                                  checkpoint=_checkpoint(checkpoint, meta, float(hp.lam), which,
                                                         monitor.describe()))
    return describe_branch(branch, meta)


def _check_equilibria_of(params: Params, equilibria: Any) -> None:
    """ParameterError when the equilibrium branch records (``meta["params"]``) a balanced system other than that
    of ``params``: its Hopf point is then no Hopf point of these cycles, which would end at once with no point and no
    reason.  The unbalance ``eps`` is left out (both problems are of the balanced system); a branch without that
    record (not from :func:`continue_gfb_equilibria`) is not checked."""
    recorded = (getattr(equilibria, "meta", None) or {}).get("params")
    if not isinstance(recorded, dict):
        return
    differ = []
    for f in dataclasses.fields(params):
        if f.name == "eps" or f.name not in recorded:
            continue
        v, w = _plain(getattr(params, f.name)), recorded[f.name]
        same = (math.isclose(v, w, rel_tol=1e-12, abs_tol=1e-300)
                if isinstance(v, float) and isinstance(w, float) else v == w)
        if not same:
            differ.append(f"{f.name} = {v!r} (the equilibria: {w!r})")
    if differ:
        raise ParameterError("params are not the system the equilibria were computed for: " + ", ".join(differ[:5])
                             + (" ..." if len(differ) > 5 else "") + "; pass the params of continue_gfb_equilibria")


def hopf_criticality(cycles: cont.Branch, lam_hopf: float) -> str:
    """"subcritical" when the first cycles from a Hopf point lie below its speed and are unstable, "supercritical"
    when they lie above it and are stable, else "undetermined"."""
    if len(cycles) == 0:
        return "undetermined"
    if cycles.lam[0] < lam_hopf and not cycles.stable[0]:
        return "subcritical"
    if cycles.lam[0] > lam_hopf and cycles.stable[0]:
        return "supercritical"
    return "undetermined"


def continue_gfb_equilibria(params: Params, omega_start: float, omega_end: float,
                            settings: cont.EquilibriumSettings | None = None, *, spec: SystemSpec | None = None,
                            checkpoint: str | os.PathLike | None = None, h_rub: float = 0.0,
                            on_contact: str = "stop", **kw: Any) -> cont.Branch:
    """Branch of static equilibria of the balanced system in Omega_bar, with eigenvalues, Hopf and fold points.

    The branch describes itself as in :func:`continue_gfb_cycles` (``spec``: the SystemSpec of ``params``), and
    ``checkpoint``, ``h_rub`` and ``on_contact`` (the film thickness of each equilibrium) work as there; ``kw``
    goes to :func:`gfbjax.cont.continue_equilibria` (``callback``, ``progress``).  ``settings`` may omit the speed
    bounds; bounds it sets inside the range narrow it (the branch ends at them).  The start must lie inside them
    (ParameterError otherwise)."""
    omega_start, omega_end = _check_speed_range(params, omega_start, omega_end)
    monitor = film_monitor(h_rub, on_contact)
    meta = branch_meta(params, "equilibria", spec)  # before the work: a spec of another system fails fast
    settings = _within_range(_check_settings(settings or cont.EquilibriumSettings(), cont.EquilibriumSettings),
                             omega_start, omega_end)
    eq = solve_equilibrium(params, omega_start)
    if not eq.converged:
        raise NoSolutionError(f"no static equilibrium at Omega_bar = {omega_start}: {eq.message}")
    branch = cont.continue_equilibria(gfb_equilibrium_problem(params, monitor), settings, eq.state, omega_start,
                                      checkpoint=_checkpoint(checkpoint, meta, omega_start, omega_end,
                                                             monitor.describe()), **kw)
    return describe_branch(branch, meta)


# -- self-describing branches -------------------------------------------------------------------------------

#: Conventions of every branch of this module (docs/model.md, :mod:`gfbjax.params`), written into ``Branch.meta``
#: so that a branch file can be read without gfbjax at hand.
CONVENTIONS = {
    "time": "tau = t / t*, t* = 6 mu R^2 / (p0 c^2) [s]",
    "speed": "Omega_bar = Omega t*, the bearing number Lambda = 6 mu Omega R^2 / (p0 c^2); "
             "rpm = Omega_bar / t* * 60 / (2 pi)",
    "lengths": "over the nominal radial clearance c",
    "pressures": "over the ambient pressure p0",
    "forces": "over p0 R L",
    "axes": "x horizontal, y vertical and pointing up (gravity along -y); the rotor spins from x towards y",
    "theta0": "angle of the foil's fixed end [rad], from the x axis towards the y axis",
    "unbalance": "eps = e_u / c with e_u = G / omega_r (ISO 1940, G in mm/s; omega_r in spec.omega_r_unit) unless "
                 "e_u is given, times (m_d + 2 m_j) / m_d when spec.unbalance_mass is 'rotor'",
    "foil_damping": "c_f = eta k_f / Omega_bar when params.structural_damping is 1 (spec.foil_damping "
                    "'structural'), eta k_f when 0 ('paper')",
    "rotor_states": "jeffcott: x_j, y_j, x_d, y_d and their d/dtau; rigid: x_j, y_j and their d/dtau",
    "model_options": "params.gumbel 'forces': max(p - 1, 0) in the bearing force and foil drive, 'pressure': the "
                     "film kept at or above ambient as well; params.foil_springs 'all': a spring under each of the "
                     "Nx - 1 strips, 'no_first' / 'no_last': the first / last strip from theta0 held at q = 0; "
                     "params.axial_domain 'half': pressures on the half length (edge to mid-plane, n_z = Nz), "
                     "'full': on the whole length (n_z = 2 Nz - 1)",
}

_PROBLEMS = {
    "unbalance_response": "synchronous limit cycles of the unbalanced rotor, autonomous form Eq. (21)-(22) "
                          "with the phase oscillator (one trivial Floquet multiplier)",
    "self_excited": "self-excited whirl cycles of the rotor without unbalance forcing (no oscillator), from a "
                    "Hopf point of its equilibria",
    "equilibria": "static equilibria of the rotor without unbalance forcing; multipliers are the Jacobian's "
                  "eigenvalues",
}


def branch_units(kind: str) -> dict[str, str]:
    """Units of the arrays of a GFB branch of ``kind`` ("cycles" or "equilibria"), for ``Branch.units``."""
    return {"lam": "Omega_bar = Omega t* (dimensionless speed)",
            "period": "tau = t / t*" if kind == "cycles" else "tau = t / t* (NaN: equilibria have none)",
            "l2": "dimensionless (norm of the whole state: pressures over p0, lengths over c, d/dtau)",
            "xmax": "over clearance c", "xmin": "over clearance c",
            "multipliers": "dimensionless (Floquet multipliers)" if kind == "cycles"
            else "per tau (eigenvalues of the Jacobian)",
            "trivial_error": "dimensionless", "ds": "arclength of the continuation", "tangent_lam": "dimensionless"}


def branch_meta(params: Params, problem: str, spec: SystemSpec | None = None) -> dict[str, Any]:
    """What a GFB branch file records about its system (``Branch.meta``; JSON-able).

    Keys: ``model``, ``problem`` (``"unbalance_response"``, ``"self_excited"`` or ``"equilibria"``) and its
    ``problem_description``, ``gfbjax_version``, ``continuation_parameter``, ``conventions``
    (:data:`CONVENTIONS`), ``params`` (every field of ``params``: the dimensionless groups as floats, grid, rotor
    kind), ``grid`` (``Nx``, ``Nz``, ``n_theta``, ``n_pressure``), ``state_layout`` (``n`` states, ``oscillator``,
    ``slices`` as [start, stop) per part, ``rotor_states`` names), ``component_names`` and, with ``spec``:
    ``spec`` (``spec.to_dict()``, SI, with the convention switches ``foil_damping``, ``unbalance_mass`` and
    ``omega_r_unit``), ``preset`` (``spec.preset``), ``t_star_s`` [s], ``c_m`` [m] and ``rpm_per_omega_bar``
    (``spec.rpm(1.0)``: rpm = Omega_bar * rpm_per_omega_bar).

    Raises ParameterError when ``spec`` is not the system of ``params`` (a field of ``spec.nondim()`` differs),
    so that a file never names a system it was not computed for.
    """
    from .. import __version__

    if problem not in _PROBLEMS:
        raise ValueError(f"problem must be one of {sorted(_PROBLEMS)}, got {problem!r}")
    oscillator = problem == "unbalance_response"
    groups = {f.name: _plain(getattr(params, f.name)) for f in dataclasses.fields(params)}
    if spec is not None:
        if not isinstance(spec, SystemSpec):
            raise TypeError(f"spec must be a SystemSpec, got {type(spec).__name__}")
        own = {f.name: _plain(getattr(spec.nondim(), f.name)) for f in dataclasses.fields(params)}
        for name, v in own.items():
            w = groups[name]
            same = (math.isclose(v, w, rel_tol=1e-12, abs_tol=1e-300)
                    if isinstance(v, float) and isinstance(w, float) else v == w)
            if not same:
                raise ParameterError(f"spec does not describe params: {name} = {v!r} from spec.nondim(), "
                                     f"{w!r} in params")
    lay = layout(params, oscillator)
    npos = len(rotor_components(params, oscillator))
    rotor_states = list(JOURNAL_AND_DISC[:npos]) + [f"{s}'" for s in JOURNAL_AND_DISC[:npos]]
    meta: dict[str, Any] = {
        "model": "gfbjax GFB-rotor (rotor on two identical gas foil bearings)",
        "problem": problem, "problem_description": _PROBLEMS[problem], "gfbjax_version": __version__,
        "continuation_parameter": "Omega_bar",
        "conventions": dict(CONVENTIONS),
        "params": groups,
        "grid": {"Nx": int(params.Nx), "Nz": int(params.Nz), "n_theta": int(lay.grid.n_theta),
                 "n_pressure": int(lay.grid.n_pressure)},
        "state_layout": {"n": int(lay.n), "oscillator": oscillator,
                         "slices": {k: [int(s.start), int(s.stop)] for k, s in lay.slices.items()
                                    if s.stop > s.start},
                         "rotor_states": rotor_states},
        "component_names": list(JOURNAL_AND_DISC[:npos]),
    }
    if spec is not None:
        meta.update({"spec": spec.to_dict(), "preset": spec.preset, "t_star_s": spec.t_star, "c_m": spec.c,
                     "rpm_per_omega_bar": spec.rpm(1.0)})
    return meta


def describe_branch(branch: cont.Branch, meta: dict[str, Any]) -> cont.Branch:
    """Attach :func:`branch_meta` to ``branch`` (its ``meta``, ``component_names`` and ``units``); returns it."""
    branch.meta = meta
    branch.component_names = list(meta["component_names"])
    branch.units = branch_units(branch.kind)
    return branch


def _plain(v: Any) -> Any:
    """A Params / spec field as a JSON value: str, int and bool as they are, numbers and 0-d arrays as float,
    arrays as nested lists of floats."""
    if isinstance(v, (str, bool, int)) or v is None:
        return v
    a = np.asarray(v, dtype=float)
    return float(a) if a.ndim == 0 else a.tolist()
