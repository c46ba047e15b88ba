"""``gfbjax static``: static equilibrium of the balanced rotor under gravity and an extra load; optionally the
load-displacement curves and equilibrium loci of the paper's Figs. 4-5."""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from typing import Any

from ... import limits
from ...params import ParameterError, SystemSpec
from ._common import (
    add_system_options,
    check_range,
    float_list,
    output_dir,
    resolve_speeds,
    spec_from_args,
    traced_params,
    write_json,
)

NAME = "static"
DEFAULT_SPEED = 0.4
DEFAULT_ALPHAS = [0.01, 0.1, 1.0]
DEFAULT_SPEEDS = [0.2, 0.4, 0.6]
DEFAULT_LOADS = [0.0, 0.1, 0.2, 0.4, 0.8]

DESCRIPTION = """\
Static equilibrium of the balanced rotor (no unbalance) on its two gas foil bearings at one speed, under gravity
plus an extra vertical load per bearing: journal position, film, pressure, foil deflection and the linear
stability from the eigenvalues of the Jacobian (paper Sect. 3.1).  With --curves, also the journal's vertical
displacement against the specific load (paper Fig. 4) and the equilibrium loci with mid-plane pressure and foil
deflection profiles (paper Fig. 5), for several foil compliances alpha_f and speeds.

Writes to --out: static.json (summary of the equilibrium, curves, the system spec and its dimensionless groups),
static_summary.png and, with --curves, load_displacement.png and equilibrium_locus.png.
Exit status: 0 when the equilibrium converged, 1 when the bearing cannot carry the load at this speed (film
closes: "contact") or Newton failed, 2 for invalid input.
"""

EPILOG = """\
units: speeds are dimensionless, Omega_bar = Omega t* = 6 mu Omega R^2 / (p0 c^2) (the bearing number); specific
loads are W / (p0 L D) per bearing, beyond gravity; lengths are reported over the clearance c and in um.

examples:
  gfbjax static                                   reference system at Omega_bar = 0.4, gravity only
  gfbjax static --rpm 20000 --load 5              5 N extra per bearing at 20000 rpm
  gfbjax static --system af1 --set eta=0.2 --w 0.3
  gfbjax static --curves --speeds 0.2,0.5,1 --loads 0,0.25,0.5,1
"""


