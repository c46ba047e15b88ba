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
    md('''
## The model variants the paper leaves open (10 N, first grid)

Each is an option of `SystemSpec` or `validation_case` (docs/reproduction.md, *Fig. 6 and Table 1*, has the table on
the default grid): the Gumbel condition applied to the film itself, `N_X - 2` springs, the whole bearing length
instead of the half with its symmetry plane, and the rotor mass. The paper gives no rotor mass; reading its Table 1
(15 N) as the rotor's weight and its text (10 N) as the static load is the one reading that moves the Hopf speed
towards the paper.
'''),
    code('''
variants = {"baseline (mass = load / g)": gfbjax.validation_case(10.0, **GRID),
            "Gumbel on the film": gfbjax.validation_case(10.0, gumbel="pressure", **GRID),
            "N_X - 2 springs": gfbjax.validation_case(10.0, foil_springs="no_first", **GRID),
            "whole length": gfbjax.validation_case(10.0, axial_domain="full", **GRID),
            "15 N weight, 10 N load": gfbjax.validation_case(10.0, mass_per_bearing=15.0 / 9.81, **GRID)}
rows = []
for name, spec in variants.items():
    b = continue_gfb_equilibria(spec.nondim(), 0.2, 1.2, spec=spec)
    hp = [sp for sp in b.special if sp.type == "HOPF"]
    rpm = spec.rpm(float(hp[0].lam)) if hp else float("nan")
    rows.append((name, f"{rpm:,.0f}", f"{100 * (rpm / REPORTED['paper'] - 1):+.1f} %"))
table(["variant", "Hopf rpm", "vs 12,030 rpm"], rows)
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

# ---------------------------------------------------------------------------------------------------------------
NOTEBOOKS["figs08_11_variations"] = [
    md('''
# Figs. 8-11: bifurcation diagrams of the design variations

The paper changes one design value at a time around the reference system (`k_s = 1`, `alpha_f = 0.1`,
`eta = 0.05`, G6.3) to its next lower and higher value: shaft stiffness `k_s` 0.3 / 3 (Fig. 8), foil compliance
`alpha_f` 0.01 / 1 (Fig. 9), foil loss factor `eta` 0.005 / 0.5 (Fig. 10) and unbalance G0 / G1 / G2.5 (Fig. 11;
`gfbjax.params.VARIATIONS`). Each of its figures has four panels: (a) the branch of limit cycles, (b) the STFT of a
run-up, (c) a trajectory with Poincare map and FFT, (d) the Floquet multipliers. Here panel (a) only, under both
presets: the cycle branches in `Omega_bar` with their special points and where stability is first lost (the
balanced rotor G0 has no forced cycle: its equilibria and their Hopf point instead). The run-up and its STFT are
shown for the reference system in `fig07_reference_branch.ipynb`.

Every branch starts at `Omega_bar = 0.05` and ends at the end of the range or where the film closes (outcome
`contact`: the cycles beyond are not physical). The paper's text names the types of bifurcation but gives no
speeds (those are only in its figures).
'''),
    code(SETUP),
    code('''
from gfbjax.analyses.cycles import continue_gfb_cycles, continue_gfb_equilibria, default_cycle_settings

FIGURES = {  # the paper's figures and the variations they compare with the reference (gfbjax.params.VARIATIONS)
    "Fig. 8": ("ks0.3", "ks3"),
    "Fig. 9": ("af0.01", "af1"),
    "Fig. 10": ("eta0.005", "eta0.5"),
    "Fig. 11": ("G0", "G1", "G2.5"),
}
LABELS = {"reference": "reference (G6.3)", "ks0.3": "k_s 0.3", "ks3": "k_s 3", "af0.01": "alpha_f 0.01",
          "af1": "alpha_f 1", "eta0.005": "eta 0.005", "eta0.5": "eta 0.5", "G0": "G0 (equilibria)", "G1": "G1",
          "G2.5": "G2.5"}
# The paper preset's unbalance (24.1 um on the disc, twice) closes the film early or makes the cycles strongly
# nonlinear at low speed, where the continuation takes small steps: a shorter range, more points.
END_SPEED = {"corrected": 1.0 if PAPER_QUALITY else 0.5, "paper": 0.6 if PAPER_QUALITY else 0.45}
MAX_POINTS = {"corrected": 200 if PAPER_QUALITY else 40, "paper": 200 if PAPER_QUALITY else 70}
branches, specs = {}, {}
for p in PRESETS:
    settings = default_cycle_settings(**MESH, max_points=MAX_POINTS[p])
    for name in LABELS:
        s = gfbjax.variation(name, preset=p, **GRID)
        t0 = time.perf_counter()
        if float(s.nondim().eps) > 0.0:
            b = continue_gfb_cycles(s.nondim(), 0.05, END_SPEED[p], settings, spec=s)
        else:  # balanced rotor: no forced cycle; its static equilibria and their Hopf point
            b = continue_gfb_equilibria(s.nondim(), 0.05, END_SPEED[p], spec=s)
        branches[(name, p)], specs[(name, p)] = b, s
        print(f"{name:>9} {p:>9}: {len(b.lam):3d} points to {b.lam[-1]:.3f}, {b.outcome} "
              f"({time.perf_counter() - t0:4.1f} s); special points {specials(b, s)}")
'''),
    md('''
## Bifurcation diagrams, one paper figure each (left: corrected, right: paper preset)

Journal displacement, maximum and minimum over the cycle (for G0: the equilibrium); stable solid, unstable
dashed, special points marked. The reference branch is drawn in every figure.
'''),
    code('''
from gfbjax.plot.branch import plot_bifurcation

for fig_name, names in FIGURES.items():
    fig, axes = plt.subplots(2, 2, figsize=(15, 8), constrained_layout=True, sharex="col")
    for col, p in enumerate(PRESETS):
        plot_bifurcation({LABELS[n]: branches[(n, p)] for n in ("reference",) + names},
                         spec=specs[("reference", p)], ax=axes[:, col])
        axes[0, col].set_title(f"preset {p!r}", fontsize=10, pad=28)
    _ = fig.suptitle(f"{fig_name}: " + ", ".join(LABELS[n] for n in names) + f" against the reference ({QUALITY})")
'''),
    md('''
## Where stability is first lost

First special point of each branch and the first point labelled unstable (both with the film open, since a branch
stops where the film closes); `x` marks a branch that ends before the end of the range.
'''),
    code('''
fig, axes = plt.subplots(1, 2, figsize=(15, 4.5), constrained_layout=True, sharey=True)
order = ["reference"] + [n for names in FIGURES.values() for n in names]
for ax, p in zip(axes, PRESETS):
    for k, name in enumerate(order):
        b = branches[(name, p)]
        lam = np.asarray(b.lam)
        ax.plot([lam[0], lam[-1]], [k, k], "-", color="0.75", lw=6, solid_capstyle="butt")
        unstable = np.flatnonzero(~np.asarray(b.stable, bool))
        if unstable.size:
            ax.plot(lam[unstable[0]], k, "v", color="tab:red", ms=8)
        for sp in b.special:
            ax.plot(sp.lam, k, "D", ms=6, color="tab:purple")
            ax.annotate(sp.type, (sp.lam, k), textcoords="offset points", xytext=(3, 6), fontsize=7)
        if lam[-1] < END_SPEED[p] - 1e-9:
            ax.plot(lam[-1], k, "kx", ms=8)
    ax.set(title=f"preset {p!r}", xlabel="Omega_bar")
    ax.set_yticks(range(len(order)), [LABELS[n] for n in order])
    ax.grid(alpha=0.3)
_ = fig.suptitle("grey: range computed; red triangle: first unstable point; diamond: special point; x: the branch "
                 "ended before the end of the range", fontsize=10)
'''),
    md('''
## Verdict

Stability is lost between the last stable point and the first unstable one (a located special point is inserted
as a point of its own). Points flagged (`Branch.flagged`; grey crosses in the diagrams, whose legend names only
the trivial multiplier): cycles whose estimated mesh error is above the tolerance, whose trivial Floquet
multiplier is off, or whose multipliers the mesh does not resolve (`Branch.multiplier_error`,
`Branch.stiff_modulus`: at low speed the film's fast modes and the rotor mode), i.e. the orbit, its multipliers or
its stability label are less certain. On the coarse mesh (N = 8) that is
most cycles of the paper preset, whose large orbits it does not resolve.
'''),
    code('''
def stability_lost(b):
    i = np.flatnonzero(~np.asarray(b.stable, bool))
    if not i.size:
        return "stable throughout"
    return f"{b.lam[i[0] - 1]:.4f} - {b.lam[i[0]]:.4f}" if i[0] > 0 else f"unstable from {b.lam[0]:.4f}"


def bifurcations(b, s):
    sp = specials(b, s)
    return "; ".join(f"{t} {lam:.4f}" + ("" if ok else " (bracketed)") for t, lam, rpm, ok in sp) or "none"


def ending(b, p):
    if str(b.outcome) == "reached_end":
        return f"reached {b.lam[-1]:.3f}"
    return f"{b.outcome} at {b.lam[-1]:.3f}" + (" (film closes)" if str(b.outcome) == "contact" else "")


rows = []
for fig_name, names in FIGURES.items():
    for name in ("reference",) + names:
        for p in PRESETS:
            b, s = branches[(name, p)], specs[(name, p)]
            rows.append((fig_name if name != "reference" else "(all)", LABELS[name], p, bifurcations(b, s),
                         stability_lost(b), ending(b, p), f"{int(np.sum(b.flagged))}/{len(b.lam)}"))
rows = list(dict.fromkeys(rows))  # the reference once per preset
table(["figure", "design", "preset", "bifurcations with the film open (Omega_bar)", "stability lost between",
       "branch", "points flagged"], rows)
'''),
    md('''
The paper's claims (from its text; its figures, and so its speeds, cannot be read here) against what the branches
above give, per preset. The checks are computed from the branches; the reasons are the project's reading
(docs/reproduction.md, *Figs. 8-11*).
'''),
    code('''
def types(name, p):
    return sorted({sp.type for sp in branches[(name, p)].special})


def first(name, p):
    b = branches[(name, p)]
    return (b.special[0].type, float(b.special[0].lam)) if b.special else None


def said(name, p):
    f = first(name, p)
    return f"{f[0]} {f[1]:.3f}" if f else ending(branches[(name, p)], p)


def claims(p):
    ref = first("reference", p)
    out = []
    # Fig. 8
    pd = [n for n in FIGURES["Fig. 8"] if "PD" in types(n, p)]
    out.append(("Fig. 8", "k_s 0.3 / 3: bifurcation sets differ from the reference; no period doubling",
                f"{'PD in ' + ', '.join(pd) if pd else 'no PD'}; first: k_s 0.3 {said('ks0.3', p)}, k_s 3 "
                f"{said('ks3', p)}, reference {said('reference', p)}"))
    # Fig. 9
    out.append(("Fig. 9", "alpha_f 0.01 / 1: the same types as the reference (PD, SN, NS), at other speeds",
                f"types: reference {types('reference', p) or 'none'}, alpha_f 0.01 {types('af0.01', p) or 'none'}, "
                f"alpha_f 1 {types('af1', p) or 'none'}; first: alpha_f 0.01 {said('af0.01', p)}, alpha_f 1 "
                f"{said('af1', p)}"))
    # Fig. 10
    shift = [abs(first(n, p)[1] - ref[1]) for n in FIGURES["Fig. 10"] if first(n, p) and ref]
    out.append(("Fig. 10", "eta 0.005 / 0.5: little influence on the bifurcation set; PD in one case (Fig. 10c)",
                f"first: eta 0.005 {said('eta0.005', p)}, eta 0.5 {said('eta0.5', p)}, reference "
                f"{said('reference', p)}" + (f"; largest shift {max(shift):.4f}" if shift else "")))
    # Fig. 11
    ns = [(n, first(n, p)[1]) for n in ("G1", "G2.5", "reference") if first(n, p) and first(n, p)[0] == "NS"]
    falls = len(ns) > 1 and all(a[1] > b[1] for a, b in zip(ns, ns[1:]))
    out.append(("Fig. 11", "G0 loses stability by Hopf near the speed where the unbalanced rotors have NS; the larger "
                "the unbalance, the lower the NS speed",
                f"G0 {said('G0', p)}; G1 {said('G1', p)}, G2.5 {said('G2.5', p)}, G6.3 {said('reference', p)}: "
                + (f"the NS speed falls with the unbalance ({len(ns)} of 3 have an NS)" if falls else
                   "the NS speeds do not fall with the unbalance" if len(ns) > 1 else
                   f"{len(ns)} of 3 unbalanced rotors have an NS")))
    return out


def reason(p):
    cyc = [n for n in LABELS if n != "G0"]
    by = {"bif": [n for n in cyc if branches[(n, p)].special],
          "closes": [n for n in cyc if not branches[(n, p)].special and str(branches[(n, p)].outcome) == "contact"],
          "stalls": [n for n in cyc if not branches[(n, p)].special and str(branches[(n, p)].outcome)
                     not in ("contact", "reached_end")]}
    eps = float(specs[("reference", p)].nondim().eps)
    hopf = first("G0", p)
    txt = (f"eps = {eps:.3f} for G6.3 (e_u {specs[('reference', p)].eccentricity_u * 1e6:.1f} um"
           + (", carried twice" if p == "paper" else "") + ")")
    txt += f"; G0's Hopf at {hopf[1]:.3f}" if hopf else "; G0: no Hopf in the range"
    names = lambda key: ", ".join(LABELS[n] for n in by[key]) or "none"
    first_speeds = [first(n, p)[1] for n in by["bif"]]
    if first_speeds:
        txt += (f". First bifurcation with the film open for {names('bif')}: "
                f"{', '.join(sorted({first(n, p)[0] for n in by['bif']}))} between {min(first_speeds):.3f} "
                f"and {max(first_speeds):.3f}")
    if by["closes"]:
        txt += f". The film closes before any bifurcation for {names('closes')}"
    if by["stalls"]:
        txt += (f". The continuation stops at low speed (a resonance of the large cycle, film nearly closed) for "
                f"{names('stalls')}")
    return txt + "."


REASON = {"corrected": "the unbalance is small: the synchronous cycle stays close to the equilibrium, and it loses "
                       "stability where the balanced rotor's whirl mode does (Hopf of G0), so each variation moves "
                       "that one NS a little",
          "paper": "the literal unbalance is 19 times larger (the rpm reading of Eq. 16 and the whole rotor's "
                   "mass): large cycles, which mostly close the film before any bifurcation"}
rows = []
for p in PRESETS:
    rows += [(f, claim, p, got) for f, claim, got in claims(p)]
table(["figure", "paper's claim", "preset", "what we get"], rows)
table(["preset", "what decides", "in numbers"], [(p, REASON[p], reason(p)) for p in PRESETS])
'''),
    code(END),
]

# ---------------------------------------------------------------------------------------------------------------
# A helper shared by the notebooks of Figs. 13-14 and Fig. 15: drawing a map over the foil properties.  The maps
# themselves come from gfbjax.design.maps.energy_map_stepped (every foil reached from a solved neighbour).
FOIL_MAP = '''\
from gfbjax.design.evaluate import FOIL_BOUNDS, CycleNotConverged, FoilDesign
from gfbjax.design.maps import energy_map_stepped
from gfbjax.model import film


def _edges(v):
    """Cell edges around log-spaced values."""
    u = np.log(v)
    mid = 0.5 * (u[1:] + u[:-1])
    return np.exp(np.r_[2 * u[0] - mid[0], mid, 2 * u[-1] - mid[-1]])


def draw_map(ax, alphas, etas, values, h_min, title, log=False, cmap="viridis"):
    """A map over (alpha_f, eta) on log axes; x: the film closes over the cycle (not physical); blank: no cycle."""
    from matplotlib.colors import LogNorm

    ok = np.isfinite(values)
    norm = LogNorm(np.nanmin(values[values > 0]), np.nanmax(values)) if log and np.any(values > 0) else None
    pc = ax.pcolormesh(_edges(alphas), _edges(etas), values, shading="flat", cmap=cmap, norm=norm)
    ax.figure.colorbar(pc, ax=ax)
    closed = ok & (h_min <= 0.0)
    A, E = np.meshgrid(alphas, etas)
    ax.plot(A[closed], E[closed], "wx", ms=9, mew=2)
    ax.set(xscale="log", yscale="log", xlabel="alpha_f", ylabel="eta", title=title)
    ax.title.set_fontsize(9)
'''

NOTEBOOKS["figs13_14_maps"] = [
    md('''
# Figs. 13-14: gas-film and foil dissipation over the foil properties

At fixed speed, the synchronous limit cycle of the reference system (`k_s = 1`, G6.3) for every foil of a grid
over compliance `alpha_f` and loss factor `eta` (log-spaced inside the design bounds `0.005 <= alpha_f <= 2`,
`1e-4 <= eta <= 10`), under both presets: `W_cb`, the energy the gas films dissipate per cycle (Fig. 13),
`W_cf`, the energy the foil dampers dissipate (Fig. 14), both in `p0 R L c`, and the largest non-trivial Floquet
multiplier `max|mu|` (not a figure of the paper: where the cycle is stable, < 1). The paper computes the maps at
`Omega_bar` 0.2, 0.4 and 0.6; the coarse run one speed, 0.2, on a 5 x 5 grid.

Every point is reached from a solved neighbour by small steps in the foil properties
(`gfbjax.design.maps.energy_map_stepped`); `gfbjax.design.maps.energy_map`, the project's batched map, starts
every point from the one cycle of the reference foil and is used as a cross-check where it converges.
'''),
    code(SETUP),
    code(FOIL_MAP),
    code('''
from gfbjax.design.maps import energy_map

SPEEDS = (0.2, 0.4, 0.6) if PAPER_QUALITY else (0.2,)
K = 9 if PAPER_QUALITY else 5
ALPHAS = np.geomspace(*FOIL_BOUNDS["alpha_f"], K)
ETAS = np.geomspace(*FOIL_BOUNDS["eta"], K)
specs = {p: gfbjax.reference_system(preset=p, **GRID) for p in PRESETS}
maps, checks = {}, {}
for w in SPEEDS:
    for p, s in specs.items():
        maps[(w, p)] = m = energy_map_stepped(s.nondim(), w, ALPHAS, ETAS, **MESH)
        n_ok, n_closed = int(m.converged.sum()), int(np.sum(m.h_min <= 0.0))
        line = (f"Omega_bar {w}, {p:>9}: {n_ok}/{K * K} foils with a cycle, {n_closed} of them with the film closed; "
                f"{m.member_steps} Newton steps, {m.seconds:.0f} s")
        try:  # the batched map from the reference foil's cycle, where its Newton converges
            em = energy_map(s.nondim(), w, ALPHAS, ETAS, **MESH)
            both = em.converged & m.converged
            dev = float(np.max(np.abs(em.W_cb - m.W_cb)[both] / np.abs(m.W_cb[both]))) if both.any() else np.nan
            checks[(w, p)] = (int(em.converged.sum()), int(both.sum()), dev)
            line += f"; energy_map: {em.converged.sum()}/{K * K} converged, largest relative difference {dev:.1e}"
        except CycleNotConverged as exc:
            checks[(w, p)] = (0, 0, np.nan)
            line += f"; energy_map: {exc}"
        print(line)
'''),
    md('''
## The maps (rows: presets; columns: W_cb as Fig. 13, W_cf as Fig. 14, max|mu|)

Star: the largest `W_cb` with the film open; white x: the film closes somewhere on the cycle (not physical);
blank: no cycle found.
'''),
    code('''
for w in SPEEDS:
    fig, axes = plt.subplots(2, 3, figsize=(16, 8.5), constrained_layout=True)
    for row, p in zip(axes, PRESETS):
        m = maps[(w, p)]
        draw_map(row[0], ALPHAS, ETAS, m.W_cb, m.h_min, f"W_cb [p0 R L c], preset {p!r}")
        draw_map(row[1], ALPHAS, ETAS, m.W_cf, m.h_min, f"W_cf [p0 R L c] (log colour), preset {p!r}", log=True)
        draw_map(row[2], ALPHAS, ETAS, m.max_mu, m.h_min, f"max|mu|, preset {p!r}", cmap="coolwarm")
        row[2].contour(ALPHAS, ETAS, m.max_mu, levels=[1.0], colors="k")
        ok = m.converged & (m.h_min > 0.0)
        if ok.any():
            i, j = np.unravel_index(np.argmax(np.where(ok, m.W_cb, -np.inf)), ok.shape)
            row[0].plot(ALPHAS[j], ETAS[i], "*", color="tab:red", ms=16, mec="w")
    _ = fig.suptitle(f"Omega_bar = {w} ({QUALITY}; {K} x {K} foils)")
'''),
    md('''
## How much the foil matters: W_cb along the grid lines

`W_cb` against `alpha_f` for every `eta` of the grid (open film only), relative to the reference foil's.
'''),
    code('''
fig, axes = plt.subplots(len(SPEEDS), 2, figsize=(14, 4 * len(SPEEDS)), constrained_layout=True, squeeze=False)
for r, w in enumerate(SPEEDS):
    for ax, p in zip(axes[r], PRESETS):
        m = maps[(w, p)]
        for i, e in enumerate(ETAS):
            ok = m.h_min[i] > 0.0
            ax.plot(ALPHAS[ok], m.W_cb[i][ok], "o-", ms=4, label=f"eta {e:.2g}")
        ax.set(xscale="log", xlabel="alpha_f", ylabel="W_cb [p0 R L c]", title=f"Omega_bar {w}, preset {p!r}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
plt.show()
'''),
    md('## Verdict'),
    code('''
CLAIM_W_cb = {0.2: "largest at alpha_f about 1 and low eta", 0.4: "largest at alpha_f about 1 and high eta",
              0.6: "largest for several pairs: low alpha_f with high eta"}
CLAIM_W_cf = "grows as the foil gets softer and less damped (all three speeds)"


def argmax(values, ok):
    if not ok.any():
        return None
    i, j = np.unravel_index(np.argmax(np.where(ok, values, -np.inf)), values.shape)
    return ALPHAS[j], ETAS[i], values[i, j]


rows = []
for w in SPEEDS:
    for p in PRESETS:
        m = maps[(w, p)]
        ok = m.converged & (m.h_min > 0.0)
        if not ok.any():
            rows.append((w, p, CLAIM_W_cb[w], "no cycle with an open film", "-", "-", "-"))
            continue
        a, e, v = argmax(m.W_cb, ok)
        spread = (np.max(m.W_cb[ok]) - np.min(m.W_cb[ok])) / np.max(m.W_cb[ok])
        af, ef, vf = argmax(m.W_cf, ok)
        mu = m.max_mu[ok]
        fu = m.W_fu[ok]
        au, eu, _ = argmax(m.W_fu, ok)
        rows.append((w, p, CLAIM_W_cb[w],
                     f"alpha_f {a:.3g}, eta {e:.2g} (W_cb {v:.3g}; over the map it varies by {100 * spread:.0f} %)",
                     f"alpha_f {af:.3g}, eta {ef:.2g} (W_cf {vf:.2g})",
                     f"alpha_f {au:.3g}, eta {eu:.2g} / {100 * (fu.max() - fu.min()) / fu.max():.0f} % / "
                     f"{100 * np.max(m.W_cf[ok] / fu):.0f} %",
                     f"{np.sum(mu < 1)}/{mu.size} stable (max|mu| {mu.min():.3f}-{mu.max():.3f})",
                     f"{ok.sum()}/{K * K} open, {np.sum(m.h_min <= 0)} closed, "
                     f"{np.sum(~m.converged)} not found"))
table(["Omega_bar", "preset", "paper, W_cb (Fig. 13)", "largest W_cb, open film (ours)",
       "largest W_cf (ours; paper: " + CLAIM_W_cf + ")",
       "W_fu: largest at / its spread over the map / W_cf's largest share of it",
       "cycles stable", "foils"], rows)
table(["Omega_bar", "preset", "energy_map converged", "compared", "largest relative difference in W_cb"],
      [(w, p, f"{c[0]}/{K * K}", c[1], f"{c[2]:.1e}") for (w, p), c in checks.items()])
'''),
    md('''
**Reading the table.** On every cycle `W_fu = W_cf + W_cb`: the work the unbalance puts in per cycle leaves through
the foil dampers or through the films. `W_cf` vanishes as `eta -> 0` (no damper) and as `eta -> infinity` (a
damper too stiff to move), so its largest value cannot lie at the lowest loss factor, as the paper's "low damping"
has it; a soft foil, as the paper says, does raise it. `W_cb` is then the difference of the other two works: a
softer foil lets the journal move more and raises the unbalance's work `W_fu`, but its dampers take a larger share
of it (the table gives where `W_fu` is largest and the largest share `W_cf` takes). In the coarse run the dampers'
share wins and `W_cb` is largest on the stiffest foils, not at `alpha_f` about 1. "Not found": no cycle reached from
the solved neighbours (a cycle may still exist there); the paper's text does not say how its maps treat such
foils or a closed film. Its colour scales cannot be read from its text, so only the locations of the maxima are
compared.

`energy_map` starts every foil from the reference foil's cycle, so it misses the foils far from it; where both
converge they agree to rounding. Both fix every cycle's phase by the reference foil's cycle: the discretised
cycle is not exactly invariant under a shift in time, so with each walk step's start as the phase reference
instead, the works of the two maps differed by up to 1e-4 relative on the coarse mesh.
'''),
    code(END),
]

# ---------------------------------------------------------------------------------------------------------------
NOTEBOOKS["fig15_optimizer_traces"] = [
    md('''
# Fig. 15: optimiser traces at one speed, pattern search against the gradient method

The paper maximises `W_cb` (its first objective, as `1/W_cb`) over the foil properties at each speed with a
generalised pattern search (its Appendix A2) and shows in Fig. 15 the objective, `alpha_f` and `eta` at every
iteration, at `Omega_bar` 0.2, 0.4 and 0.6. Here, at one speed (coarse: 0.2; `PAPER_QUALITY`: all three), the same
pattern search (`method="pattern"`) against gfbjax's projected quasi-Newton method with implicit gradients
(`method="gradient"`), for both objectives (`"W_cb"`, maximised, and `"max_mu"`, the largest non-trivial Floquet
multiplier, minimised), under both presets, both from the reference foil (`alpha_f = 0.1`, `eta = 0.05`; the
paper starts from random values). The currency is the cycle solve.

As in `benchmarks/foil_optimizers.py` both methods run on the smoothed Gumbel condition (`gumbel_width = 1e-3`):
with the exact `max(p - 1, 0)` the multipliers jump where a film node crosses ambient, which stalls a gradient
method on `max_mu`. The background of each path is a coarse map of the objective over the same plane (computed as
in `figs13_14_maps.ipynb`).
'''),
    code(SETUP),
    code(FOIL_MAP),
    code('''
from gfbjax.design.schedule import optimize_at_speed

SPEEDS = (0.2, 0.4, 0.6) if PAPER_QUALITY else (0.2,)
K = 9 if PAPER_QUALITY else 5
ALPHAS = np.geomspace(*FOIL_BOUNDS["alpha_f"], K)
ETAS = np.geomspace(*FOIL_BOUNDS["eta"], K)
X0 = (0.1, 0.05)
OBJECTIVES, METHODS = ("W_cb", "max_mu"), ("pattern", "gradient")
specs = {p: gfbjax.reference_system(preset=p, gumbel_width=1e-3, **GRID) for p in PRESETS}
runs, maps, hmin, failed = {}, {}, {}, {}
for w in SPEEDS:
    for p, s in specs.items():
        params = s.nondim()
        try:
            design = FoilDesign(params, w, **MESH)
            start = design.evaluate(*X0)
        except CycleNotConverged as exc:
            failed[(w, p)] = str(exc)
            print(f"Omega_bar {w}, {p}: no cycle at the reference foil: {exc}")
            continue
        h_of = jax.jit(jax.vmap(lambda x: film(x[:-2], params).min()))
        for obj in OBJECTIVES:
            for method in METHODS:
                design.set_speed(w, start.orbit)
                try:
                    r = optimize_at_speed(design, obj, method, X0)
                except CycleNotConverged as exc:
                    failed[(w, p, obj, method)] = str(exc)
                    continue
                runs[(w, p, obj, method)] = r
                hmin[(w, p, obj, method)] = float(np.min(h_of(r.evaluation.orbit.xm)))
                print(f"Omega_bar {w}, {p:>9}, {obj:>6}, {method:>8}: alpha_f {r.alpha_f:.4g}, eta {r.eta:.4g}, "
                      f"value {r.value:.6g} after {r.n_solves} cycle solves ({r.n_gradients} gradients), "
                      f"{r.seconds:.1f} s, stop: {r.reason}")
        t0 = time.perf_counter()
        maps[(w, p)] = energy_map_stepped(params, w, ALPHAS, ETAS, **MESH)
        print(f"Omega_bar {w}, {p}: background map {time.perf_counter() - t0:.0f} s")
'''),
    md('''
## Paths over the (alpha_f, eta) plane

Small dots: every foil evaluated; line: the best so far (the incumbent), from the start (square) to the optimum
(star). Background: the objective over the plane (white x: the film closes).
'''),
    code('''
STYLE = {"pattern": dict(color="tab:blue"), "gradient": dict(color="tab:red")}
for w in SPEEDS:
    fig, axes = plt.subplots(2, 2, figsize=(14, 10), constrained_layout=True)
    for row, p in zip(axes, PRESETS):
        for ax, obj in zip(row, OBJECTIVES):
            if (w, p) in maps:
                m = maps[(w, p)]
                draw_map(ax, ALPHAS, ETAS, getattr(m, obj), m.h_min, f"{obj}, preset {p!r}",
                         cmap="viridis" if obj == "W_cb" else "coolwarm")
            for method in METHODS:
                r = runs.get((w, p, obj, method))
                if r is None:
                    continue
                h = np.asarray(r.history, float)
                sign = -1.0 if obj == "W_cb" else 1.0
                best = np.minimum.accumulate(sign * h[:, 2])
                inc = np.r_[0, np.flatnonzero(np.diff(best) < 0) + 1]  # the evaluations that improved
                ax.plot(h[:, 0], h[:, 1], ".", ms=3, alpha=0.5, **STYLE[method])
                ax.plot(h[inc, 0], h[inc, 1], "-", lw=1.5, label=f"{method}: {r.n_solves} solves", **STYLE[method])
                ax.plot(r.alpha_f, r.eta, "*", ms=15, mec="k", **STYLE[method])
            ax.plot(*X0, "ks", ms=8)
            ax.set(xscale="log", yscale="log", xlabel="alpha_f", ylabel="eta")
            ax.legend(fontsize=8, loc="best", framealpha=0.6)
    _ = fig.suptitle(f"Optimiser paths at Omega_bar = {w} ({QUALITY})")
'''),
    md('''
## Traces as in Fig. 15: objective, alpha_f and eta at every evaluation

One point per converged cycle solve, in the order the optimiser asked for them (failed solves, counted in the
totals above, leave no point).
'''),
    code('''
for w in SPEEDS:
    cols = [(p, obj) for p in PRESETS for obj in OBJECTIVES]
    fig, axes = plt.subplots(3, len(cols), figsize=(4.2 * len(cols), 8), constrained_layout=True, sharex="col")
    for k, (p, obj) in enumerate(cols):
        for method in METHODS:
            r = runs.get((w, p, obj, method))
            if r is None:
                continue
            h = np.asarray(r.history, float)
            n = np.arange(1, len(h) + 1)
            for row, (c, label) in enumerate(((2, obj), (0, "alpha_f"), (1, "eta"))):
                axes[row, k].plot(n, h[:, c], ".-", lw=0.7, ms=3, label=f"{method} ({len(h)} converged)",
                                  **STYLE[method])
                axes[row, k].set_ylabel(label)
        axes[0, k].set_title(f"{obj}, preset {p!r}", fontsize=9)
        axes[0, k].legend(fontsize=7)
        axes[1, k].set_yscale("log")
        axes[2, k].set_yscale("log")
        axes[2, k].set_xlabel("evaluation (converged cycle solve)")
        for row in axes[:, k]:
            row.grid(alpha=0.3)
    _ = fig.suptitle(f"Optimisation traces at Omega_bar = {w} ({QUALITY})")
'''),
    md('## Verdict'),
    code('''
rows = [("paper, Fig. 15", "all", "W_cb", "pattern search from random foils; 10 to 200 iterations depending on the "
         "speed (optima in the figure only)", "-", "-", "-")]
for w in SPEEDS:
    for p in PRESETS:
        if (w, p) in failed:
            rows.append((w, p, "both", f"no cycle at the reference foil ({failed[(w, p)][:60]}...)", "-", "-", "-"))
            continue
        for obj in OBJECTIVES:
            rp, rg = runs.get((w, p, obj, "pattern")), runs.get((w, p, obj, "gradient"))
            txt = {}
            for method, r in (("pattern", rp), ("gradient", rg)):
                if r is None:
                    txt[method] = "no cycle"
                    continue
                h = hmin[(w, p, obj, method)]
                txt[method] = (f"alpha_f {r.alpha_f:.3g}, eta {r.eta:.3g}: {obj} {r.value:.5g}; {r.n_solves} solves; "
                               f"{'stable' if r.evaluation.stable else 'unstable'}; min h {h:.3f} c"
                               + (" (film closed)" if h <= 0 else ""))
            if rp and rg:
                better, worse = (rg, rp) if (rg.value > rp.value) == (obj == "W_cb") else (rp, rg)
                rel = abs(rg.value - rp.value) / max(abs(rp.value), abs(rg.value))
                same = ("yes" if rel <= 5e-3 else f"no: {better.method} better ({better.value:.4g} against "
                        f"{worse.value:.4g})")
                if rel <= 5e-3 and np.hypot(*np.log(np.array([rp.alpha_f, rp.eta]) / [rg.alpha_f, rg.eta])) > 0.1:
                    same += ", at another foil (a flat objective)"
                ratio = f"{rp.n_solves / rg.n_solves:.1f}"
            else:
                same, ratio = "-", "-"
            rows.append((w, p, obj, txt["pattern"], txt["gradient"], same, ratio))
table(["Omega_bar", "preset", "objective", "pattern search (paper's method)", "gradient method",
       "same objective value (0.5 %)", "solves pattern / gradient"], rows)
'''),
    code(END),
]


def main() -> None:
    for name, cells in NOTEBOOKS.items():
        nb = new_notebook(cells=cells, metadata={
            "kernelspec": {"name": "python3", "display_name": "Python 3", "language": "python"},
            "language_info": {"name": "python"}})
        for k, cell in enumerate(nb.cells):  # fixed ids: rewriting a notebook changes only what its sources change
            cell.id = f"{name[:48]}-{k}"
        nbformat.validate(nb)
        path = HERE / f"{name}.ipynb"
        nbformat.write(nb, path)
        print("wrote", path)


if __name__ == "__main__":
    main()
