#!/usr/bin/env python
"""How accurate are the reference branch's Floquet multipliers, and do the cycles' estimates say so?

The bearing's Gumbel condition max(p - 1, 0) makes f_x jump wherever a film pressure crosses ambient, so the
variational equation is one order less smooth than the orbit and the multipliers converge erratically with N
(``gfbjax.cont._resolution``, "Propagated mode defects").  For each speed the cycle of the reference branch is
corrected at fixed Omega_bar on uniform meshes of N = 16, 24, 32 and 128 intervals (m = 4, the default
collocation points, sparse solver), and the leading non-trivial multiplier of each is compared with the one on
N = 128.  Printed per (speed, N): that difference (the "true" error, itself carrying the N = 128 cycle's error,
which its own estimate states) and the three estimates a recorded point carries: the mode defects'
(``cont.mode_error``), the change on halved intervals (``cont.halved_error``) and the frozen-coefficient model's
(``cont.resolution``).

Usage:  python benchmarks/multiplier_accuracy.py [--nx 48 --nz 8] [--speeds 0.3768 0.55]
Writes benchmarks/results/multiplier_accuracy.json and prints a table.  About 4 min per speed on 2 cores.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import gfbjax

from gfbjax import cont
from gfbjax.analyses.cycles import continue_gfb_cycles, default_cycle_settings, gfb_cycle_problem
from gfbjax.cont import _collocation as col
from gfbjax.cont._mesh import remesh

RESULTS = Path(__file__).resolve().parent / "results"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--nx", type=int, default=48)
    ap.add_argument("--nz", type=int, default=8)
    ap.add_argument("--speeds", type=float, nargs="+", default=[0.3768, 0.55])
    ap.add_argument("--meshes", type=int, nargs="+", default=[16, 24, 32])
    ap.add_argument("--reference-N", type=int, default=128)
    ap.add_argument("--out", default=str(RESULTS / "multiplier_accuracy.json"))
    a = ap.parse_args()

    params = gfbjax.reference_system(Nx=a.nx, Nz=a.nz).nondim()
    problem = gfb_cycle_problem(params)
    rows = []
    t0 = time.perf_counter()
    for lam in a.speeds:
        st = default_cycle_settings(max_points=2, save_states=True)
        start = cont.start_from_branch(continue_gfb_cycles(params, lam, lam + 0.1, st), 0).orbit
        scheme = col.Scheme(st.m, st.collocation)
        got = {}
        for N in sorted(set(a.meshes) | {a.reference_N}):
            s = default_cycle_settings(N=N)
            sol, lin = cont.correct_cycle(problem, remesh(start, scheme, col.uniform_mesh(N)), settings=s)
            if not sol.converged:
                raise SystemExit(f"no cycle at Omega_bar {lam} on N = {N}: {sol.outcome}")
            an = cont.analyse(problem, lin)
            mu = an["spectrum"]
            lead = cont.nontrivial(mu, problem.n_trivial)[0]
            modes = cont.mode_error(problem.f, problem.args, sol.x, scheme, lin, mu, an["modes"], problem.n_trivial)
            halved = cont.halved_error(sol.x, scheme, lin, mu, cont.bind_solver(problem, scheme, s).linearise,
                                       an["modes"], problem.n_trivial)
            frozen = cont.resolution(problem.f, sol.x, problem.args, scheme, abs(lead))[1]
            got[N] = (lead, modes, halved, frozen)
        ref = got[a.reference_N][0]
        for N, (lead, modes, halved, frozen) in sorted(got.items()):
            true = abs(lead - ref) / max(1.0, abs(ref)) if N != a.reference_N else float("nan")
            rows.append({"Omega_bar": lam, "N": N, "leading_mu": [lead.real, lead.imag], "true_error": true,
                         "mode_error": modes, "halved_error": halved, "frozen_error": frozen})
    wall = time.perf_counter() - t0

    print(f"{'Omega_bar':>9} {'N':>4} {'|mu_lead|':>10} {'true error':>11} {'mode est':>9} {'ratio':>6} "
          f"{'halved est':>10} {'ratio':>6} {'frozen est':>10}")
    for r in rows:
        def ratio(k):
            return r[k] / r["true_error"] if r["true_error"] > 0 else float("nan")
        print(f"{r['Omega_bar']:>9.4f} {r['N']:>4d} {abs(complex(*r['leading_mu'])):>10.6f} {r['true_error']:>11.2e} "
              f"{r['mode_error']:>9.2e} {ratio('mode_error'):>6.2f} {r['halved_error']:>10.2e} "
              f"{ratio('halved_error'):>6.2f} {r['frozen_error']:>10.2e}")
    rec = {"grid": f"{a.nx}x{a.nz}", "n": problem.n, "reference_N": a.reference_N, "rows": rows,
           "wall_s": round(wall, 1),
           "note": "true_error: |mu_N - mu_ref| / max(1, |mu_ref|) of the leading non-trivial multiplier at fixed "
                   "Omega_bar; the reference carries its own error (its mode_error row)"}
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(rec, indent=1))
    print(f"wrote {a.out} ({wall:.0f} s)")


if __name__ == "__main__":
    main()
