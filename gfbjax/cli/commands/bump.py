"""``gfbjax bump``: bump-foil geometry <-> dimensionless compliance alpha_f, both ways (Heshmat's bump formula,
:mod:`gfbjax.model.bump`), with the system's ambient pressure p0 and clearance c."""

from __future__ import annotations

import argparse
import time
from typing import Any

from ... import limits
from ...params import ParameterError
from ._common import add_system_options, output_dir, spec_from_args, write_json

NAME = "bump"

DESCRIPTION = """\
Bump-foil compliance alpha_f = 2 p0 (l0/t_b)^3 (1 - nu^2) s0 / (c E) from the bump geometry, or, with --alpha-f,
the one geometric quantity (--solve-for: foil thickness t_b, bump half length l0, bump pitch s0 or Young's modulus
E) that gives that compliance with the others.  p0 and c are the system's (--system, --set).  The compliance per
area in SI, alpha_f c / p0 [m/Pa], and the foil stiffness per area k_f = p0 / (alpha_f c) [N/m^3] are reported too.

Writes to --out: bump.json (the geometry, alpha_f, k_f and the system's p0 and c).
Exit status: 0 on success, 2 for invalid input (a result that is no bump foil names the quantity and its range).
"""

EPILOG = """\
units: lengths in m, E in Pa (SI throughout; e.g. 1.5e-3 for 1.5 mm).

examples:
  gfbjax bump --l0 1.5e-3 --t-b 1e-4 --s0 4.5e-3                   alpha_f of this geometry (Inconel X-750 default)
  gfbjax bump --alpha-f 0.1 --solve-for t_b --l0 1.5e-3 --s0 4.5e-3  the foil thickness that gives alpha_f = 0.1
"""

# a typical bump foil of Inconel X-750 (Heshmat's generation I foils)
DEFAULT_E = 214e9
DEFAULT_NU = 0.29
QUANTITIES = ("t_b", "l0", "s0", "E")


def register(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser(NAME, help="bump-foil geometry <-> compliance alpha_f (both ways)",
                              description=DESCRIPTION, epilog=EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    add_system_options(p, NAME)
    g = p.add_argument_group("bump foil (SI)")
    g.add_argument("--alpha-f", type=float, default=None, metavar="ALPHA_F",
                   help=f"target compliance, in {limits.ALPHA_F.interval()}: solve for --solve-for")
    g.add_argument("--solve-for", choices=QUANTITIES, default="t_b",
                   help="quantity to solve for with --alpha-f (default %(default)s)")
    g.add_argument("--l0", type=float, default=None, metavar="M", help="bump half length [m]")
    g.add_argument("--t-b", dest="t_b", type=float, default=None, metavar="M", help="foil thickness [m]")
    g.add_argument("--s0", type=float, default=None, metavar="M", help="bump pitch [m]")
    g.add_argument("--E", type=float, default=None, metavar="PA",
                   help=f"Young's modulus of the foil [Pa] (default {DEFAULT_E:g}, Inconel X-750)")
    g.add_argument("--poisson", type=float, default=DEFAULT_NU, metavar="NU",
                   help=f"Poisson's ratio, in {limits.POISSON.interval()} (default %(default)s)")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from ...model.bump import bump_foil_compliance, bump_parameter_for_compliance

    t0 = time.perf_counter()
    spec = spec_from_args(args)
    geo = {"l0": args.l0, "t_b": args.t_b, "s0": args.s0, "E": args.E}
    if args.alpha_f is None:
        if geo["E"] is None:
            geo["E"] = DEFAULT_E
        missing = [f"--{k.replace('_', '-')}" for k, v in geo.items() if v is None]
        if missing:
            raise ParameterError(f"{', '.join(missing)}: give the whole geometry (--l0, --t-b, --s0) or --alpha-f "
                                 "with all but the --solve-for quantity")
        alpha = bump_foil_compliance(geo["l0"], geo["t_b"], geo["s0"], geo["E"], args.poisson, spec.p0, spec.c)
        solved = "alpha_f"
    else:
        if args.solve_for != "E" and geo["E"] is None:
            geo["E"] = DEFAULT_E
        if geo[args.solve_for] is not None:
            raise ParameterError(f"--{args.solve_for.replace('_', '-')}: it is the quantity solved for "
                                 f"(--solve-for {args.solve_for}); leave it out")
        known = {k: v for k, v in geo.items() if k != args.solve_for}
        geo[args.solve_for] = bump_parameter_for_compliance(args.alpha_f, args.solve_for, nu=args.poisson,
                                                            p0=spec.p0, c=spec.c, **known)
        alpha = args.alpha_f
        solved = args.solve_for
    out = output_dir(args)
    k_f = spec.p0 / (alpha * spec.c)
    print("\n".join([
        f"gfbjax bump: system '{args.system}' (p0 = {spec.p0:g} Pa, c = {spec.c * 1e6:.2f} um); solved for {solved}",
        f"  geometry          l0 = {geo['l0'] * 1e3:.4g} mm, t_b = {geo['t_b'] * 1e6:.4g} um, "
        f"s0 = {geo['s0'] * 1e3:.4g} mm, E = {geo['E'] / 1e9:.4g} GPa, nu = {args.poisson:g}",
        f"  compliance        alpha_f = {alpha:.6g} ({alpha * spec.c / spec.p0:.4g} m/Pa per area); "
        f"k_f = {k_f:.4g} N/m^3",
    ]), flush=True)
    data = {"command": NAME, "system": {"name": args.system, "p0_Pa": spec.p0, "c_m": spec.c},
            "solved_for": solved, "alpha_f": alpha, "compliance_m_per_Pa": alpha * spec.c / spec.p0,
            "k_f_N_per_m3": k_f, "geometry": {"l0_m": geo["l0"], "t_b_m": geo["t_b"], "s0_m": geo["s0"],
                                             "E_Pa": geo["E"], "poisson": args.poisson},
            "timings_s": {"total": time.perf_counter() - t0}}
    write_json(out / "bump.json", data)
    print(f"  wrote             {out}/bump.json", flush=True)
    return 0
