"""Figures of continuation branches (:class:`gfbjax.cont.Branch`): the bifurcation diagram of limit cycles (max and
min of the journal displacements against speed, stable solid / unstable dashed, special points marked), the
Floquet multipliers in the complex plane with the unit circle, and the equilibrium branch of the balanced rotor
(journal position and critical eigenvalue real part against speed), the energy flow of cycle branches and the
optimised foil schedules of :func:`gfbjax.design.schedule.optimized_continuation`."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np

__all__ = ["plot_bifurcation", "plot_multipliers", "plot_equilibria", "plot_energy", "plot_schedule",
           "SPECIAL_STYLE"]

# marker, colour of each special-point type
SPECIAL_STYLE = {"NS": ("D", "tab:purple"), "PD": ("s", "tab:orange"), "LPC": ("^", "tab:green"),
                 "HOPF": ("*", "tab:red"), "FOLD": ("^", "tab:green"), "BP": ("o", "k")}


def _save(fig, path):
    if path is not None:
        fig.savefig(Path(path), dpi=130, bbox_inches="tight")
    return fig


def _segments(x: np.ndarray, y: np.ndarray, mask: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Runs of consecutive points where ``mask`` holds, each extended by one point on either side so that stable
    and unstable pieces join."""
    out = []
    n = len(x)
    i = 0
    while i < n:
        if mask[i]:
            j = i
            while j + 1 < n and mask[j + 1]:
                j += 1
            a, b = max(i - 1, 0), min(j + 1, n - 1)
            out.append((x[a:b + 1], y[a:b + 1]))
            i = j + 1
        else:
            i += 1
    return out


def _special_rows(branch: Any) -> list[tuple[dict, int | None]]:
    """Each special point with the row of the branch arrays it sits on (None when not stored)."""
    rows = []
    for s in branch.special:
        idx = s.index
        row = None
        if idx is not None and 0 <= int(idx) < len(branch.lam):
            row = int(idx)
            if not s.located or abs(float(branch.lam[row]) - s.lam) > 1e-9:
                # not inserted: the nearest point in speed
                row = int(np.argmin(np.abs(np.asarray(branch.lam) - s.lam)))
        elif len(branch.lam):
            row = int(np.argmin(np.abs(np.asarray(branch.lam) - s.lam)))
        rows.append((s, row))
    return rows


def plot_bifurcation(branch: Any, *, names: Sequence[str] = ("x_j", "y_j"), columns: Sequence[int] = (0, 1),
                     c_um: float | None = None, title: str | None = None, path: str | Path | None = None):
    """Bifurcation diagram of a cycle branch: max and min over the cycle of the journal vertical (top) and
    horizontal (bottom) displacement against Omega_bar; stable solid, unstable dashed; special points marked.

    ``columns`` are the columns of ``branch.xmax`` holding ``names`` (the recorded rotor components are
    x_j, y_j[, x_d, y_d])."""
    import matplotlib.pyplot as plt

    lam = np.asarray(branch.lam, float)
    order = np.arange(len(lam))  # keep the branch order (folds)
    stable = np.asarray(branch.stable, bool)
    col_of = dict(zip(names, columns))
    panels = [("y_j", "vertical $y_j/c$"), ("x_j", "horizontal $x_j/c$")]
    fig, axes = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    rows = _special_rows(branch)
    for ax, (name, label) in zip(axes, panels):
        k = col_of[name]
        for arr, colour, ext in ((branch.xmax, "tab:red", "max"), (branch.xmin, "tab:blue", "min")):
            v = np.asarray(arr, float)[order, k]
            first = True
            for xs, ys in _segments(lam, v, stable):
                ax.plot(xs, ys, "-", color=colour, lw=1.6, label=f"{ext} (stable)" if first else None)
                first = False
            first = True
            for xs, ys in _segments(lam, v, ~stable):
                ax.plot(xs, ys, "--", color=colour, lw=1.2, label=f"{ext} (unstable)" if first else None)
                first = False
        flagged = np.asarray(branch.flagged, bool)
        if flagged.any():  # stability labels that the trivial multiplier's error does not support
            k_arr = np.asarray(branch.xmax, float)[:, k]
            ax.plot(lam[flagged], k_arr[flagged], "x", color="0.4", ms=6, zorder=4,
                    label="inaccurate (trivial multiplier)")
        seen = set()
        for s, row in rows:
            if row is None:
                continue
            mk, colour = SPECIAL_STYLE.get(s.type, ("o", "k"))
            # an unlocated point is only bracketed between two rows: hollow marker, "?" in the label
            key = s.type if s.located else f"{s.type} (not located)"
            for arr in (branch.xmax, branch.xmin):
                ax.plot(s.lam, float(np.asarray(arr)[row, k]), mk, color=colour, ms=8, mec="k",
                        mfc=colour if s.located else "none", label=key if key not in seen else None, zorder=5)
                seen.add(key)
            ax.annotate(f"{s.type}{'' if s.located else '?'} {s.lam:.4f}",
                        (s.lam, float(np.asarray(branch.xmax)[row, k])),
                        textcoords="offset points", xytext=(6, 8), fontsize=8, color=colour)
        ax.set_ylabel(label + (f"  (c = {c_um:.1f} um)" if c_um else ""))
        ax.grid(alpha=0.3)
    axes[0].legend(loc="best", fontsize=7, ncol=2)
    axes[1].set_xlabel(r"speed $\bar\Omega$")
    fig.suptitle(title or "Limit cycles: bifurcation diagram")
    fig.tight_layout()
    return _save(fig, path)


