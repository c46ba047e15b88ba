"""Write the gallery notebooks of this folder from the cell sources below (run from anywhere:
``python notebooks/_make_notebooks.py``).  The notebooks are stored without outputs; CI executes them
(``pytest --nbmake``, see pyproject.toml).  Edit the sources here, not the .ipynb files, and rerun this script."""
from __future__ import annotations

from pathlib import Path

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

HERE = Path(__file__).resolve().parent

SETUP = '''\
# One switch: False runs a coarse grid in about a minute on 2 CPU cores (numbers are qualitative and marked
# "coarse" in docs/reproduction.md); True uses the project's default grid and collocation mesh (minutes to an hour).
PAPER_QUALITY = False

import os
import tempfile
import time

import gfbjax  # turns on 64-bit floats
import jax

# Keep compiled kernels on disk between notebooks and runs: a choice of this notebook's process, not of gfbjax.
jax.config.update("jax_compilation_cache_dir", os.path.join(tempfile.gettempdir(), "gfbjax-notebook-jax-cache"))
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.2)

import matplotlib.pyplot as plt
import numpy as np
from IPython.display import Markdown, display

GRID = dict(Nx=48, Nz=8) if PAPER_QUALITY else dict(Nx=16, Nz=2)   # finite-difference grid of the film
MESH = dict(N=16, m=4) if PAPER_QUALITY else dict(N=8, m=3)         # collocation mesh of the cycles
QUALITY = "default grid 48x8, N=16, m=4" if PAPER_QUALITY else "coarse grid 16x2, N=8, m=3"
PRESETS = ("corrected", "paper")
T_START = time.perf_counter()


def specials(branch, spec):
    """The special points of a branch as (type, Omega_bar, rpm, located)."""
    return [(sp.type, round(float(sp.lam), 4), round(spec.rpm(float(sp.lam))), bool(sp.located))
            for sp in branch.special]


def table(header, rows):
    """Show rows as a Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    display(Markdown("\\n".join(lines)))
'''

END = '''\
print(f"notebook run time: {time.perf_counter() - T_START:.0f} s ({QUALITY})")
'''


def md(text: str):
    return new_markdown_cell(text.strip("\n"))


def code(text: str):
    return new_code_cell(text.strip("\n"))


NOTEBOOKS: dict[str, list] = {}

