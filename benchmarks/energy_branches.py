"""Energy flow along the limit-cycle branches of the paper's Fig. 12 designs, and the paper's claim that W_cb
changes sign at the first Neimark-Sacker bifurcation (issue 5, item 1).

Designs (Fig. 12): a) k_s 3, b) alpha_f 0.01, c) eta 0.5 (all G6.3), d) the reference foil with G2.5.  For each,
the synchronous cycle branch Omega_bar 0.05 -> 1.0 on the default grid with its states, W_fu, W_B, W_cf, W_cb by
the collocation quadrature (``gfbjax.analyses.energy``), the NS speeds and the speeds where W_cb changes sign.  The JSON
reports both, and their difference, whatever it is.

Usage:  python benchmarks/energy_branches.py [--nx 48 --nz 8] [--designs ks3 af0.01 eta0.5 G2.5]
Writes benchmarks/results/energy_branches.json and energy_branches.png (and docs/figures/energy_flow.png).
"""
from __future__ import annotations

import argparse
import json
import shutil
import time
from pathlib import Path

import gfbjax
import numpy as np

from gfbjax.analyses.cycles import continue_gfb_cycles, default_cycle_settings
from gfbjax.analyses.energy import branch_energy, sign_changes
from gfbjax.plot.branch import plot_energy

RESULTS = Path(__file__).resolve().parent / "results"
FIGURES = Path(__file__).resolve().parent.parent / "docs" / "figures"
LABELS = {"ks3": "a) $k_s$ = 3, G6.3", "af0.01": r"b) $\alpha_f$ = 0.01, G6.3", "eta0.5": r"c) $\eta$ = 0.5, G6.3",
          "G2.5": "d) reference foil, G2.5", "reference": "reference, G6.3"}


def first_local_max(lam: np.ndarray, W: np.ndarray) -> float | None:
    """Speed of the first interior local maximum of W along the branch (vertex of the parabola through the
    maximal point and its neighbours)."""
    for i in range(1, len(W) - 1):
        if W[i] >= W[i - 1] and W[i] > W[i + 1]:
            x, y = lam[i - 1:i + 2], W[i - 1:i + 2]
            c = np.polyfit(x, y, 2)
            return float(-c[1] / (2 * c[0])) if c[0] < 0 else float(lam[i])
    return None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--nx", type=int, default=48)
    ap.add_argument("--nz", type=int, default=8)
    ap.add_argument("--designs", nargs="+", default=["ks3", "af0.01", "eta0.5", "G2.5"])
    ap.add_argument("--end", type=float, default=1.0)
    ap.add_argument("--out", default=str(RESULTS / "energy_branches"))
    a = ap.parse_args()
    rows, panels = [], []
    for name in a.designs:
        params = gfbjax.variation(name, Nx=a.nx, Nz=a.nz).nondim()
        t0 = time.perf_counter()
        b = continue_gfb_cycles(params, 0.05, a.end, default_cycle_settings(save_states=True))
        E = branch_energy(b, params)
        sec = time.perf_counter() - t0
        ns = [float(s.lam) for s in b.special_of("NS")]
        zc = sign_changes(b.lam, E.W_cb)
        first_down = next((c["Omega_bar"] for c in zc if c["from"] == "+"), None)
        wmax = first_local_max(np.asarray(b.lam), np.asarray(E.W_cb))
        ident = float(np.max(np.abs(E.W_fu - E.W_B) / np.maximum(np.abs(E.W_fu), 1e-300)))
        rows.append({"design": name, "points": len(b), "reached": float(b.lam[-1]),
                     "outcome": str(b.outcome), "message": b.message,
                     "NS_Omega_bar": ns, "W_cb_sign_changes": zc,
                     "first_NS": ns[0] if ns else None, "first_W_cb_drop_below_0": first_down,
                     "difference": (first_down - ns[0]) if (ns and first_down is not None) else None,
                     "first_W_cb_maximum": wmax,
                     "min_W_cf": float(np.min(E.W_cf)), "max_rel_identity_error": ident, "seconds": round(sec, 1),
                     "Omega_bar": b.lam.tolist(), "stable": np.asarray(b.stable).tolist(),
                     "W_fu": E.W_fu.tolist(), "W_cf": E.W_cf.tolist(), "W_cb": E.W_cb.tolist()})
        panels.append((LABELS.get(name, name), b, E))
        print(f"{name}: {len(b)} points in {sec:.0f} s; NS {ns}; W_cb sign changes {zc}; "
              f"max |W_fu - W_B|/|W_fu| = {ident:.1e}", flush=True)
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    plot_energy(panels, path=out.with_suffix(".png"))
    FIGURES.mkdir(parents=True, exist_ok=True)
    shutil.copy(out.with_suffix(".png"), FIGURES / "energy_flow.png")
    out.with_suffix(".json").write_text(json.dumps({"grid": [a.nx, a.nz], "designs": rows}, indent=1))
    print(f"\n{'design':<10} {'first NS':>10} {'W_cb + -> -':>12} {'difference':>11} {'W_cb max at':>12}")
    for r in rows:
        f = lambda v: "-" if v is None else f"{v:.4f}"
        print(f"{r['design']:<10} {f(r['first_NS']):>10} {f(r['first_W_cb_drop_below_0']):>12} {f(r['difference']):>11}"
              f" {f(r['first_W_cb_maximum']):>12}")
    print(f"wrote {out.with_suffix('.json')}")


if __name__ == "__main__":
    main()