def register(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        NAME, help="static equilibrium under load; load-displacement curves and loci (paper Figs. 4-5)",
        description=DESCRIPTION, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_system_options(p, NAME)

    op = p.add_argument_group("operating point")
    sp = op.add_mutually_exclusive_group()
    sp.add_argument("--speed", type=float, default=None, metavar="OMEGA_BAR",
                    help=f"dimensionless speed Omega_bar in {limits.SPEED.interval()} (default {DEFAULT_SPEED:g})")
    sp.add_argument("--rpm", type=float, default=None, metavar="RPM",
                    help="shaft speed in rev/min, converted with the system's time scale t*")
    ld = op.add_mutually_exclusive_group()
    ld.add_argument("--load", type=float, default=None, metavar="NEWTON",
                    help="extra vertical (downward) load per bearing in N, beyond gravity (default 0)")
    ld.add_argument("--w", type=float, default=None, metavar="W_BAR",
                    help=f"extra specific load per bearing W/(p0 L D) in {limits.LOAD_W.interval()}, beyond gravity "
                         "(default 0); the system's own 'load' field is added to either")

    cv = p.add_argument_group("load-displacement curves and loci (paper Figs. 4-5)")
    cv.add_argument("--curves", action="store_true",
                    help="also compute the load-displacement curves and equilibrium loci and plot them")
    cv.add_argument("--alphas", type=float_list("--alphas", limits.ALPHA_F),
                    default=DEFAULT_ALPHAS, metavar="A1,A2,...",
                    help="foil compliances alpha_f, one panel each (default: %s)"
                         % ",".join(f"{v:g}" for v in DEFAULT_ALPHAS))
    cv.add_argument("--speeds", type=float_list("--speeds", limits.SPEED),
                    default=DEFAULT_SPEEDS, metavar="S1,S2,...",
                    help="dimensionless speeds Omega_bar, one curve each (default: %s)"
                         % ",".join(f"{v:g}" for v in DEFAULT_SPEEDS))
    cv.add_argument("--loads", type=float_list("--loads", limits.LOAD_W, increasing=True),
                    default=DEFAULT_LOADS, metavar="W1,W2,...",
                    help="increasing specific loads W/(p0 L D) beyond gravity along each curve (default: %s); "
                         "a curve stops at the first load whose film closes" % ",".join(f"{v:g}" for v in DEFAULT_LOADS))
    cv.add_argument("--profile-speed", type=float, default=None, metavar="OMEGA_BAR",
                    help="speed whose pressure and foil profiles are drawn in the locus figure (default: the "
                         "middle of --speeds)")

    o = p.add_argument_group("output")
    o.add_argument("--no-figures", action="store_true", help="write static.json only, no PNG figures")
    o.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
    return p


# -- helpers ---------------------------------------------------------------------------------------------------


def _force_unit(spec: SystemSpec) -> float:
    """p0 L D [N]: the unit of specific load."""
    return spec.p0 * spec.L * 2.0 * spec.R


def _operating_point(args: argparse.Namespace, spec: SystemSpec) -> tuple[float, float, float]:
    """(omega_bar, extra specific load w from the options, total extra specific load incl. spec.load)."""
    if args.rpm is not None:  # the speed range in rev/min of this system
        rpm_range = limits.SPEED.with_bounds(lo=spec.rpm(limits.SPEED.lo), hi=spec.rpm(limits.SPEED.hi),
                                             unit="rev/min", what=f"Omega_bar in {limits.SPEED.interval()}")
        omega = spec.omega_bar(check_range("--rpm", args.rpm, rpm_range))
    else:
        if args.speed is None:
            args.speed = DEFAULT_SPEED
        resolve_speeds(args, spec, ("--speed", "--rpm"))  # an rpm typed as --speed gets a hint
        omega = args.speed
    fu = _force_unit(spec)
    if args.load is not None:  # the specific-load range in N per bearing
        load_range = limits.LOAD_W.with_bounds(hi=limits.LOAD_W.hi * fu, unit="N",
                                               what=f"per bearing; W/(p0 L D) in {limits.LOAD_W.interval()}")
        w_opt = check_range("--load", args.load, load_range) / fu
    elif args.w is not None:
        w_opt = check_range("--w", args.w, limits.LOAD_W)
    else:
        w_opt = 0.0
    w = w_opt + spec.load / fu
    if not limits.LOAD_W.contains(w):
        raise ParameterError(f"load: the total extra specific load {w:g} (option + system 'load') is outside the "
                             f"allowed range {limits.LOAD_W.interval()}")
    return float(omega), float(w_opt), float(w)


def _fmt_um(v: float, c_um: float) -> str:
    return f"{v:+.4f} c ({v * c_um:+.2f} um)"


def format_summary(res: Any, spec: SystemSpec, system: str) -> str:
    """Human-readable report of one equilibrium."""
    c_um = spec.c * 1e6
    s = res.summary(spec)
    si = s["SI"]
    lam = res.critical_eigenvalue
    ts = spec.t_star
    w_n = res.w * _force_unit(spec)
    rotor = f"{spec.rotor} rotor" + (f", k_s_bar = {spec.k_s_bar:g}" if spec.rotor == "jeffcott" else "")
    lines = [
        f"gfbjax static: system '{system}' ({rotor}, alpha_f = {spec.alpha_f:g}, eta = {spec.eta:g}; "
        f"R = {spec.R * 1e3:g} mm, L = {spec.L * 1e3:g} mm, c = {c_um:.1f} um)",
        f"  grid              Nx = {spec.Nx}, Nz = {spec.Nz}: {s['n_states']} states",
        f"  speed             Omega_bar = {res.omega:.4g}  ({si['speed_rpm']:.0f} rpm)",
        f"  load per bearing  gravity {spec.bearing_weight:.3g} N + extra {w_n:.4g} N "
        f"(W/(p0 L D) = {res.w:.4g})",
        f"  outcome           {res.outcome}: {res.message}",
    ]
    if not res.converged:
        lines.append(f"                    (the state below carries {100 * res.load_fraction:.1f}% of the load)")
    lines += [
        f"  journal           x_j = {_fmt_um(res.x_j, c_um)},  y_j = {_fmt_um(res.y_j, c_um)}",
        f"  eccentricity      {res.eccentricity:.4f} c ({res.eccentricity * c_um:.2f} um), "
        f"attitude angle {res.attitude_deg:.2f} deg",
        f"  film              h_min = {res.h_min:.4f} c ({res.h_min * c_um:.2f} um),  "
        f"p_max = {s['p_max']:.4f} p0 ({si['p_max_Pa'] / 1e3:.1f} kPa),  q_max = {s['q_max']:.4f} c "
        f"({s['q_max'] * c_um:.2f} um)",
        f"  critical eigenvalue  {lam.real:.4g} {'+-' if lam.imag else '+'} {abs(lam.imag):.4g}i per tau  "
        f"({lam.real / ts:.4g} 1/s, {abs(lam.imag) / ts / (2 * math.pi):.1f} Hz): "
        + ({True: "STABLE", False: "UNSTABLE"}.get(res.stable, "no stability verdict (not an equilibrium)")),
        f"  Newton            residual {res.residual:.2e}, {res.iterations} iterations",
    ]
    return "\n".join(lines)


def _curve_record(alpha: float, omega: float, rs: list, spec: SystemSpec) -> dict[str, Any]:
    c_um = spec.c * 1e6
    return {
        "alpha_f": alpha, "omega_bar": omega, "speed_rpm": spec.rpm(omega),
        "ended_in_contact": bool(rs) and rs[-1].outcome == "contact",
        "points": [{
            "w_specific": r.w, "outcome": r.outcome, "load_fraction": r.load_fraction,
            "x_j": r.x_j, "y_j": r.y_j, "y_j_um": r.y_j * c_um, "eccentricity": r.eccentricity,
            "attitude_deg": r.attitude_deg, "h_min": r.h_min, "p_max": float(r.pressure.max()),
            "stable": r.stable, "critical_eigenvalue": [r.critical_eigenvalue.real, r.critical_eigenvalue.imag],
        } for r in rs],
    }


def compute_curves(spec: SystemSpec, alphas: list[float], speeds: list[float], loads: list[float],
                   progress: bool = True) -> dict[float, dict[float, list]]:
    """``{alpha_f: {omega: [StaticResult, ...]}}`` over the given compliances, speeds and increasing loads."""
    from tqdm.auto import tqdm

    from ...analyses.static import load_displacement

    curves: dict[float, dict[float, list]] = {}
    total = len(alphas) * len(speeds) * len(loads)
    with tqdm(total=total, desc="load-displacement", unit="eq", disable=not progress, file=sys.stderr,
              dynamic_ncols=True) as bar:
        for a in alphas:
            params = traced_params(spec.replace(alpha_f=a, load=0.0))  # curves: beyond gravity only
            curves[a] = {}
            for om in speeds:
                bar.set_postfix_str(f"alpha_f={a:g} Omega={om:g}")
                done = [0]

                def tick(k: int, n: int, done=done) -> None:
                    bar.update(k - done[0])
                    done[0] = k

                rs = load_displacement(params, om, loads, progress=tick)
                bar.update(len(loads) - done[0])  # the rest of a curve that ended in contact
                curves[a][om] = rs
    return curves


# -- the command ------------------------------------------------------------------------------------------------


def run(args: argparse.Namespace) -> int:
    import gfbjax

    from ...analyses.static import solve_equilibrium

    t_start = time.perf_counter()
    spec = spec_from_args(args)
    omega, w_opt, w = _operating_point(args, spec)
    if args.profile_speed is not None:
        check_range("--profile-speed", args.profile_speed, limits.SPEED)
    out = output_dir(args)
    params = traced_params(spec)

    res = solve_equilibrium(params, omega, w_opt)  # the system's own load is in params already
    t_eq = time.perf_counter() - t_start
    print(format_summary(res, spec, args.system), flush=True)

    figures: list[str] = []
    curves = None
    t_curves = None
    if args.curves:
        if spec.load:
            print(f"  note: the curves' loads are beyond gravity only; the system's load = {spec.load:g} N is not "
                  "added to them", flush=True)
        t0 = time.perf_counter()
        curves = compute_curves(spec, args.alphas, args.speeds, args.loads, progress=not args.quiet)
        t_curves = time.perf_counter() - t0
        n_eq = sum(len(rs) for d in curves.values() for rs in d.values())
        n_contact = sum(1 for d in curves.values() for rs in d.values() if rs and rs[-1].outcome == "contact")
        print(f"  curves            {len(args.alphas)} alpha_f x {len(args.speeds)} speeds: {n_eq} equilibria, "
              f"{n_contact} curve(s) ended in contact, {t_curves:.1f} s", flush=True)

    if not args.no_figures:
        import matplotlib.pyplot as plt

        from ...plot.static import plot_equilibrium_locus, plot_load_displacement, plot_static_summary

        fig = plot_static_summary(res, spec, path=out / "static_summary.png")
        plt.close(fig)
        figures.append("static_summary.png")
        if curves is not None:
            fig = plot_load_displacement(curves, spec=spec, path=out / "load_displacement.png",
                                         title=f"Load-displacement, system '{args.system}' (paper Fig. 4)")
            plt.close(fig)
            fig = plot_equilibrium_locus(curves, spec=spec, profile_speed=args.profile_speed,
                                         path=out / "equilibrium_locus.png")
            plt.close(fig)
            figures += ["load_displacement.png", "equilibrium_locus.png"]

    params_np = spec.nondim()
    data = {
        "command": NAME,
        "gfbjax_version": gfbjax.__version__,
        "system": {
            "name": args.system,
            "spec": spec.to_dict(),
            "nondim": {f.name: getattr(params_np, f.name) for f in dataclasses.fields(params_np)},
            "t_star_s": spec.t_star,
            "bearing_weight_N": spec.bearing_weight,
            "force_unit_p0LD_N": _force_unit(spec),
        },
        "operating_point": {"omega_bar": omega, "speed_rpm": spec.rpm(omega), "w_option": w_opt,
                            "w_specific": w, "extra_load_N": w * _force_unit(spec)},
        "equilibrium": res.summary(spec),
        "curves": None if curves is None else [
            _curve_record(a, om, rs, spec) for a, d in curves.items() for om, rs in d.items()],
        "figures": figures,
        "timing_s": {"equilibrium": t_eq, "curves": t_curves, "total": time.perf_counter() - t_start},
    }
    path = write_json(out / "static.json", data)
    written = ", ".join([path.name] + figures)
    print(f"  wrote             {out}/: {written}  ({data['timing_s']['total']:.1f} s)", flush=True)
    return 0 if res.converged else 1