# ---------------------------------------------------------------------------------------------------------------
NOTEBOOKS["00_getting_started"] = [
    md('''
# Getting started with gfbjax

A rotor on two gas foil bearings, from a system in SI units to a branch of limit cycles, then one design change
and the two readings of the paper (the *presets*, docs/model.md section 6). Every cell uses the public API;
`PAPER_QUALITY` in the first cell switches from a coarse grid (fast, qualitative) to the project's default grid.
'''),
    code(SETUP),
    md('''
## 1. A system in SI units and its dimensionless groups

`gfbjax.reference_system()` is the project's reference system (docs/model.md section 8). `preset="paper"` reads
the paper literally: foil damping `c_f = eta k_f`, the whole rotor's unbalance carried by the disc and the
ISO grade converted at 2500 rpm.
'''),
    code('''
specs = {p: gfbjax.reference_system(preset=p, **GRID) for p in PRESETS}
spec, params = specs["corrected"], specs["corrected"].nondim()
print(f"t* = {spec.t_star * 1e6:.0f} us; Omega_bar = 1 is {spec.rpm(1.0):,.0f} rpm")
print("dimensionless groups:", {k: round(float(getattr(params, k)), 5)
                                for k in ("kappa", "zeta", "sigma", "k_s", "mass_ratio", "alpha_f", "eta", "eps")})
table(["preset", "foil damping", "unbalance on the disc", "omega_r unit", "e_u [um]", "eps = disc forcing / (c Omega^2)"],
      [(p, s.foil_damping, s.unbalance_mass, s.omega_r_unit, f"{s.eccentricity_u * 1e6:.2f}",
        f"{float(s.nondim().eps):.4f}") for p, s in specs.items()])
'''),
    md('''
## 2. Static equilibrium of the balanced rotor

Gravity only, at Omega_bar = 0.3. The presets give the same equilibrium (damping and unbalance do not act on a
steady state) but not the same stability: the foil damping enters the Jacobian.
'''),
    code('''
from gfbjax.analyses.static import solve_equilibrium
from gfbjax.plot.static import plot_static_summary

eqs = {p: solve_equilibrium(s.nondim(), 0.3) for p, s in specs.items()}
table(["preset", "outcome", "y_j [c]", "h_min [c]", "critical eigenvalue", "stable"],
      [(p, e.outcome, f"{e.y_j:.4f}", f"{e.h_min:.4f}", f"{e.critical_eigenvalue:.6f}", e.stable)
       for p, e in eqs.items()])
assert abs(eqs["corrected"].y_j - eqs["paper"].y_j) < 1e-9
fig = plot_static_summary(eqs["corrected"], spec)
'''),
    md('''
## 3. A short branch of unbalance-response limit cycles

Orthogonal collocation and pseudo-arclength continuation in the speed, with the Floquet multipliers of every cycle
and the bifurcations located (NS: Neimark-Sacker, PD: period doubling, LPC: fold of cycles).
'''),
    code('''
from gfbjax.analyses.cycles import continue_gfb_cycles, default_cycle_settings
from gfbjax.plot.branch import plot_bifurcation

settings = default_cycle_settings(**MESH, max_points=40)
branches = {"reference (corrected)": continue_gfb_cycles(params, 0.2, 0.5, settings, spec=spec)}
b = branches["reference (corrected)"]
print(b.outcome, "-", b.message)
print("special points (type, Omega_bar, rpm, located):", specials(b, spec))
'''),
    md('''
## 4. Change one parameter, and the paper's literal reading

A softer foil (`alpha_f = 1`), and the reference system under the paper preset (its larger unbalance makes the
cycles much larger: the branch is followed only to 0.3 here).
'''),
    code('''
soft = spec.replace(alpha_f=1.0)
branches["alpha_f = 1 (corrected)"] = continue_gfb_cycles(soft.nondim(), 0.2, 0.5, settings, spec=soft)
branches["reference (paper preset)"] = continue_gfb_cycles(specs["paper"].nondim(), 0.2, 0.3, settings,
                                                           spec=specs["paper"])
fig = plot_bifurcation(branches, spec=spec, title=f"Limit cycles, three systems ({QUALITY})")
'''),
    md('''
## Verdict

The first loss of stability of each branch in the range computed (coarse-grid numbers unless `PAPER_QUALITY`).
'''),
    code('''
rows = []
for label, b in branches.items():
    sp = specials(b, spec)
    first = sp[0] if sp else None
    rows.append((label, f"{b.lam[0]:.2f} - {b.lam[-1]:.3f}", first[0] if first else "none",
                 f"{first[1]:.4f} ({first[2]:,} rpm)" if first else "-", b.outcome))
table(["system", "range Omega_bar", "first bifurcation", "at", "branch end"], rows)
'''),
    code(END),
]

