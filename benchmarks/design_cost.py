"""Design cost (issue 15, item 3): cycle solves for a whole optimised foil schedule, the paper's pattern search at
every speed against the gradient method without and with the predictor.

One design case (the reference system with G2.5 and the smoothed Gumbel condition, as in
benchmarks/optimized_continuation.py), one grid, one speed schedule; the same march
(:func:`gfbjax.design.schedule.optimized_continuation`, objective max|mu| by default) three ways:

* ``pattern`` — the paper's generalized pattern search (App. A2: mesh 1, mesh tolerance 1e-6) at every speed,
  from the previous optimum and cycle;
* ``gradient`` — the projected L-BFGS with implicit gradients, from the previous optimum and cycle, to its
  first-order test (``predict=False``: the method before issue 15);
* ``predictor`` — ``predict=True`` (the default for the gradient method): each speed starts from the optimum
  and cycle extrapolated from the last optima (secant in log variables, a variable on a bound stays there) and is
  corrected by a projected BFGS that carries its curvature model from speed to speed, stops once the model or
  the last step leaves less than 1e-4 |f| to gain, and checks each stop with one long exploratory step.  The
  first speed has nothing to extrapolate from: it runs the L-BFGS of ``gradient`` with the relative stopping
  rule.

All three start the first speed from the reference foil (alpha_f 0.1, eta 0.05).  A gradient evaluation is one
cycle solve plus the implicit derivatives (counted as one solve and one gradient); failed solves count.  The
kernels are compiled before the first timed schedule.  Per speed the objective of each method is compared
with the pattern search's and with the best of the three (the pattern search can itself stop short on a kink
or in another local minimum); "same optimum" means within 0.5% (issue 15).  The solve ratio is pattern /
method over the speeds all three reached.

Usage:  python benchmarks/design_cost.py [--nx 24 --nz 3] [--start 0.1 --end 0.6 --step 0.05]
                                         [--objective max_mu] [--methods pattern gradient predictor]
        python benchmarks/design_cost.py --quick     # 16x2, Omega_bar 0.3-0.5, ~3 min on 2 cores
Writes benchmarks/results/design_cost.json (design_cost_quick.json with --quick).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import gfbjax
import jax
import numpy as np

from gfbjax.design.evaluate import FoilDesign
from gfbjax.design.schedule import optimized_continuation

RESULTS = Path(__file__).resolve().parent / "results"
METHODS = {"pattern": dict(method="pattern"), "gradient": dict(method="gradient", predict=False),
           "predictor": dict(method="gradient", predict=True)}
SAME = 5e-3  # "the same optimum": within 0.5% of the objective


def worse_by(v: float, ref: float, objective: str) -> float:
    """Relative shortfall of ``v`` against ``ref`` (> 0: worse; max_mu is minimised, W_cb maximised)."""
    return ((v - ref) if objective == "max_mu" else (ref - v)) / abs(ref)


def run(params, a: argparse.Namespace, name: str) -> dict:
    t0 = time.perf_counter()
    s = optimized_continuation(params, a.start, a.end, a.step, objective=a.objective, **METHODS[name])
    wall = time.perf_counter() - t0
    values = s.max_mu if a.objective == "max_mu" else s.W_cb
    print(f"{name:>9}: {s.n_solves} solves, {s.n_gradients} gradients, {wall:.1f} s; per speed "
          f"{s.n_solves_per_speed}; {s.outcome}: {s.message}", flush=True)
    return {"method": name, "Omega_bar": s.omega, "alpha_f": s.alpha_f, "eta": s.eta, "value": list(values),
            "stable": s.stable, "solves_per_speed": s.n_solves_per_speed, "stop_reasons": s.stop_reasons,
            "n_solves": s.n_solves, "n_gradients": s.n_gradients, "seconds": round(wall, 2),
            "outcome": str(s.outcome), "message": s.message}


def compare(runs: dict[str, dict], objective: str) -> dict:
    """Per speed reached by every method: values, shortfalls against the pattern search and the best; totals."""
    common = sorted(set.intersection(*(set(np.round(r["Omega_bar"], 9)) for r in runs.values())))
    at = {m: {round(w, 9): i for i, w in enumerate(r["Omega_bar"])} for m, r in runs.items()}
    rows = []
    for w in common:
        vals = {m: runs[m]["value"][at[m][w]] for m in runs}
        best = min(vals.values()) if objective == "max_mu" else max(vals.values())
        row = {"Omega_bar": w, "best": best}
        for m in runs:
            i = at[m][w]
            row[m] = {"value": vals[m], "alpha_f": runs[m]["alpha_f"][i], "eta": runs[m]["eta"][i],
                      "solves": runs[m]["solves_per_speed"][i], "reason": runs[m]["stop_reasons"][i],
                      "vs_best": worse_by(vals[m], best, objective)}
            if "pattern" in runs:
                row[m]["vs_pattern"] = worse_by(vals[m], vals["pattern"], objective)
        rows.append(row)
    totals = {}
    for m, r in runs.items():
        n = sum(r["solves_per_speed"][at[m][w]] for w in common)
        totals[m] = {"solves_common": n, "first_speed_solves": r["solves_per_speed"][0] if r["solves_per_speed"]
                     else None, "later_solves_per_speed": (n - r["solves_per_speed"][0]) / max(len(common) - 1, 1),
                     "max_shortfall_vs_best": max((row[m]["vs_best"] for row in rows), default=None),
                     "same_optima_as_best": all(row[m]["vs_best"] <= SAME for row in rows)}
        if "pattern" in runs:
            totals[m]["max_shortfall_vs_pattern"] = max((row[m]["vs_pattern"] for row in rows), default=None)
            totals[m]["same_optima_as_pattern"] = all(row[m]["vs_pattern"] <= SAME for row in rows)
    if "pattern" in runs:
        for m in runs:
            totals[m]["solve_ratio_pattern_over_method"] = totals["pattern"]["solves_common"] / \
                totals[m]["solves_common"]
            totals[m]["time_ratio_pattern_over_method"] = runs["pattern"]["seconds"] / runs[m]["seconds"]
    return {"common_speeds": common, "rows": rows, "totals": totals}


def table(runs: dict[str, dict], cmp: dict) -> str:
    f = (lambda v, fmt: "-" if v is None else format(v, fmt))
    out = ["| method | speeds | cycle solves (all / common speeds) | gradients | wall s | first speed | "
           "later, per speed | pattern / method (solves) | (time) | worst vs pattern | worst vs best |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for m, r in runs.items():
        t = cmp["totals"][m]
        out.append(f"| {m} | {len(r['Omega_bar'])} | {r['n_solves']} / {t['solves_common']} | {r['n_gradients']} | "
                   f"{r['seconds']:.1f} | {t['first_speed_solves']} | {t['later_solves_per_speed']:.1f} | "
                   f"{f(t.get('solve_ratio_pattern_over_method'), '.1f')} | "
                   f"{f(t.get('time_ratio_pattern_over_method'), '.1f')} | "
                   f"{f(t.get('max_shortfall_vs_pattern'), '+.1e')} | {f(t['max_shortfall_vs_best'], '+.1e')} |")
    out += ["", "| Omega_bar | " + " | ".join(f"{m}: value (solves, stop)" for m in runs) + " | "
            + " | ".join(f"{m} vs pattern / vs best" for m in runs if m != "pattern") + " |",
            "|---|" + "---|" * (2 * len(runs) - ("pattern" in runs))]
    for row in cmp["rows"]:
        cells = [f"{row[m]['value']:.6f} ({row[m]['solves']}, {row[m]['reason']})" for m in runs]
        cells += [f"{f(row[m].get('vs_pattern'), '+.1e')} / {row[m]['vs_best']:+.1e}" for m in runs if m != "pattern"]
        out.append(f"| {row['Omega_bar']:.3f} | " + " | ".join(cells) + " |")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--nx", type=int, default=24)
    ap.add_argument("--nz", type=int, default=3)
    ap.add_argument("--G", type=float, default=2.5, help="unbalance grade of the design case")
    ap.add_argument("--gumbel-width", type=float, default=1e-3)
    ap.add_argument("--start", type=float, default=0.1)
    ap.add_argument("--end", type=float, default=0.6, help="last speed; the march also ends at the first "
                                                           "unstable optimised cycle")
    ap.add_argument("--step", type=float, default=0.05)
    ap.add_argument("--objective", choices=("max_mu", "W_cb"), default="max_mu")
    ap.add_argument("--methods", nargs="+", choices=list(METHODS), default=list(METHODS))
    ap.add_argument("--quick", action="store_true", help="16x2, Omega_bar 0.3-0.5 (~3 min)")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    if a.quick:
        a.nx, a.nz, a.start, a.end = 16, 2, 0.3, 0.5
    out = Path(a.out) if a.out else RESULTS / ("design_cost_quick.json" if a.quick else "design_cost.json")
    load0 = os.getloadavg()
    params = gfbjax.reference_system(Nx=a.nx, Nz=a.nz, gumbel_width=a.gumbel_width, G=a.G).nondim()
    t0 = time.perf_counter()
    FoilDesign(params, a.start).evaluate(0.1, 0.05, gradient=True)  # compiles every kernel; not counted
    t_compile = time.perf_counter() - t0
    print(f"grid {a.nx}x{a.nz}, G{a.G}, Omega_bar {a.start}-{a.end} step {a.step}, objective {a.objective}; "
          f"compile {t_compile:.1f} s", flush=True)
    runs = {m: run(params, a, m) for m in a.methods}
    cmp = compare(runs, a.objective)
    print()
    print(table(runs, cmp))
    doc = {"grid": [a.nx, a.nz], "G": a.G, "gumbel_width": a.gumbel_width, "start": a.start, "end": a.end,
           "step": a.step, "objective": a.objective, "x0": [0.1, 0.05], "quick": a.quick, "same_within": SAME,
           "compile_s": round(t_compile, 1), "runs": runs, "comparison": cmp,
           "machine": {"platform": platform.platform(), "python": platform.python_version(),
                       "cpus": os.cpu_count(), "jax": jax.__version__, "numpy": np.__version__,
                       "load_avg_start": load0, "load_avg_end": os.getloadavg()},
           "note": "wall times on a possibly shared machine (see load_avg); solve counts do not depend on it"}
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(doc, indent=1, default=float) + "\n")
    print(f"\nwrote {out} ({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
