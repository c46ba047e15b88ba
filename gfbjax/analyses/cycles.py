"""Limit cycles of the unbalanced GFB-rotor system and equilibria of the balanced one, on the generic engine
:mod:`gfbjax.cont` (paper Sect. 2.3, 3.2, Appendix A1).

The cycles are those of the autonomous system of Eq. (21)-(22): the phase oscillator makes the unbalance forcing
autonomous, so a synchronous (1X) response is a periodic orbit of period ``T = 2 pi / Omega_bar`` and the Floquet
multipliers carry one trivial multiplier at +1.  The continuation parameter is the speed Omega_bar.

A branch starts at a low speed from the *linear forced response* around the static equilibrium,

    x(tau) = x_eq + Re( (i Omega I - J)^-1 B eps Omega^2 (1, -i) e^{i Omega tau} ),

with J the Jacobian of the balanced system and B the input matrix of the unbalance force, a first-order harmonic
balance that puts collocation Newton well inside its basin.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from .. import cont
from ..model import core_rates, layout, vector_field
from ..model.pattern import jacobian_sparsity
from .. import limits
from ..params import ParameterError, Params, SystemSpec
from ..limits import NoSolutionError
from .static import StaticResult, solve_equilibrium

__all__ = ["JOURNAL_AND_DISC", "default_cycle_settings", "gfb_cycle_problem", "gfb_equilibrium_problem",
           "gfb_self_excited_problem", "jacobian_sparsity", "linear_response_start", "rotor_components",
           "continue_gfb_cycles", "continue_gfb_equilibria", "continue_gfb_hopf_cycles", "hopf_criticality",
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


def gfb_cycle_problem(params: Params) -> cont.CycleProblem:
    """Periodic orbits of the autonomous unbalanced system, Eq. (21), in Omega_bar (one trivial multiplier).

    The problem carries the Jacobian's sparsity pattern: on fine grids the continuation uses the sparse
    per-interval LU of sparse linear solver of :mod:`gfbjax.cont` (``CycleSettings.linear_solver=None``, automatic)."""
    lay = layout(params, oscillator=True)
    return cont.CycleProblem(f=_f_cycles, n=lay.n, args=params, n_trivial=1,
                             record=rotor_components(params, True), jac_sparsity=jacobian_sparsity(params))


def gfb_self_excited_problem(params: Params) -> cont.CycleProblem:
    """Periodic orbits of the *balanced* core system (no oscillator): the self-excited whirl cycles that emanate
    from a Hopf point of the equilibria (paper Table 1), in Omega_bar; period unknown, one trivial multiplier."""
    lay = layout(params, oscillator=False)
    return cont.CycleProblem(f=_f_equilibria, n=lay.n, args=params, n_trivial=1,
                             record=rotor_components(params, False), jac_sparsity=jacobian_sparsity(params, False))


def gfb_equilibrium_problem(params: Params) -> cont.EquilibriumProblem:
    """Equilibria of the balanced system (G0) in Omega_bar: Hopf points start self-excited cycles."""
    lay = layout(params, oscillator=False)
    return cont.EquilibriumProblem(f=_f_equilibria, n=lay.n, args=params, record=rotor_components(params, False))


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
    J = np.asarray(jax.jacfwd(core_rates)(x_eq, om, jnp.zeros(2), params))
    B = np.asarray(jax.jacfwd(core_rates, argnums=2)(x_eq, om, jnp.zeros(2), params))
    F = float(params.eps) * float(omega) ** 2 * np.array([1.0, -1.0j])
    X = np.linalg.solve(1j * float(omega) * np.eye(J.shape[0]) - J, B @ F)
    T = 2.0 * math.pi / float(omega)
    xe = np.asarray(x_eq)

    def x_of_t(t: np.ndarray) -> np.ndarray:
        ph = 2.0 * math.pi * np.asarray(t)
        core = xe[None, :] + np.real(X[None, :] * np.exp(1j * ph)[:, None])
        return np.concatenate([core, np.cos(ph)[:, None], np.sin(ph)[:, None]], axis=1)

    return x_of_t, T, eq


def default_cycle_settings(**changes: Any) -> cont.CycleSettings:
    """Cycle-continuation settings tuned for the GFB system.

    The arclength metric includes the period ``T = 2 pi / Omega_bar``, which changes by ``2 pi / Omega_bar^2`` per
    unit speed (2500 at Omega_bar = 0.05): steps are large in that metric (``ds`` up to 20) and the speed change
    per step is capped by ``dlam_max`` instead.
    """
    base = dict(m=4, N=16, ds=10.0, ds_min=1e-4, ds_max=20.0, dlam_max=0.02, max_points=200)
    base.update(changes)
    return cont.CycleSettings(**base)


def _check_speed_range(params: Params, omega_start: float, omega_end: float) -> tuple[float, float]:
    """The checked speeds (Python floats); ParameterError for a bad Params or speed, before any work."""
    params.check()
    omega_start = limits.SPEED.check(omega_start, "omega_start")
    omega_end = limits.SPEED.check(omega_end, "omega_end")
    if omega_start == omega_end:
        raise ParameterError("omega_start and omega_end must differ")
    return omega_start, omega_end


def _check_size(problem: cont.CycleProblem, settings: cont.CycleSettings) -> None:
    """The engine's size checks (memory of the collocation system, Floquet method) as a ParameterError."""
    try:
        cont.check_cycle_size(problem, settings.N, settings.m, settings)
    except ValueError as exc:
        raise ParameterError(str(exc)) from None