# ---------------------------------------------------------------------------------------------------------------
NOTEBOOKS["figs04_05_static"] = [
    md('''
# Figs. 4 and 5: static load capacity, equilibrium locus, pressure and foil profiles

The balanced rotor under gravity plus an extra vertical load per bearing, for three foil compliances and three
speeds, under both presets. The paper's Figs. 4-5 use several clearance ratios (R/c = 500, 750, 1000); here the
reference system's R/c = 500 only. The presets change the foil damping and the unbalance, neither of which acts on
a steady state: the equilibria must coincide, while their stability (the Jacobian's eigenvalues) need not.
'''),
    code(SETUP),
    code('''
from gfbjax.analyses.static import load_displacement
from gfbjax.plot.static import plot_equilibrium_locus, plot_load_displacement

ALPHAS = (0.01, 0.1, 1.0)
SPEEDS = (0.2, 0.4, 0.6)
LOADS = (0.0, 0.05, 0.1, 0.2, 0.3, 0.4, 0.6, 0.8) if PAPER_QUALITY else (0.0, 0.1, 0.2, 0.4, 0.8)
curves = {}
for p in PRESETS:
    curves[p] = {}
    for a in ALPHAS:
        prm = gfbjax.reference_system(preset=p, alpha_f=a, **GRID).nondim()
        curves[p][a] = {w: load_displacement(prm, w, LOADS) for w in SPEEDS}
spec = gfbjax.reference_system(**GRID)
'''),
    md('## Fig. 4: vertical journal displacement against the specific load, both presets'),
    code('''
fig, axes = plt.subplots(2, 3, figsize=(15, 8), constrained_layout=True)
for row, p in zip(axes, PRESETS):
    plot_load_displacement(curves[p], spec=spec, ax=row)
    row[0].set_title(f"preset {p!r}: " + row[0].get_title(), fontsize=9)
_ = fig.suptitle(f"Fig. 4 under both presets ({QUALITY})")
'''),
    md('## Fig. 5: equilibrium locus, mid-plane pressure and foil deflection (identical under both presets)'),
    code('''
fig = plot_equilibrium_locus(curves["corrected"], spec=spec, profile_speed=0.4,
                             title=f"Fig. 5 ({QUALITY}); the paper preset gives the same equilibria")
'''),
    md('''
## Stability of the equilibria under the two presets

Real part of the critical eigenvalue against load (negative: stable).
'''),
    code('''
fig, axes = plt.subplots(1, 3, figsize=(15, 4), constrained_layout=True)
for ax, a in zip(axes, ALPHAS):
    for w, colour in zip(SPEEDS, ("tab:blue", "tab:orange", "tab:green")):
        for p, ls in zip(PRESETS, ("-", "--")):
            rs = [r for r in curves[p][a][w] if r.converged]
            ax.plot([r.w for r in rs], [r.critical_eigenvalue.real for r in rs], ls, color=colour,
                    label=f"Omega_bar {w}, {p}")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set(title=f"alpha_f = {a}", xlabel="W / (p0 L D)", ylabel="Re(critical eigenvalue)")
    ax.grid(alpha=0.3)
_ = axes[0].legend(fontsize=7)
'''),
    md('## Verdict'),
    code('''
dy, n_pts, n_flip, rows = 0.0, 0, 0, []
for a in ALPHAS:
    for w in SPEEDS:
        rc, rp = curves["corrected"][a][w], curves["paper"][a][w]
        for r1, r2 in zip(rc, rp):
            if r1.converged and r2.converged:
                dy = max(dy, abs(r1.y_j - r2.y_j))
                n_pts += 1
                n_flip += r1.stable != r2.stable
        last = rc[-1]
        carried = last.w if last.converged else rc[-2].w if len(rc) > 1 else 0.0
        pmax = max(float(r.pressure.max()) for r in rc if r.converged)
        rows.append((a, w, f"{carried:g}" + ("" if last.converged else " (film closes above)"),
                     f"{min(r.y_j for r in rc if r.converged):.3f}", f"{pmax:.2f}",
                     "yes" if all(r.stable for r in rc if r.converged) else "no"))
assert dy < 1e-8, dy
table(["alpha_f", "Omega_bar", "largest load carried", "lowest y_j [c]", "largest p/p0", "all stable (corrected)"],
      rows)
print(f"largest |y_j(corrected) - y_j(paper)| over {n_pts} equilibria: {dy:.1e} c; stability label differs at "
      f"{n_flip} of them")
'''),
    code(END),
]

