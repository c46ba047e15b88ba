"""The paper's validation case (Table 1): rigid rotor, 10 N and 15 N per bearing.

For each load: the equilibria of the balanced rotor against speed and their Hopf point (speed in rpm, whirl
frequency), then the self-excited cycles born there (``continue_gfb_hopf_cycles``).  The direction in which the
cycle branch leaves the Hopf point and the stability of its first cycles tell super- from subcritical; the table
lists the cycle amplitude (half peak-to-peak of the journal's x_j and y_j, in c) along the branch.

Usage:  python benchmarks/validation_table1.py [--loads 10 15] [--points 40]
Writes benchmarks/results/validation_table1.json.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import gfbjax

from gfbjax import cont
from gfbjax.analyses.cycles import (continue_gfb_equilibria, continue_gfb_hopf_cycles, default_cycle_settings,
                           hopf_criticality)

RESULTS = Path(__file__).resolve().parent / "results"


def run(load: float, points: int) -> dict:
    spec = gfbjax.validation_case(load)
    p = spec.nondim()
    t0 = time.perf_counter()
    eq = continue_gfb_equilibria(p, 0.3, 1.2, cont.EquilibriumSettings(ds=0.05, ds_max=0.1, max_points=200))
    t_eq = time.perf_counter() - t0
    hopf = eq.special_of("HOPF")
    rec = {"load_N": load, "grid": f"{spec.Nx}x{spec.Nz}", "equilibria_s": round(t_eq, 1),
           "hopf": [{"Omega_bar": float(h.lam), "rpm": spec.rpm(float(h.lam)),
                     "whirl_ratio": float(h.omega) / float(h.lam) if h.omega else None}
                    for h in hopf]}
    if not hopf:
        rec["cycles"] = "no Hopf point in 0.3..1.2"
        return rec
    s = default_cycle_settings(ds=0.02, ds_max=2.0, dlam_max=0.005, max_points=points, lam_min=0.3, lam_max=1.2)
    t0 = time.perf_counter()
    b = continue_gfb_hopf_cycles(p, eq, 0, s, progress=True)
    amp = (b.xmax - b.xmin)[:, :2] / 2
    lam_h = float(hopf[0].lam)
    rec["cycles"] = {
        "seconds": round(time.perf_counter() - t0, 1), "outcome": str(b.outcome), "message": b.message,
        "criticality": hopf_criticality(b, lam_h),
        "Omega_bar": b.lam.tolist(), "rpm": [spec.rpm(float(v)) for v in b.lam],
        "amplitude_xj_c": amp[:, 0].tolist(), "amplitude_yj_c": amp[:, 1].tolist(),
        "stable": b.stable.tolist(), "period": b.period.tolist(),
        "special": [{"type": sp.type, "Omega_bar": float(sp.lam), "rpm": spec.rpm(float(sp.lam))}
                    for sp in b.special],
    }
    return rec


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--loads", type=float, nargs="+", default=[10.0, 15.0])
    ap.add_argument("--points", type=int, default=40)
    ap.add_argument("--out", default=str(RESULTS / "validation_table1.json"))
    a = ap.parse_args()
    out = []
    for load in a.loads:
        r = run(load, a.points)
        out.append(r)
        for h in r["hopf"]:
            print(f"{load:>5.1f} N: Hopf at Omega_bar {h['Omega_bar']:.4f} = {h['rpm']:.0f} rpm, "
                  f"whirl ratio {h['whirl_ratio']:.3f}")
        c = r["cycles"]
        if isinstance(c, dict):
            print(f"        cycles: {c['criticality']}, {len(c['Omega_bar'])} points, ended: {c['outcome']} ({c['message']})")
            for lam, rpm, ax, ay, st in zip(c["Omega_bar"], c["rpm"], c["amplitude_xj_c"], c["amplitude_yj_c"],
                                            c["stable"]):
                print(f"        {lam:.5f} {rpm:8.0f} rpm  amp x {ax:.4f} c  y {ay:.4f} c  "
                      f"{'stable' if st else 'unstable'}")
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(out, indent=1))
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
