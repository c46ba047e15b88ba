"""Bifurcation diagrams of the reference system and the paper's design variations (issue 3, item 7).

For every design (k_s 0.3 and 3; alpha_f 0.01 and 1; eta 0.005 and 0.5; unbalance G1, G2.5 and the reference
G6.3) the branch of synchronous limit cycles Omega_bar 0.05 -> 1.0 on the default grid, with its bifurcations;
for the balanced rotor (G0) the equilibria with their Hopf point.  The table gives the first bifurcation of each
design and where stability is first lost; the figure shows the journal's vertical displacement (max and min over
the cycle) of every design, stable solid and unstable dashed.

Usage:  python benchmarks/variation_diagrams.py [--from DIR]   (DIR/<name>/branch.{npz,json} from earlier
        ``gfbjax cycles --system <name> --out DIR/<name>`` runs are loaded instead of recomputed)
Writes benchmarks/results/variations.json and variations.png.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import gfbjax
import numpy as np

from gfbjax import cont
from gfbjax.analyses.cycles import continue_gfb_cycles, continue_gfb_equilibria

RESULTS = Path(__file__).resolve().parent / "results"
DESIGNS = ["reference", "ks0.3", "ks3", "af0.01", "af1", "eta0.005", "eta0.5", "G1", "G2.5"]


def _branch(name: str, src: Path | None, kind: str, folder: str | None = None) -> tuple[cont.Branch, float | None]:
    """Load ``src/<folder or name>/branch`` when present, else compute the branch (and time it)."""
    if src is not None and (src / (folder or name) / "branch.json").exists():
        return cont.Branch.load(src / (folder or name) / "branch"), None
    params = gfbjax.variation(name).nondim()
    t0 = time.perf_counter()
    b = (continue_gfb_cycles(params, 0.05, 1.0) if kind == "cycles"
         else continue_gfb_equilibria(params, 0.05, 1.0))
    return b, time.perf_counter() - t0


def summary(name: str, b: cont.Branch, seconds: float | None) -> dict:
    spec = gfbjax.variation(name)
    first_unstable = next((float(b.lam[i]) for i in range(len(b)) if not b.stable[i]), None)
    sp = [{"type": s.type, "Omega_bar": float(s.lam), "rpm": spec.rpm(float(s.lam)),
           "located": bool(s.located), "angle": None if s.angle is None else float(s.angle)} for s in b.special]
    return {"design": name, "points": len(b), "reached": float(b.lam[-1]),
            "outcome": str(b.outcome), "message": b.message,
            "first_unstable_Omega_bar": first_unstable, "special": sp,
            "max_trivial_error": float(np.nanmax(b.trivial_error)) if b.kind == "cycles" else None,
            "seconds": None if seconds is None else round(seconds, 1)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--from", dest="src", default=None, help="folder with earlier gfbjax cycles outputs")
    ap.add_argument("--out", default=str(RESULTS / "variations"))
    a = ap.parse_args()
    src = Path(a.src) if a.src else None
    rows, branches = [], {}
    for name in DESIGNS:
        b, sec = _branch(name, src, "cycles")
        branches[name] = b
        rows.append(summary(name, b, sec))
    g0, sec = _branch("G0", src, "equilibria", folder="G0eq")
    g0row = summary("G0", g0, sec)
    for s, raw in zip(g0row["special"], g0.special):
        if s["type"] == "HOPF" and raw.omega is not None:  # whirl frequency (Im of the critical eigenvalue)
            s["whirl_ratio"] = float(raw.omega) / s["Omega_bar"]
    rows.append(g0row)

    print(f"{'design':<10} {'first bifurcation':<34} {'first unstable':>15} {'reached':>8}  all special points")
    for r in rows:
        first = r["special"][0] if r["special"] else None
        fb = f"{first['type']} {first['Omega_bar']:.4f} ({first['rpm']:.0f} rpm)" if first else "none"
        fu = f"{r['first_unstable_Omega_bar']:.4f}" if r["first_unstable_Omega_bar"] is not None else "-"
        allsp = ", ".join(f"{s['type']}@{s['Omega_bar']:.4f}" for s in r["special"])
        print(f"{r['design']:<10} {fb:<34} {fu:>15} {r['reached']:>8.4f}  {allsp}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 3, figsize=(13, 10), sharex=True)
    for ax, name in zip(axes.ravel(), DESIGNS):
        b = branches[name]
        lam, st = np.asarray(b.lam), np.asarray(b.stable)
        for arr in (b.xmax[:, 1], b.xmin[:, 1]):
            ax.plot(lam, np.where(st, arr, np.nan), "b-", lw=1.4)
            ax.plot(lam, np.where(~st, arr, np.nan), "r--", lw=1.0)
        for s in b.special:
            i = int(np.argmin(np.abs(lam - s.lam)))
            ax.plot(lam[i], b.xmax[i, 1], "D", color="tab:purple" if s.type == "NS" else "tab:orange")
            ax.annotate(s.type, (lam[i], b.xmax[i, 1]), textcoords="offset points", xytext=(4, 4), fontsize=8)
        ax.set_title(name, fontsize=10)
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("Omega_bar")
    for ax in axes[:, 0]:
        ax.set_ylabel("y_j / c (max, min)")
    fig.suptitle("Synchronous limit cycles of the design variations (stable solid blue, unstable dashed red)")
    fig.tight_layout()
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out.with_suffix(".png"), dpi=110)
    out.with_suffix(".json").write_text(json.dumps({"designs": rows, "grid": "48x8 (default)", "N": 16, "m": 4},
                                                   indent=1, default=float))
    print(f"wrote {out.with_suffix('.json')} and {out.with_suffix('.png')}")


if __name__ == "__main__":
    main()