def plot_multipliers(branch: Any, *, n_show: int | None = 8, title: str | None = None,
                     path: str | Path | None = None):
    """Floquet multipliers of every point of a cycle branch in the complex plane with the unit circle, coloured
    by Omega_bar; the multipliers of the special points are ringed.  ``n_show``: the largest in modulus per point
    (None: all)."""
    import matplotlib.pyplot as plt

    lam = np.asarray(branch.lam, float)
    mu = np.asarray(branch.multipliers)
    if n_show is not None:
        mu = mu[:, :n_show]
    fig, ax = plt.subplots(figsize=(6.8, 6))
    th = np.linspace(0, 2 * np.pi, 400)
    ax.plot(np.cos(th), np.sin(th), "k-", lw=0.8, label="unit circle")
    if mu.size:
        cc = np.repeat(lam[:, None], mu.shape[1], axis=1)
        sc = ax.scatter(mu.real.ravel(), mu.imag.ravel(), c=cc.ravel(), s=9, cmap="viridis")
        fig.colorbar(sc, ax=ax, label=r"speed $\bar\Omega$")
    for s in branch.special:
        m = s.spectrum
        if m is None:
            continue
        m = np.asarray(m)
        if m.ndim == 2:  # [re, im] pairs from JSON
            m = m[:, 0] + 1j * m[:, 1]
        m = m[:n_show] if n_show is not None else m
        _, colour = SPECIAL_STYLE.get(s.type, ("o", "k"))
        ax.scatter(m.real, m.imag, s=70, facecolors="none", edgecolors=colour, lw=1.5,
                   label=f"{s.type} at {s.lam:.4f}")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(r"Re $\mu$")
    ax.set_ylabel(r"Im $\mu$")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=7)
    ax.set_title(title or "Floquet multipliers")
    fig.tight_layout()
    return _save(fig, path)


def critical_real_part(branch: Any) -> np.ndarray:
    """Largest real part of the eigenvalues at each point of an equilibrium branch."""
    ev = np.asarray(branch.multipliers)
    return ev.real.max(axis=1) if ev.size else np.zeros(0)


