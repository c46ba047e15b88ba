"""Table 1 (the paper's validation case): Hopf speed of the balanced rigid rotor under the model variants.

The paper reports 12,030 rpm for 10 N per bearing (Zhou et al.: 11,475 rpm); gfbjax's default model gives
13,793 rpm on its default 48x8 grid.  Each variant below changes one modelling choice that the paper's Sect. 2.1
or its Table 1 leaves open (``gfbjax.SystemSpec`` options ``gumbel``, ``foil_springs``, ``axial_domain``; the
rotor mass of ``gfbjax.validation_case(..., mass_per_bearing=...)``), and the script locates the Hopf point of the
equilibria continued in speed (``gfbjax.analyses.cycles.continue_gfb_equilibria``), as
``benchmarks/validation_table1.py`` does.  Variants:

* ``baseline``: ``validation_case(load)``, rotor mass per bearing ``load / g``;
* ``gumbel=pressure``: the film pressure kept at or above ambient inside the Reynolds equation;
* ``foil_springs=no_first`` / ``no_last``: ``Nx - 2`` springs, the strip next to the fixed end held;
* ``springs spread``: ``Nx - 2`` springs' stiffness spread over the ``Nx - 1`` strips (``alpha_f`` times
  ``(Nx - 1) / (Nx - 2)``; no code option, an ``alpha_f`` override);
* ``axial_domain=full``: the whole bearing length, no symmetry condition;
* ``mass m kg``: the static load kept, applied as an external force on a rotor of ``m`` kg per bearing (the paper
  gives no rotor mass): a sensitivity sweep, and the masses that reproduce 12,030 and 11,475 rpm (Brent's method);
* ``weight 15 N, load 10 N``: Table 1's ``F_B,y = 15 N`` read as the rotor's weight and the text's 10 N as the
  static bearing load of the Hopf comparison;
* ``... + foil_damping=paper``: that reading with the paper's printed foil damping (the other change towards the
  paper).

Usage:
    python benchmarks/table1_variants.py                 # default grid 48x8; --loads 10 15: 3 min on 2 cores
    python benchmarks/table1_variants.py --quick         # grid 32x4; --loads 10 15: 1 min; writes *_quick.json
    python benchmarks/table1_variants.py --grid 24x3 --loads 10 15 --variants baseline gumbel=pressure

Writes benchmarks/results/table1_variants.json (``--quick``: table1_variants_quick.json): one record per row with
the variant, its description, the load, grid, Hopf Omega_bar, rpm, whirl ratio (whirl frequency / speed), the
differences to 12,030 rpm and to the baseline of the same load and grid, the run time and the full ``SystemSpec``.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any, Callable

import gfbjax
import numpy as np
from scipy.optimize import brentq

from gfbjax.analyses.cycles import continue_gfb_equilibria

RESULTS = Path(__file__).resolve().parent / "results"
PAPER_RPM = 12030.0  # the paper's Hopf speed, 10 N per bearing (Sect. 3.2, Fig. 6c)
ZHOU_RPM = 11475.0  # Zhou et al. as the paper reports it
G = 9.81
SPEED_RANGE = (0.25, 1.5)  # Omega_bar; holds the Hopf point of every variant and mass below (0.40 .. 0.82)
MASS_SWEEP = (0.5, 0.75, 1.25, 1.5, 2.0, 3.0)  # kg per bearing; the baseline is load / g = 1.019 kg at 10 N


def _variants(load: float, nx: int) -> list[tuple[str, str, dict[str, Any]]]:
    """(name, description, keyword arguments of gfbjax.validation_case) for one load and grid."""
    base = gfbjax.validation_case(load)
    rows = [
        ("baseline", "rotor weight = load, spring under every strip, Gumbel on forces, half length", {}),
        ("gumbel=pressure", "film pressure kept >= ambient inside the Reynolds equation", {"gumbel": "pressure"}),
        ("foil_springs=no_first", "Nx - 2 springs, first strip after the fixed end held", {"foil_springs": "no_first"}),
        ("foil_springs=no_last", "Nx - 2 springs, last strip before the fixed end held", {"foil_springs": "no_last"}),
        ("springs spread", "Nx - 2 springs' stiffness over Nx - 1 strips: alpha_f (Nx - 1)/(Nx - 2)",
         {"alpha_f": base.alpha_f * (nx - 1) / (nx - 2)}),
        ("axial_domain=full", "whole bearing length, ambient at both edges", {"axial_domain": "full"}),
    ]
    rows += [(f"mass {m:g} kg", f"static load {load:g} N as an external force, rotor {m:g} kg per bearing",
              {"mass_per_bearing": m}) for m in MASS_SWEEP]
    if load == 10.0:
        w15 = {"mass_per_bearing": 15.0 / G}
        rows += [("weight 15 N, load 10 N", "Table 1's 15 N as the rotor weight, the text's 10 N as the static load",
                  w15),
                 ("weight 15 N, load 10 N + foil_damping=paper", "the same with c_f = eta k_f as printed",
                  {**w15, "foil_damping": "paper"})]
    return rows


def hopf(spec: gfbjax.SystemSpec) -> dict[str, Any]:
    """The first Hopf point of the balanced rotor's equilibria in SPEED_RANGE (None values if there is none)."""
    t0 = time.perf_counter()
    b = continue_gfb_equilibria(spec.nondim(), *SPEED_RANGE, spec=spec)
    hp = b.special_of("HOPF")
    rec: dict[str, Any] = {"outcome": str(b.outcome), "seconds": round(time.perf_counter() - t0, 1),
                           "Omega_bar": None, "rpm": None, "whirl_ratio": None}
    if hp:
        lam = float(hp[0].lam)
        rec.update(Omega_bar=lam, rpm=spec.rpm(lam),
                   whirl_ratio=float(hp[0].omega) / lam if hp[0].omega else None)
    return rec