# ---------------------------------------------------------------------------------------------------------------
NOTEBOOKS["fig06_table1_validation"] = [
    md('''
# Fig. 6 and Table 1: Hopf speed of the validation case

Rigid rotor on two foil bearings with the properties of the paper's Table 1 (after Zhou et al. 2021; docs/model.md
section 8), balanced, 10 N (the text) and 15 N (the table) per bearing. The equilibria are continued in speed and
the Hopf bifurcation (onset of the self-excited whirl) located. Of the three switches only the foil damping acts
here (the rotor is balanced and rigid).

The paper reports a Hopf speed of 12,030 rpm for its model and 11,475 rpm for Zhou et al.'s (10 N); the two numbers
are not in the project's text copy of the paper and are compared below as reported.
'''),
    code(SETUP),
    code('''
from gfbjax.analyses.cycles import continue_gfb_equilibria
from gfbjax.plot.branch import plot_equilibria

REPORTED = {"paper": 12030, "Zhou et al.": 11475}  # rpm, 10 N per bearing
grids = [GRID, dict(Nx=80, Nz=8)] if PAPER_QUALITY else [GRID, dict(Nx=32, Nz=4)]
hopf, eq_branches = {}, {}
for grid in grids:
    for load in (10.0, 15.0):
        for p in PRESETS:
            spec = gfbjax.validation_case(load, preset=p, **grid)
            b = continue_gfb_equilibria(spec.nondim(), 0.3, 1.2, spec=spec)
            hp = [sp for sp in b.special if sp.type == "HOPF"]
            hopf[(grid["Nx"], grid["Nz"], load, p)] = (float(hp[0].lam), spec.rpm(float(hp[0].lam))) if hp else None
            eq_branches[(grid["Nx"], grid["Nz"], load, p)] = b
'''),
    md('## Equilibria and the critical eigenvalue, 10 N, both presets (finest grid of this run)'),
    code('''
g = grids[-1]
fig = plot_equilibria({f"{p}": eq_branches[(g["Nx"], g["Nz"], 10.0, p)] for p in PRESETS},
                      spec=gfbjax.validation_case(10.0, **g),
                      title=f"Validation case, 10 N per bearing, grid {g['Nx']}x{g['Nz']}")
'''),
    md('''
## Self-excited cycles from the Hopf point (only with `PAPER_QUALITY`)

Whether the Hopf bifurcation is sub- or supercritical and the first stable cycle past it; on the default grid the
project finds both loads subcritical (README, *Results*).
'''),
    code('''
if PAPER_QUALITY:
    from gfbjax.analyses.cycles import continue_gfb_hopf_cycles, default_cycle_settings, hopf_criticality
    for load in (10.0, 15.0):
        spec = gfbjax.validation_case(load, **GRID)
        b = eq_branches[(GRID["Nx"], GRID["Nz"], load, "corrected")]
        cyc = continue_gfb_hopf_cycles(spec.nondim(), b, settings=default_cycle_settings(
            **MESH, ds=0.02, ds_max=0.5, dlam_max=0.01, max_points=40), spec=spec)
        print(load, "N:", hopf_criticality(cyc, hopf[(GRID["Nx"], GRID["Nz"], load, "corrected")][0]),
              specials(cyc, spec))
else:
    print("skipped on the coarse grid (set PAPER_QUALITY = True)")
'''),
    md('## Verdict'),
    code('''
rows = []
for (nx, nz, load, p), v in hopf.items():
    if v is None:
        rows.append((f"{nx}x{nz}", f"{load:g} N", p, "no Hopf in 0.3-1.2", "", ""))
        continue
    lam, rpm = v
    rows.append((f"{nx}x{nz}", f"{load:g} N", p, f"{lam:.4f}", f"{rpm:,.0f}",
                 f"{100 * (rpm / REPORTED['paper'] - 1):+.1f} %"))
table(["grid", "load", "preset", "Hopf Omega_bar", "Hopf rpm", "vs 12,030 rpm"], rows)
for (nx, nz) in {(g["Nx"], g["Nz"]) for g in grids}:
    for load in (10.0, 15.0):
        a, b = hopf[(nx, nz, load, "corrected")], hopf[(nx, nz, load, "paper")]
        if a and b:
            print(f"grid {nx}x{nz}, {load:g} N: paper damping moves the Hopf speed by {b[1] - a[1]:+.0f} rpm")
'''),
    code(END),
]