def plot_equilibria(branch: Any, *, names: Sequence[str] = ("x_j", "y_j"), columns: Sequence[int] = (0, 1),
                    title: str | None = None, path: str | Path | None = None):
    """Equilibrium branch of the balanced rotor: journal position (x_j, y_j over c) and the real part of the
    critical eigenvalue against Omega_bar (stable solid, unstable dashed), Hopf and fold points marked."""
    import matplotlib.pyplot as plt

    lam = np.asarray(branch.lam, float)
    stable = np.asarray(branch.stable, bool)
    fig, axes = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    colours = ("tab:blue", "tab:red")
    for name, k, colour in zip(names, columns, colours):
        v = np.asarray(branch.xmax, float)[:, k]
        for i, (xs, ys) in enumerate(_segments(lam, v, stable)):
            axes[0].plot(xs, ys, "-", color=colour, lw=1.6, label=f"${name[0]}_j/c$ (stable)" if i == 0 else None)
        for i, (xs, ys) in enumerate(_segments(lam, v, ~stable)):
            axes[0].plot(xs, ys, "--", color=colour, lw=1.2, label=f"${name[0]}_j/c$ (unstable)" if i == 0 else None)
    re = critical_real_part(branch)
    axes[1].plot(lam, re, "-", color="k", lw=1.4, label=r"max Re $\lambda$")
    axes[1].axhline(0.0, color="0.5", lw=0.8)
    for s, row in _special_rows(branch):
        if row is None:
            continue
        mk, colour = SPECIAL_STYLE.get(s.type, ("o", "k"))
        lab = f"{s.type} {s.lam:.4f}"
        for name, k in zip(names, columns):
            axes[0].plot(s.lam, float(np.asarray(branch.xmax)[row, k]), mk, color=colour, ms=10, mec="k")
        axes[0].annotate(lab, (s.lam, float(np.asarray(branch.xmax)[row, columns[-1]])),
                         textcoords="offset points", xytext=(6, 8), fontsize=8, color=colour)
        axes[1].plot(s.lam, float(re[row]), mk, color=colour, ms=10, mec="k", label=lab)
    axes[0].set_ylabel("journal position over c")
    axes[1].set_ylabel(r"critical eigenvalue Re $\lambda$ (per $\tau$)")
    axes[1].set_xlabel(r"speed $\bar\Omega$")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=7)
    fig.suptitle(title or "Equilibria of the balanced rotor")
    fig.tight_layout()
    return _save(fig, path)