def matching_mass(load: float, grid: dict[str, int], target_rpm: float, bracket: tuple[float, float]
                  ) -> dict[str, Any]:
    """The rotor mass per bearing [kg] whose Hopf speed is ``target_rpm`` (Brent's method on ``bracket``)."""
    t0 = time.perf_counter()
    calls = []

    def f(m: float) -> float:
        r = hopf(gfbjax.validation_case(load, mass_per_bearing=m, **grid))
        calls.append(r["rpm"])
        return r["rpm"] - target_rpm

    m = brentq(f, *bracket, xtol=1e-4)
    return {"target_rpm": target_rpm, "mass_per_bearing_kg": m, "rotor_mass_kg": 2 * m,
            "mass_over_baseline": m / (load / G), "evaluations": len(calls),
            "seconds": round(time.perf_counter() - t0, 1)}


def run(loads: list[float], grid: dict[str, int], names: list[str] | None, match: bool,
        echo: Callable[[str], None] = print) -> dict[str, Any]:
    rows, matches = [], []
    gname = f"{grid['Nx']}x{grid['Nz']}"
    for load in loads:
        baseline = None
        for name, what, kw in _variants(load, grid["Nx"]):
            if names and name not in names and name != "baseline":
                continue
            spec = gfbjax.validation_case(load, **grid, **kw)
            rec = {"variant": name, "description": what, "load_N": load, "grid": gname, **hopf(spec),
                   "spec": spec.to_dict()}
            if name == "baseline":
                baseline = rec["rpm"]
            rpm = rec["rpm"]
            rec["vs_paper_pct"] = 100 * (rpm / PAPER_RPM - 1) if (rpm and load == 10.0) else None
            rec["vs_baseline_rpm"] = rpm - baseline if (rpm and baseline) else None
            rows.append(rec)
            echo(_line(rec))
        if match and load == 10.0:
            for target in (PAPER_RPM, ZHOU_RPM):
                r = matching_mass(load, grid, target, (1.0, 2.5))
                r.update(load_N=load, grid=gname)
                matches.append(r)
                echo(f"  rotor mass per bearing for {target:,.0f} rpm at {load:g} N, {gname}: "
                     f"{r['mass_per_bearing_kg']:.3f} kg ({r['mass_over_baseline']:.3f} x load/g; "
                     f"{r['evaluations']} continuations, {r['seconds']:.0f} s)")
    return {"rows": rows, "matching_mass": matches}


def _line(r: dict[str, Any]) -> str:
    rpm = "no Hopf" if r["rpm"] is None else f"{r['rpm']:>9,.0f}"
    vp = "" if r["vs_paper_pct"] is None else f"{r['vs_paper_pct']:+6.1f} %"
    vb = "" if r["vs_baseline_rpm"] is None else f"{round(r['vs_baseline_rpm']) or 0:+7d} rpm"  # no "-0"
    return f"{r['variant']:<44} {r['load_N']:>4g} N {r['grid']:>5} {rpm} {vp:>9} {vb:>12}  ({r['seconds']:.0f} s)"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="grid 32x4 (about a minute for both loads)")
    ap.add_argument("--grid", default=None, help="NXxNZ, e.g. 48x8 (default: 48x8, or 32x4 with --quick)")
    ap.add_argument("--loads", type=float, nargs="+", default=[10.0], help="N per bearing (default 10)")
    ap.add_argument("--variants", nargs="+", default=None,
                    help="variant names to run (the baseline always runs); default: all")
    ap.add_argument("--no-match", action="store_true", help="skip the search for the masses that match 12,030 and "
                                                           "11,475 rpm")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    gtext = a.grid or ("32x4" if a.quick else "48x8")
    nx, nz = (int(v) for v in gtext.lower().split("x"))
    grid = {"Nx": nx, "Nz": nz}
    out = Path(a.out) if a.out else RESULTS / ("table1_variants_quick.json" if a.quick else "table1_variants.json")
    print(f"{'variant':<44} {'load':>6} {'grid':>5} {'Hopf rpm':>9} {'vs 12,030':>9} {'vs baseline':>12}")
    t0 = time.perf_counter()
    res = run(a.loads, grid, a.variants, not a.no_match)
    res.update(paper_rpm=PAPER_RPM, zhou_rpm=ZHOU_RPM, speed_range_omega_bar=list(SPEED_RANGE),
               seconds=round(time.perf_counter() - t0, 1), gfbjax_version=gfbjax.__version__,
               command="python benchmarks/table1_variants.py " + " ".join(
                   f"--{k.replace('_', '-')} {' '.join(map(str, v)) if isinstance(v, list) else v}"
                   for k, v in vars(a).items() if v not in (None, False)).replace(" True", ""))
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(res, indent=1, default=lambda v: float(v) if isinstance(v, np.floating) else str(v)))
    print(f"wrote {out} ({res['seconds']:.0f} s)")


if __name__ == "__main__":
    main()
