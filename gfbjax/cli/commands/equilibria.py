"""``gfbjax equilibria``: continuation of the static equilibria of the balanced rotor in the speed Omega_bar, with
the eigenvalues of the Jacobian and the Hopf (onset of self-excited whirl) and fold points (paper Sect. 3.1)."""

from __future__ import annotations

import argparse
import math
import time
from ...limits import NoSolutionError
from typing import Any

from ...params import ParameterError
from ._checkpoints import add_checkpoint_options, interrupted_status, prepare_run
from ._contact import add_contact_options, contact_kwargs, contact_line, contact_summary
from ._common import (add_speed_option, add_system_options, branch_row_um, check_continuation_options, check_option,
                      speed_si, write_summary)

NAME = "equilibria"

DESCRIPTION = """\
Continuation of the static equilibrium of the balanced rotor (no unbalance) over a speed range by
pseudo-arclength steps, with the eigenvalues of the Jacobian at every point; Hopf points (a complex pair crossing
the imaginary axis: onset of the self-excited sub-synchronous whirl, where the self-excited cycles start) and
folds are detected and located (unless --no-locate).

Writes to --out: branch.npz + branch.json (gfbjax.cont.Branch.load; plain numpy + json; the JSON records the
system spec, grid, units and rpm conversion), equilibria.json
(the Hopf/fold points: Omega_bar, rpm, the Hopf frequency omega per tau and in Hz and the whirl ratio
omega/Omega_bar; why the branch ended; timings) and equilibria.png (journal position and the real part of the
critical eigenvalue against speed).
Exit status: 0 when the branch reached --end, 1 when it ended early, 2 for invalid input, 130 when interrupted
(continue with --resume).
"""

EPILOG = """\
units: speeds are dimensionless, Omega_bar = Omega t* (the bearing number); eigenvalues per tau = t/t*;
positions over the clearance c.

examples:
  gfbjax equilibria                               reference system, Omega_bar 0.05 -> 1.0
  gfbjax equilibria --nx 24 --nz 3 --start 0.1 --end 2
"""

_FIELDS = {"ds": "--ds", "ds_max": "--ds-max", "max_points": "--max-points", "lam_min": "--start",
           "lam_max": "--end", "ds_min": "--ds"}