def continue_gfb_cycles(params: Params, omega_start: float, omega_end: float,
                        settings: cont.CycleSettings | None = None, *, progress: bool = False,
                        callback: Callable[[int, Any], Any] | None = None,
                        spec: SystemSpec | None = None) -> cont.Branch:
    """Branch of unbalance-response limit cycles from ``omega_start`` towards ``omega_end`` (Omega_bar).

    The start is the linear forced response at ``omega_start`` (corrected by collocation Newton); the branch
    follows pseudo-arclength continuation with Floquet multipliers and LPC/PD/NS detection.  ``settings`` may
    omit the speed bounds: they are set from the range.  Whatever ends the branch, the finished points are
    returned with the reason (``Branch.outcome``, ``Branch.message``).

    The branch describes itself (:func:`branch_meta`): ``meta`` holds the dimensionless groups, the grid, the
    state layout and the conventions, and with ``spec`` (the SystemSpec ``params`` came from) also the SI system
    and the rpm conversion; ``component_names`` are x_j, y_j (, x_d, y_d); ``units`` those of each array.
    ParameterError when ``spec`` is not the system of ``params``.
    """
    omega_start, omega_end = _check_speed_range(params, omega_start, omega_end)
    if float(params.eps) <= 0.0:
        raise ParameterError("eps = 0 (balanced rotor): there is no forced cycle; use continue_gfb_equilibria "
                             "and start cycles from its Hopf point")
    settings = settings or default_cycle_settings()
    lo, hi = sorted((omega_start, omega_end))
    direction = 1 if omega_end > omega_start else -1
    import dataclasses

    settings = dataclasses.replace(settings, lam_min=max(settings.lam_min, lo), lam_max=min(settings.lam_max, hi),
                                   direction=direction)
    meta = branch_meta(params, "unbalance_response", spec)  # before the work: a spec of another system fails fast
    problem = gfb_cycle_problem(params)
    _check_size(problem, settings)
    x_of_t, T, _ = linear_response_start(params, omega_start)
    start = cont.start_from_function(x_of_t, T, omega_start, settings)
    branch = cont.continue_cycles(problem, settings, start, progress=progress, callback=callback)
    return describe_branch(branch, meta)


def continue_gfb_hopf_cycles(params: Params, equilibria: cont.Branch, which: int = 0,
                             settings: cont.CycleSettings | None = None, *, progress: bool = False,
                             callback: Callable[[int, Any], Any] | None = None,
                             spec: SystemSpec | None = None) -> cont.Branch:
    """Self-excited cycles from the ``which``-th Hopf point of an equilibrium branch (:func:`continue_gfb_equilibria`).

    The branch leaves the Hopf point along its first harmonic; toward higher speed with stable cycles when the
    Hopf bifurcation is supercritical, toward lower speed with unstable ones when it is subcritical (the sign of
    ``Branch.tangent_lam`` on the first points tells which).  ``settings.lam_min``/``lam_max`` bound the speed.
    The branch describes itself as in :func:`continue_gfb_cycles` (``spec``: the SystemSpec of ``params``)."""
    settings = settings or default_cycle_settings(m=4, N=16, ds=0.02, ds_max=0.5, dlam_max=0.01, max_points=80)
    meta = branch_meta(params, "self_excited", spec)
    hp = cont.hopf_point(gfb_equilibrium_problem(params), equilibria, which)
    problem = gfb_self_excited_problem(params)
    _check_size(problem, settings)
    start = cont.start_from_hopf(hp, settings)
    branch = cont.continue_cycles(problem, settings, start, progress=progress, callback=callback)
    return describe_branch(branch, meta)


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
                            **kw: Any) -> cont.Branch:
    """Branch of static equilibria of the balanced system in Omega_bar, with eigenvalues, Hopf and fold points.

    The branch describes itself as in :func:`continue_gfb_cycles` (``spec``: the SystemSpec of ``params``);
    ``kw`` goes to :func:`gfbjax.cont.continue_equilibria` (``callback``, ``progress``)."""
    omega_start, omega_end = _check_speed_range(params, omega_start, omega_end)
    meta = branch_meta(params, "equilibria", spec)  # before the work: a spec of another system fails fast
    eq = solve_equilibrium(params, omega_start)
    if not eq.converged:
        raise NoSolutionError(f"no static equilibrium at Omega_bar = {omega_start}: {eq.message}")
    settings = settings or cont.EquilibriumSettings()
    import dataclasses

    lo, hi = sorted((omega_start, omega_end))
    fields = {f.name for f in dataclasses.fields(settings)}
    upd = {k: v for k, v in (("lam_min", lo), ("lam_max", hi),
                             ("direction", 1 if omega_end > omega_start else -1)) if k in fields}
    settings = dataclasses.replace(settings, **upd)
    branch = cont.continue_equilibria(gfb_equilibrium_problem(params), settings, eq.state, omega_start, **kw)
    return describe_branch(branch, meta)


# -- self-describing branches -------------------------------------------------------------------------------

#: Conventions of every branch of this module (DESIGN.md, :mod:`gfbjax.params`), written into ``Branch.meta``
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
    "unbalance": "eps = e_u / c with e_u = G / omega_r (ISO 1940, G in mm/s) unless e_u is given",
    "rotor_states": "jeffcott: x_j, y_j, x_d, y_d and their d/dtau; rigid: x_j, y_j and their d/dtau",
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
    ``spec`` (``spec.to_dict()``, SI), ``t_star_s`` [s], ``c_m`` [m] and ``rpm_per_omega_bar``
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
        meta.update({"spec": spec.to_dict(), "t_star_s": spec.t_star, "c_m": spec.c,
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