# ---------------------------------------------------------------------------------------------------------------
NOTEBOOKS["fig07_reference_branch"] = [
    md("""
# Fig. 7: the reference system's bifurcation set, run-up, STFT and Floquet multipliers

Reference system (`k_s = 1`, `alpha_f = 0.1`, `eta = 0.05`, G6.3) under both presets, and under the two single
switches that matter, to tell which one does what. The paper's Fig. 7 shows PD, SN (fold) and NS bifurcations; its
text gives no speeds. Under the corrected conventions the unbalance is 2.52 um (eps = 0.066); under the paper's
literal reading it is 24.1 um, for the whole rotor's mass, carried by the disc (eps = 1.26, more than the
clearance).

Each branch ends where the film closes (the journal would pass through the foil: the cycles beyond are not
physical), reported as the outcome `contact`.
"""),
    code(SETUP),
    code("""
from gfbjax.analyses.cycles import continue_gfb_cycles, default_cycle_settings

ref = gfbjax.reference_system(**GRID)
VARIANTS = {
    "corrected": ref,
    "paper": ref.with_preset("paper"),
    "e_u 24.1 um, Eq. 15a": ref.replace(omega_r_unit="rpm"),      # only the rpm reading of Eq. (16)
    "c_f = eta k_f only": ref.replace(foil_damping="paper"),     # only the printed foil damping
}
END_SPEED = {"corrected": 1.0 if PAPER_QUALITY else 0.6, "paper": 0.4, "e_u 24.1 um, Eq. 15a": 0.45,
             "c_f = eta k_f only": 1.0 if PAPER_QUALITY else 0.6}
settings = default_cycle_settings(**MESH, max_points=200 if PAPER_QUALITY else 60)
branches = {}
for name, s in VARIANTS.items():
    branches[name] = continue_gfb_cycles(s.nondim(), 0.05, END_SPEED[name], settings, spec=s)
    print(f"{name:>22}: {branches[name].outcome} - {branches[name].message}")
    print(" " * 24, "special points:", specials(branches[name], s))
"""),
    md("## Bifurcation diagrams side by side"),
    code("""
from gfbjax.plot.branch import plot_bifurcation

fig, axes = plt.subplots(2, len(VARIANTS), figsize=(6 * len(VARIANTS), 8), constrained_layout=True)
for col, (name, s) in enumerate(VARIANTS.items()):
    plot_bifurcation(branches[name], spec=s, ax=axes[:, col])
    axes[0, col].set_title(name, fontsize=10, pad=28)
_ = fig.suptitle(f"Fig. 7a: limit cycles of the reference system ({QUALITY})")
"""),
    md("""
## Where the cycles stop being physical

The smallest film thickness over each cycle (`Branch.monitor`); at or below zero the journal passes through the foil.
"""),
    code("""
fig, ax = plt.subplots(figsize=(8, 3.5))
for name, b in branches.items():
    ax.plot(b.lam, b.monitor, ".-", ms=3, label=name)
ax.axhline(0.0, color="k", lw=0.8)
ax.set(xlabel="Omega_bar", ylabel="min h / c over the cycle")
ax.legend(fontsize=8)
ax.grid(alpha=0.3)
plt.show()
"""),
    md("## Run-up through the range (Eq. 15b) with the cycles overlaid, and its STFT (both presets)"),
    code("""
from gfbjax.analyses.signals import runup_stft, subsynchronous
from gfbjax.analyses.transient import run_up
from gfbjax.plot.transient import plot_runup, plot_spectrogram

REVS = 300 if PAPER_QUALITY else 150
runs = {p: run_up(VARIANTS[p].nondim(), 0.05, END_SPEED["corrected"], revolutions=REVS) for p in PRESETS}
fig, axes = plt.subplots(2, 2, figsize=(15, 7), constrained_layout=True, sharex=True)
for col, p in enumerate(PRESETS):
    b = branches[p]
    cyc = {"speed": b.lam, "stable": b.stable, "y_max": b.xmax[:, 1], "y_min": b.xmin[:, 1],
           "x_max": b.xmax[:, 0], "x_min": b.xmin[:, 0]}
    plot_runup(runs[p], cyc, ax=axes[:, col])
    axes[0, col].set_title(f"preset {p!r}: {runs[p].outcome} at Omega_bar {runs[p].speed[-1]:.3f}", fontsize=9)
fig, axes = plt.subplots(1, 2, figsize=(15, 4.5), constrained_layout=True)
sub = {}
for ax, p in zip(axes, PRESETS):
    r = runs[p]
    sg = runup_stft(r.tau, r.y_j, r.speed)
    sub[p] = subsynchronous(sg)
    plot_spectrogram(sg, subsync=sub[p], ax=ax, title=f"STFT of y_j, preset {p!r}")
"""),
    md("## Floquet multipliers"),
    code("""
from gfbjax.plot.branch import plot_multipliers

fig, axes = plt.subplots(1, len(VARIANTS), figsize=(5.5 * len(VARIANTS), 5.5), constrained_layout=True)
for ax, (name, b) in zip(axes, branches.items()):
    plot_multipliers(b, ax=ax, title=name)
"""),
    md("## Verdict"),
    code("""
rows = [("paper, Fig. 7", "PD, SN and NS (speeds in the figure only)", "-", "-")]
for name, b in branches.items():
    s = VARIANTS[name]
    h_close = float(b.lam[-1]) if b.outcome == "contact" else None  # located where min h reaches 0
    run = runs.get(name)
    rows.append((name,
                 "; ".join(f"{t} {lam:.4f} ({rpm:,} rpm)" + ("" if located else " (bracketed)")
                           for t, lam, rpm, located in specials(b, s)) or "none",
                 f"{h_close:.4f}" if h_close is not None else f"open up to {b.lam[-1]:.3f}",
                 (f"{run.outcome} at {run.speed[-1]:.3f}" + (f"; sub-synchronous from {sub[name][0].speed_start:.3f}"
                                                           if sub[name] else "")) if run else "-"))
table(["system", "bifurcations with the film open (Omega_bar)", "film closes at", "run-up"], rows)
"""),
    code(END),
]

