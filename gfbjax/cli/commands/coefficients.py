"""``gfbjax coefficients``: linearised stiffness and damping of one gas foil bearing (film plus foil) against speed,
dimensionless and SI, for synchronous whirl or a given whirl ratio (:mod:`gfbjax.analyses.coefficients`)."""

from __future__ import annotations

import argparse
import csv
import time
from typing import Any

import numpy as np

from ...params import ParameterError
from ._common import (add_speed_option, add_system_options, check_option, output_dir, resolve_speeds, spec_from_args,
                      traced_params, write_json)

NAME = "coefficients"

DESCRIPTION = """\
Linearised dynamic coefficients of one gas foil bearing at the static equilibrium of the balanced rotor (gravity
and the system's load), against speed: the 2 x 2 stiffness K and damping C of the bearing force F = -K x - C x',
from the model's Jacobian with the film and foil states condensed at the whirl frequency nu = --whirl-ratio x
running speed (1: synchronous; a gas film's coefficients depend on the whirl frequency).

Writes to --out: coefficients.json (per speed Omega_bar, rpm, kxx, kxy, kyx, kyy, cxx, ... dimensionless and in
N/m, N s/m; the journal position), coefficients.csv (SI, one row per speed: the table a rotordynamics code reads)
and coefficients.png.  Exit status: 0 on success, 1 when a speed has no equilibrium with an open film, 2 for
invalid input.
"""

EPILOG = """\
units: speeds in Omega_bar = Omega t* (or rpm with the -rpm options); K in p0 R L / c and N/m, C in p0 R L t* / c
and N s/m; x horizontal, y vertical up, K[i][j] = -dF_i/dx_j (ROSS's convention).

examples:
  gfbjax coefficients                                      reference system, 12 speeds, synchronous
  gfbjax coefficients --start-rpm 5000 --end-rpm 30000 --points 26 --nx 32 --nz 4
  gfbjax coefficients --system G0 --whirl-ratio 0.45       at the whirl ratio of the Hopf point
"""


def register(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser(NAME, help="bearing stiffness and damping vs speed (dimensionless and SI)",
                              description=DESCRIPTION, epilog=EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    add_system_options(p, NAME)
    r = p.add_argument_group("speeds")
    add_speed_option(r, "--start", default=0.1, help="first speed in Omega_bar (default 0.1)")
    add_speed_option(r, "--end", default=1.0, help="last speed in Omega_bar (default 1.0)")
    r.add_argument("--points", type=int, default=12, metavar="P", help="speeds, evenly spaced (default 12)")
    r.add_argument("--whirl-ratio", type=float, default=1.0, metavar="R",
                   help="whirl frequency over running speed, in (0, 10] (default 1: synchronous)")
    o = p.add_argument_group("output")
    o.add_argument("--no-figures", action="store_true", help="no PNG figure")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    import gfbjax

    from ...analyses.coefficients import WHIRL_RATIO, bearing_coefficients
    from ...limits import NoSolutionError

    t0 = time.perf_counter()
    spec = spec_from_args(args)
    resolve_speeds(args, spec, "--start", "--end")
    check_option("--points", args.points, 1, 10**4, what="speeds", integer=True)
    if args.points > 1 and args.start == args.end:  # the same speed computed --points times
        raise ParameterError(f"--end must differ from --start = {args.start:g} for --points {args.points} "
                             "(one speed: --points 1)")
    WHIRL_RATIO.check(args.whirl_ratio, "--whirl-ratio")
    out = output_dir(args)
    params = traced_params(spec)
    omegas = np.linspace(args.start, args.end, args.points)
    print(f"gfbjax coefficients: system '{args.system}', grid Nx={spec.Nx} Nz={spec.Nz}, Omega_bar {args.start:g} "
          f"-> {args.end:g} ({spec.rpm(args.start):.0f} -> {spec.rpm(args.end):.0f} rpm), {args.points} speeds, "
          f"whirl ratio {args.whirl_ratio:g}", flush=True)
    try:
        co = bearing_coefficients(params, omegas, args.whirl_ratio)
    except NoSolutionError as exc:
        print(f"gfbjax coefficients: {exc}", flush=True)
        return 1
    si = co.si(spec)
    header = ["Omega_bar", "rpm", "whirl_Hz", "kxx_N_per_m", "kxy_N_per_m", "kyx_N_per_m", "kyy_N_per_m",
              "cxx_Ns_per_m", "cxy_Ns_per_m", "cyx_Ns_per_m", "cyy_Ns_per_m", "x_j_um", "y_j_um"]
    with (out / "coefficients.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for k in range(len(co)):
            K, C = si["K_N_per_m"][k], si["C_Ns_per_m"][k]
            w.writerow([co.omega[k], si["speed_rpm"][k], si["whirl_Hz"][k], K[0, 0], K[0, 1], K[1, 0], K[1, 1],
                        C[0, 0], C[0, 1], C[1, 0], C[1, 1], si["x_j_um"][k], si["y_j_um"][k]])
    lines = [f"    {'rpm':>8} {'kxx':>10} {'kxy':>10} {'kyx':>10} {'kyy':>10} {'cxx':>9} {'cxy':>9} {'cyx':>9} "
             f"{'cyy':>9}   [N/m, N s/m]"]
    for k in range(len(co)):
        K, C = si["K_N_per_m"][k], si["C_Ns_per_m"][k]
        lines.append(f"    {si['speed_rpm'][k]:>8.0f} " + " ".join(f"{v:>10.4g}" for v in K.ravel()) + " "
                     + " ".join(f"{v:>9.4g}" for v in C.ravel()))
    print("\n".join(lines), flush=True)
    figures = []
    if not args.no_figures:
        import matplotlib.pyplot as plt

        from ...plot.coefficients import plot_coefficients

        fig = plot_coefficients(co, spec=spec, path=out / "coefficients.png",
                                title=f"Bearing coefficients, system '{args.system}' (Nx={spec.Nx}, Nz={spec.Nz}, "
                                      f"whirl ratio {args.whirl_ratio:g})")
        plt.close(fig)
        figures.append("coefficients.png")
    data = {"command": NAME, "gfbjax_version": gfbjax.__version__,
            "system": {"name": args.system, "spec": spec.to_dict(), "t_star_s": spec.t_star,
                       "force_scale_N": spec.force_scale, "c_m": spec.c},
            "range": {"start": args.start, "end": args.end, "points": args.points,
                      "start_rpm": spec.rpm(args.start), "end_rpm": spec.rpm(args.end)},
            "coefficients": co.to_dict(spec),
            "files": ["coefficients.json", "coefficients.csv"] + figures,
            "timings_s": {"total": time.perf_counter() - t0}}
    write_json(out / "coefficients.json", data)
    print(f"  wrote             {out}/: " + ", ".join(data["files"]) + f"  ({data['timings_s']['total']:.1f} s)",
          flush=True)
    return 0