def register(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser(NAME, help="equilibria of the balanced rotor vs speed: eigenvalues, Hopf/fold points",
                              description=DESCRIPTION, epilog=EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    add_system_options(p, NAME)
    r = p.add_argument_group("speed range")
    add_speed_option(r, "--start", default=0.05, help="start speed in Omega_bar (default 0.05)")
    add_speed_option(r, "--end", default=1.0,
                     help="end speed in Omega_bar (default 1.0); below --start the branch runs down in speed")
    n = p.add_argument_group("numerics")
    n.add_argument("--ds", type=float, default=0.05, help="initial arclength step (default 0.05)")
    n.add_argument("--ds-max", type=float, default=0.5, help="largest arclength step (default 0.5)")
    n.add_argument("--max-points", type=int, default=200, metavar="P", help="most points (default 200)")
    n.add_argument("--no-locate", action="store_true", help="do not locate the Hopf/fold points")
    n.add_argument("--hopf-cycles", type=int, default=0, metavar="P",
                   help="also continue the self-excited cycles born at the first Hopf point, P points (default 0: "
                        "off); tells super- from subcritical and gives the whirl amplitude (paper Table 1)")
    o = p.add_argument_group("output")
    o.add_argument("--no-figures", action="store_true", help="no PNG figure")
    o.add_argument("--quiet", action="store_true", help="no progress output")
    add_contact_options(p)
    add_checkpoint_options(p)
    p.set_defaults(func=run)
    return p


def _settings(args: argparse.Namespace):
    from ...cont import EquilibriumSettings

    check_continuation_options(args)
    check_option("--hopf-cycles", args.hopf_cycles, 0, 10**5, what="points")
    try:
        return EquilibriumSettings(ds=args.ds, ds_max=args.ds_max, max_points=args.max_points,
                                   locate=not args.no_locate)
    except ValueError as exc:
        msg = str(exc)
        opt = _FIELDS.get(msg.split()[0] if msg else "", "numerics")
        raise ParameterError(f"{opt}: {msg}") from None


def special_summary(branch: Any, spec: Any) -> list[dict[str, Any]]:
    import numpy as np

    out = []
    for s in branch.special:
        lam = float(s.lam)
        d: dict[str, Any] = {"type": s.type, "Omega_bar": lam, "rpm": spec.rpm(lam), "located": bool(s.located),
                             "localisation": s.localisation,
                             "residual": None if math.isnan(s.residual) else s.residual, "index": s.index,
                             "Omega_bar_error": None if math.isnan(s.lam_error) else s.lam_error}
        ev = np.asarray(s.spectrum, complex)
        d["max_real_part"] = float(ev.real.max()) if ev.size else None
        if s.type == "HOPF" and s.omega is not None:
            w = float(s.omega)
            d["omega_per_tau"] = w
            d["frequency_hz"] = w / spec.t_star / (2 * math.pi)
            d["whirl_ratio"] = w / lam
            d["running_frequency_hz"] = lam / spec.t_star / (2 * math.pi)
        si = speed_si(spec, lam)
        if d["max_real_part"] is not None:
            si["max_real_part_per_s"] = d["max_real_part"] / spec.t_star
        d["SI"] = {**si, **branch_row_um(branch, s.index, spec)}
        out.append(d)
    return out


def run(args: argparse.Namespace) -> int:
    import numpy as np

    import gfbjax

    from ...analyses.cycles import continue_gfb_equilibria

    from .cycles import reached_end

    t0 = time.perf_counter()
    args, spec, settings, out, params, contact, ck = prepare_run(args, NAME, _settings)
    print(f"gfbjax equilibria: system '{args.system}', grid Nx={spec.Nx} Nz={spec.Nz}, Omega_bar {args.start:g} -> "
          f"{args.end:g}", flush=True)

    def cb(i, rec):
        if not args.quiet and (i % 10 == 0):
            print(f"  point {i + 1:4d}  Omega_bar = {float(rec.lam):.4f}  "
                  f"max Re lambda = {float(np.max(np.asarray(rec.multipliers).real)):+.3e}", flush=True)
        return None

    t1 = time.perf_counter()
    try:
        branch = continue_gfb_equilibria(params, args.start, args.end, settings, callback=cb, spec=spec,
                                         checkpoint=ck, **contact)
    except NoSolutionError as exc:
        print(f"gfbjax equilibria: {exc}", flush=True)
        return 1
    t_cont = time.perf_counter() - t1
    branch.save(out / "branch")
    ok = reached_end(branch, args.start, args.end)
    rows = special_summary(branch, spec)
    n_stable = int(np.sum(branch.stable))
    lines = [
        f"  branch            {len(branch)} points ({n_stable} stable), Omega_bar "
        f"{float(branch.lam[0]) if len(branch) else math.nan:.4f} -> "
        f"{float(branch.lam[-1]) if len(branch) else math.nan:.4f}",
        f"  ended             {branch.outcome}: {branch.message}" + ("" if ok else "  (before the end of the range)"),
        f"  time              continuation {t_cont:.1f} s",
    ]
    if len(branch) and branch.monitor is not None:
        lines.append(contact_line(branch, spec))
    if not rows:
        lines.append("  special points    none")
    for d in rows:
        extra = ""
        if "omega_per_tau" in d:
            extra = (f", omega = {d['omega_per_tau']:.4f} per tau ({d['frequency_hz']:.1f} Hz), "
                     f"whirl ratio omega/Omega_bar = {d['whirl_ratio']:.3f}")
        err = d.get("Omega_bar_error")
        pm = "" if err is None else f" +- {err:.1e}"
        # a bracketed jump is placed as precisely as a zero, but it is no zero crossing: say which it is
        where = {"located": f"located, test function {d['residual'] or 0.0:.1e}; Omega_bar{pm}",
                 "bracketed": f"bracketed, NOT located: the test function jumps there (by {d['residual'] or 0.0:.1e}), "
                              f"no zero crossing; the jump lies within Omega_bar{pm}",
                 "not localised": f"not localised: reported at the first point past it; the event lies within "
                                  f"Omega_bar{pm}"}[d["localisation"]]
        lines.append(f"  {d['type']:<17} Omega_bar = {d['Omega_bar']:.5f} ({d['rpm']:.0f} rpm){extra}  [{where}]")
    print("\n".join(lines), flush=True)

    hopf = None
    first_hopf = branch.special_of("HOPF")[:1]
    if args.hopf_cycles and first_hopf and not first_hopf[0].located:
        print("  Hopf cycles       skipped: the first Hopf point was not located (its state is no Hopf point)",
              flush=True)
    elif args.hopf_cycles and first_hopf:
        hopf = _hopf_cycles(args, params, spec, branch, out)

    figures: list[str] = []
    if hopf is not None and not args.no_figures:
        figures.append("hopf_cycles.png")
    if not args.no_figures and len(branch):
        import matplotlib.pyplot as plt

        from ...plot.branch import plot_equilibria

        fig = plot_equilibria(branch, spec=spec, title=f"Equilibria of the balanced rotor, system '{args.system}'",
                              path=out / "equilibria.png")
        plt.close(fig)
        figures.append("equilibria.png")

    data = {
        "command": NAME, "gfbjax_version": gfbjax.__version__,
        "system": {"name": args.system, "spec": spec.to_dict(), "t_star_s": spec.t_star},
        "range": {"start": args.start, "end": args.end, "reached_end": ok,
                  "start_rpm": spec.rpm(args.start), "end_rpm": spec.rpm(args.end)},
        "outcome": str(branch.outcome), "message": branch.message,
        "counts": {"points": len(branch), "stable": n_stable, "HOPF": sum(d["type"] == "HOPF" for d in rows),
                   "FOLD": sum(d["type"] == "FOLD" for d in rows)},
        "special": rows,
        "film": contact_summary(branch, spec),
        "hopf_cycles": hopf,
        "files": ["branch.npz", "branch.json", "equilibria.json"] + (["hopf_cycles.npz", "hopf_cycles.json"]
                                                                     if hopf else []) + figures,
        "timings_s": {"setup": t1 - t0, "continuation": t_cont, "total": time.perf_counter() - t0},
    }
    write_summary(out, "equilibria.json", data)
    return interrupted_status(branch, ok, out, ck, NAME)


def _hopf_cycles(args: argparse.Namespace, params: Any, spec: Any, branch: Any, out: Any) -> dict:
    """Self-excited cycles from the first Hopf point: branch file, figure and a summary (criticality, amplitude)."""
    import numpy as np

    from ...analyses.cycles import continue_gfb_hopf_cycles, default_cycle_settings, hopf_criticality

    lo, hi = sorted((args.start, args.end))
    s = default_cycle_settings(ds=0.02, ds_max=2.0, dlam_max=0.005, max_points=args.hopf_cycles, lam_min=lo,
                               lam_max=hi)
    t0 = time.perf_counter()
    cyc = continue_gfb_hopf_cycles(params, branch, 0, s, progress=not args.quiet, spec=spec,
                                   **contact_kwargs(args, spec))
    cyc.save(out / "hopf_cycles")
    lam_h = float(branch.special_of("HOPF")[0].lam)
    amp = (cyc.xmax - cyc.xmin)[:, :2] / 2 if len(cyc) else np.zeros((0, 2))
    crit = hopf_criticality(cyc, lam_h)
    past = [i for i in range(len(cyc)) if cyc.stable[i] and cyc.lam[i] > lam_h]
    first_past = None
    if past:
        i = past[0]
        first_past = {"Omega_bar": float(cyc.lam[i]), "rpm": spec.rpm(float(cyc.lam[i])),
                      "amplitude_xj_c": float(amp[i, 0]), "amplitude_yj_c": float(amp[i, 1]),
                      "amplitude_xj_um": float(amp[i, 0]) * spec.c * 1e6,
                      "amplitude_yj_um": float(amp[i, 1]) * spec.c * 1e6,
                      "whirl_frequency_Hz": 1.0 / (float(cyc.period[i]) * spec.t_star)}
    summary = {"criticality": crit, "points": len(cyc), "outcome": str(cyc.outcome), "message": cyc.message,
               "special": [{"type": sp.type, "Omega_bar": sp.lam, "rpm": spec.rpm(sp.lam), "located": sp.located}
                           for sp in cyc.special],
               "first_stable_cycle_past_hopf": first_past, "seconds": time.perf_counter() - t0}
    line = f"  Hopf cycles       {crit}, {len(cyc)} points ({cyc.outcome}: {cyc.message})"
    if first_past:
        line += (f"; first stable cycle past the Hopf speed at {first_past['rpm']:.0f} rpm: amplitude "
                 f"x {first_past['amplitude_xj_c']:.3g} c, y {first_past['amplitude_yj_c']:.3g} c")
    print(line, flush=True)
    if not args.no_figures and len(cyc):
        import matplotlib.pyplot as plt

        from ...plot.branch import plot_bifurcation

        fig = plot_bifurcation(cyc, spec=spec, title=f"Self-excited cycles from the Hopf point, system '{args.system}'",
                               path=out / "hopf_cycles.png")
        plt.close(fig)
    return summary