# ---------------------------------------------------------------------------------------------------------------
NOTEBOOKS["fig12_energy"] = [
    md('''
# Fig. 12: energy flow along the cycle branches

Per cycle, in units of `p0 R L c` (docs/model.md section 5): `W_fu` the work of the unbalance force, `W_cf` the
energy dissipated in the foil dampers and `W_cb = W_B - W_cf` the net dissipation in the gas films. The paper
states that at every design the first Neimark-Sacker bifurcation coincides with `W_cb` turning negative. Here the
reference system and the G2.5 design of Fig. 12d (with `PAPER_QUALITY` also Fig. 12a-c: `k_s = 3`,
`alpha_f = 0.01`, `eta = 0.5`), under both presets.
'''),
    code(SETUP),
    code('''
from gfbjax.analyses.cycles import continue_gfb_cycles, default_cycle_settings
from gfbjax.analyses.energy import branch_energy, sign_changes

DESIGNS = {"reference": {}, "G2.5 (Fig. 12d)": {"G": 2.5}}
if PAPER_QUALITY:
    DESIGNS.update({"k_s 3 (Fig. 12a)": {"k_s_bar": 3.0}, "alpha_f 0.01 (Fig. 12b)": {"alpha_f": 0.01},
                    "eta 0.5 (Fig. 12c)": {"eta": 0.5}})
END_SPEED = {"corrected": 1.0 if PAPER_QUALITY else 0.6, "paper": 0.4}
settings = default_cycle_settings(**MESH, max_points=200 if PAPER_QUALITY else 50, save_states=True)
results = {}
for d, changes in DESIGNS.items():
    for p in PRESETS:
        s = gfbjax.reference_system(preset=p, **GRID, **changes)
        prm = s.nondim()
        b = continue_gfb_cycles(prm, 0.05, END_SPEED[p], settings, spec=s)
        E = branch_energy(b, prm)
        err = float(np.max(np.abs(E.W_fu - E.W_B) / np.maximum(np.abs(E.W_fu), 1e-300)))
        assert err < 1e-6, (d, p, err)  # the rotor is conservative: W_fu = W_B on every cycle
        results[(d, p)] = (s, b, E, np.asarray(b.monitor))  # h_min / c over each cycle
        print(f"{d:>24} {p:>9}: {len(b.lam)} cycles, {b.outcome}; max |W_fu - W_B| / |W_fu| = {err:.1e}")
'''),
    md('## W_fu, W_cf and W_cb along the branches (left: corrected, right: paper preset)'),
    code('''
from gfbjax.plot.branch import plot_energy

fig, axes = plt.subplots(1, 2, figsize=(15, 5), constrained_layout=True)
for ax, p in zip(axes, PRESETS):
    plot_energy([(d, results[(d, p)][1], results[(d, p)][2]) for d in DESIGNS], overlay=True, ax=[ax],
                quantities=("W_cf", "W_cb"))
    ax.set_title(f"preset {p!r} ({QUALITY})", fontsize=10, pad=26)
'''),
    md('''
## The gas films' share of the dissipation, W_cb / W_fu

`W_fu = W_cf + W_cb` on every cycle: the unbalance's work per cycle goes either into the foil dampers or into the
films. A sign change of `W_cb` would mean the films feed energy into the whirl.
'''),
    code('''
fig, axes = plt.subplots(1, 2, figsize=(15, 4), constrained_layout=True, sharey=True)
for ax, p in zip(axes, PRESETS):
    for d in DESIGNS:
        s, b, E, h = results[(d, p)]
        line, = ax.plot(b.lam, E.W_cb / E.W_fu, "-", label=d)
        for sp in b.special:
            if sp.type == "NS":
                ax.axvline(sp.lam, color=line.get_color(), ls=":", lw=1)
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set(title=f"preset {p!r} (dotted: NS)", xlabel="Omega_bar", ylabel="W_cb / W_fu")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
plt.show()
'''),
    md('## Verdict: does W_cb change sign at the first NS?'),
    code('''
rows = []
for (d, p), (s, b, E, h) in results.items():
    ns = [sp.lam for sp in b.special if sp.type == "NS"]
    first = b.special[0] if b.special else None
    open_ = h > 0.0
    changes = sign_changes(b.lam[open_], E.W_cb[open_])
    ratio = np.interp(ns[0], b.lam, E.W_cb / E.W_fu) if ns and np.all(np.diff(b.lam) > 0) else float("nan")
    rows.append((d, p, f"{first.type} at {first.lam:.4f}" if first else "none",
                 f"{ns[0]:.4f} (W_cb/W_fu = {ratio:.3f})" if ns else "none",
                 ", ".join(f"{c['Omega_bar']:.4f} (from {c['from']})" for c in changes) or "none",
                 f"{np.min(E.W_cb[open_]):.3g} / {np.max(E.W_cb[open_]):.3g}",
                 f"up to {b.lam[-1]:.4f} (film closes)" if b.outcome == "contact" else "all"))
table(["design", "preset", "first bifurcation", "first NS", "W_cb sign changes (open film)", "W_cb min / max",
       "cycles with open film"], rows)
'''),
    code(END),
]