def plot_energy(branches: Sequence[tuple[str, Any, Any]], *, title: str | None = None,
                path: str | Path | None = None):
    """Energy flow along cycle branches (paper Fig. 12): W_fu, W_cf and W_cb [p0 R L c] against Omega_bar, one
    panel per design; stable solid, unstable dashed; NS points and the sign changes of W_cb marked.

    ``branches``: (label, branch, :class:`gfbjax.analyses.energy.CycleEnergy` of its points) per design."""
    import matplotlib.pyplot as plt

    from ..analyses.energy import sign_changes

    k = len(branches)
    ncol = 2 if k > 1 else 1
    nrow = (k + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(6.5 * ncol, 4.2 * nrow), squeeze=False)
    for ax, (label, b, E) in zip(axes.ravel(), branches):
        lam = np.asarray(b.lam, float)
        stable = np.asarray(b.stable, bool)
        for W, name, colour in ((E.W_fu, "$W_{fu}$", "k"), (E.W_cf, "$W_{cf}$", "tab:green"),
                                (E.W_cb, "$W_{cb}$", "tab:red")):
            W = np.asarray(W, float)
            for i, (xs, ys) in enumerate(_segments(lam, W, stable)):
                ax.plot(xs, ys, "-", color=colour, lw=1.6, label=name if i == 0 else None)
            for xs, ys in _segments(lam, W, ~stable):
                ax.plot(xs, ys, "--", color=colour, lw=1.1)
        for s in b.special_of("NS"):
            ax.axvline(s.lam, color=SPECIAL_STYLE["NS"][1], ls=":", lw=1.2)
            ax.annotate(f"NS {s.lam:.4f}", (s.lam, 0.0), textcoords="offset points",
                        xytext=(4, 10), fontsize=8, color=SPECIAL_STYLE["NS"][1])
        for c in sign_changes(lam, E.W_cb):
            ax.plot(c["Omega_bar"], 0.0, "o", mfc="none", mec="tab:red", ms=8)
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_title(label, fontsize=10)
        ax.set_xlabel(r"speed $\bar\Omega$")
        ax.set_ylabel(r"work per cycle [$p_0 R L c$]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    for ax in axes.ravel()[k:]:
        ax.set_visible(False)
    fig.suptitle(title or "Energy flow of the limit cycles (solid stable, dashed unstable; o: W_cb = 0)")
    fig.tight_layout()
    return _save(fig, path)


def plot_schedule(schedules: Sequence[tuple[str, Any]], *, n_show: int | None = 8, title: str | None = None,
                  path: str | Path | None = None):
    """Optimised foil schedules along the speed (paper Figs. 16-19), one line (colour) per schedule:

    a) journal orbit extent, the max and min over the cycle of y_j (solid) and x_j (dotted) [c];
    b) the optimum alpha_f and c) eta (log scale, the bounds of :data:`gfbjax.design.evaluate.FOIL_BOUNDS` dotted);
    d) the largest non-trivial Floquet multiplier modulus with the stability limit |mu| = 1;
    e) W_cb [p0 R L c], the net gas-film dissipation per cycle;
    f) the ``n_show`` largest multipliers of every speed in the complex plane with the unit circle.

    Unstable optimised cycles (where a march ends) are marked with a cross.  ``schedules``: (label,
    :class:`gfbjax.design.schedule.Schedule`) pairs."""
    import matplotlib.pyplot as plt

    from ..design.evaluate import FOIL_BOUNDS

    fig, axes = plt.subplots(3, 2, figsize=(12, 11.5))
    ax_j, ax_a, ax_e, ax_mu, ax_w, ax_c = axes.ravel()
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    th = np.linspace(0, 2 * np.pi, 400)
    ax_c.plot(np.cos(th), np.sin(th), "k-", lw=0.8, label="unit circle")
    ax_mu.axhline(1.0, color="k", ls="--", lw=0.9, label=r"$|\mu| = 1$")
    ax_w.axhline(0.0, color="0.5", lw=0.6)
    for ax, name in ((ax_a, "alpha_f"), (ax_e, "eta")):
        for v in FOIL_BOUNDS[name]:
            ax.axhline(v, color="0.5", ls=":", lw=0.9)
    any_unstable = False
    for i, (label, s) in enumerate(schedules):
        colour = colours[i % len(colours)]
        w = np.asarray(s.omega, float)
        if w.size == 0:
            continue
        bad = ~np.asarray(s.stable, bool)
        any_unstable |= bool(bad.any())

        def line(ax, y, ls="-", lab=label, mark=True):
            y = np.asarray(y, float)
            ax.plot(w, y, ls, color=colour, marker="o", ms=3, lw=1.5, label=lab)
            if mark and bad.any():
                ax.plot(w[bad], y[bad], "x", color=colour, ms=10, mew=2)

        jmax = np.asarray(s.journal_max, float).reshape(len(w), -1)
        jmin = np.asarray(s.journal_min, float).reshape(len(w), -1)
        for k, (name, ls) in ((1, ("y", "-")), (0, ("x", ":"))):
            line(ax_j, jmax[:, k], ls, f"{label}: ${name}_j$")
            line(ax_j, jmin[:, k], ls, None)
        line(ax_a, s.alpha_f)
        line(ax_e, s.eta)
        line(ax_mu, s.max_mu)
        line(ax_w, s.W_cb)
        for j, mu in enumerate(s.multipliers):
            mu = np.asarray(mu, complex)[:n_show] if n_show is not None else np.asarray(mu, complex)
            ax_c.scatter(mu.real, mu.imag, s=40 if bad[j] else 10, marker="x" if bad[j] else "o", color=colour,
                         label=label if j == 0 else None)
    panels = ((ax_j, "a) journal orbit: max / min over the cycle", r"$x_j/c$, $y_j/c$"),
              (ax_a, r"b) foil compliance $\alpha_f$", r"$\alpha_f$"),
              (ax_e, r"c) foil loss factor $\eta$", r"$\eta$"),
              (ax_mu, r"d) largest non-trivial Floquet multiplier", r"max $|\mu|$"),
              (ax_w, r"e) gas-film dissipation per cycle $W_{cb}$", r"$W_{cb}$ [$p_0 R L c$]"))
    for ax, head, ylabel in panels:
        ax.set_title(head, fontsize=10)
        ax.set_xlabel(r"speed $\bar\Omega$")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
    ax_a.set_yscale("log")
    ax_e.set_yscale("log")
    if any_unstable:
        ax_mu.plot([], [], "x", color="k", ms=10, mew=2, label="unstable")
    ax_c.set_aspect("equal", adjustable="datalim")
    ax_c.set_title("f) Floquet multipliers" + (f" ({n_show} largest per speed)" if n_show is not None else ""),
                   fontsize=10)
    ax_c.set_xlabel(r"Re $\mu$")
    ax_c.set_ylabel(r"Im $\mu$")
    ax_c.grid(alpha=0.3)
    for ax in axes.ravel():
        if ax.get_legend_handles_labels()[1]:
            ax.legend(fontsize=7, loc="best")
    fig.suptitle(title or "Optimised foil along the speed (x: unstable optimised cycle)")
    fig.tight_layout()
    return _save(fig, path)