# ---------------------------------------------------------------------------------------------------------------
NOTEBOOKS["fig16_19_schedules"] = [
    md('''
# Figs. 16-19: foil properties scheduled along the speed to keep the cycles stable

The paper optimises the bump foil (`alpha_f`, `eta`) at each speed, marching up in speed from optimum to optimum,
and finds the bifurcation-free speed range about twice that of the reference design. Here the paper's second
objective (Figs. 18-19: the largest non-trivial Floquet multiplier, `max_mu`) with gfbjax's gradient method
(implicit derivatives through the cycle), inside the design bounds `0.005 <= alpha_f <= 2`, `1e-4 <= eta <= 10`,
for the reference system under both presets. The un-optimised limit is the first bifurcation of the reference
branch, or the speed where its film closes.
'''),
    code(SETUP),
    code('''
from gfbjax.analyses.cycles import continue_gfb_cycles, default_cycle_settings
from gfbjax.design.schedule import optimized_continuation
from gfbjax.model import film


def film_watch(params, out):
    """A callback for optimized_continuation: the smallest film thickness h/c over each optimum's cycle (at the
    collocation mesh nodes).  The design evaluation does not stop at film contact, so it is checked here."""
    h_of = jax.jit(jax.vmap(lambda x: film(x[:-2], params).min()))
    return lambda opt: out.append(float(np.min(h_of(opt.evaluation.orbit.xm))))


specs = {p: gfbjax.reference_system(preset=p, **GRID) for p in PRESETS}
START = {"corrected": 0.35, "paper": 0.1}
STEP = 0.025 if PAPER_QUALITY else 0.05
limit, schedules, hmin = {}, {}, {}
for p, s in specs.items():
    b = continue_gfb_cycles(s.nondim(), 0.05, 0.8 if PAPER_QUALITY else 0.6,
                            default_cycle_settings(**MESH, max_points=200 if PAPER_QUALITY else 60), spec=s)
    sp = [x for x in b.special if x.type in ("NS", "PD", "LPC")]
    limit[p] = (sp[0].type, float(sp[0].lam)) if sp else ("film closes" if b.outcome == "contact" else
                                                          str(b.outcome), float(b.lam[-1]))
    hmin[p] = []
    schedules[p] = optimized_continuation(s.nondim(), START[p], 0.8, STEP, objective="max_mu", method="gradient",
                                          **MESH, max_evals=None if PAPER_QUALITY else 8,
                                          callback=film_watch(s.nondim(), hmin[p]))
    sch = schedules[p]
    print(f"{p}: un-optimised limit {limit[p]}; schedule {sch.outcome} - {sch.message}; "
          f"{sch.n_solves} cycle solves, {sch.seconds:.0f} s")
'''),
    md('## The schedules (a: orbit extent, b: alpha_f, c: eta, d: max|mu|, e: W_cb, f: multipliers)'),
    code('''
from gfbjax.plot.branch import plot_schedule

fig = plot_schedule([(p, schedules[p]) for p in PRESETS], spec=specs["corrected"],
                    title=f"Optimised foil along the speed, objective max|mu| ({QUALITY}; x: unstable)")
'''),
    md('## Verdict'),
    code('''
rows = [("paper, Figs. 16-19", "-", "-", "-", "about 2x")]
for p in PRESETS:
    sch = schedules[p]
    free = sch.bifurcation_free_to
    kind, lam0 = limit[p]
    if sch.outcome == "unstable":  # the march found the speed where no admissible foil keeps the cycle stable
        reached, ratio = f"{free:.3f}; unstable at {sch.omega[-1]:.3f}", f"{free / lam0:.2f}x"
    else:  # it ended otherwise (no cycle converged, end of range): the limit is not a bifurcation
        reached, ratio = f"at least {free:.3f}; {sch.outcome}: {sch.message}" if free else str(sch.outcome), "-"
    h = np.asarray(hmin[p])
    closed = np.flatnonzero(h <= 0.0)
    film_txt = (f"open (min h = {h.min():.3f} c)" if not closed.size else
                f"closed from {sch.omega[closed[0]]:.3f} (min h = {h.min():.3f} c)")
    if closed.size and ratio != "-":
        ratio += " (film closed before)"
    rows.append((p, f"{kind} at {lam0:.4f} ({specs[p].rpm(lam0):,.0f} rpm)", reached, film_txt, ratio))
table(["system", "un-optimised limit", "optimised cycles stable up to", "film over the optimised cycles",
       "range ratio"], rows)
table(["preset", "Omega_bar", "alpha_f", "eta", "max abs(mu)", "W_cb", "min h / c"],
      [(p, f"{w:.3f}", f"{a:.4g}", f"{e:.4g}", f"{m:.4f}", f"{wcb:.3g}", f"{h:.3f}")
       for p in PRESETS for w, a, e, m, wcb, h in zip(schedules[p].omega, schedules[p].alpha_f, schedules[p].eta,
                                                      schedules[p].max_mu, schedules[p].W_cb, hmin[p])])
'''),
    code(END),
]


def main() -> None:
    for name, cells in NOTEBOOKS.items():
        nb = new_notebook(cells=cells, metadata={
            "kernelspec": {"name": "python3", "display_name": "Python 3", "language": "python"},
            "language_info": {"name": "python"}})
        nbformat.validate(nb)
        path = HERE / f"{name}.ipynb"
        nbformat.write(nb, path)
        print("wrote", path)


if __name__ == "__main__":
    main()
