"""Figures of continuation branches (:class:`gfbjax.cont.Branch`): the bifurcation diagram of limit cycles (max and
min of the journal displacements against speed, stable solid / unstable dashed, special points marked), the
Floquet multipliers in the complex plane with the unit circle, and the equilibrium branch of the balanced rotor
(journal position and critical eigenvalue real part against speed), the energy flow of cycle branches and the
optimised foil schedules of :func:`gfbjax.design.schedule.optimized_continuation`."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ._common import axes_grid, colours, finish, labelled, rpm_axis, rpm_factor

__all__ = ["plot_bifurcation", "plot_multipliers", "plot_equilibria", "plot_energy", "plot_schedule",
           "SPECIAL_STYLE"]

# marker, colour of each special-point type
SPECIAL_STYLE = {"NS": ("D", "tab:purple"), "PD": ("s", "tab:orange"), "LPC": ("^", "tab:green"),
                 "HOPF": ("*", "tab:red"), "FOLD": ("^", "tab:green"), "BP": ("o", "k")}

#: What the branch figures take for ``branch``: one :class:`gfbjax.cont.Branch`, a ``{label: Branch}`` dict or a
#: sequence of ``(label, Branch)`` pairs.  Several branches are overlaid in the same axes, one colour each, with
#: their labels in the legend (line style still marks stability: solid stable, dashed unstable).
Branches = Any


def _is_branch(obj: Any) -> bool:
    return hasattr(obj, "lam") and hasattr(obj, "stable")


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


def _stability_lines(ax, x: np.ndarray, y: np.ndarray, stable: np.ndarray, colour, label_stable: str | None = None,
                     label_unstable: str | None = None, lw: tuple[float, float] = (1.6, 1.2)) -> None:
    """(x, y) solid where stable and dashed where unstable; each label on the first piece of its kind."""
    for i, (xs, ys) in enumerate(_segments(x, y, stable)):
        ax.plot(xs, ys, "-", color=colour, lw=lw[0], label=label_stable if i == 0 else None)
    for i, (xs, ys) in enumerate(_segments(x, y, ~stable)):
        ax.plot(xs, ys, "--", color=colour, lw=lw[1], label=label_unstable if i == 0 else None)


def _overlay_legend(ax, label: str | None, colour) -> None:
    """Legend entry of one overlaid branch (a solid line in its colour)."""
    ax.plot([], [], "-", color=colour, lw=1.6, label=label)


def _style_legend(ax) -> None:
    """Legend entries for the line styles of overlaid branches."""
    ax.plot([], [], "-", color="0.4", lw=1.4, label="stable")
    ax.plot([], [], "--", color="0.4", lw=1.2, label="unstable")


def _end_label(ax, x: np.ndarray, y: np.ndarray, text: str, colour) -> None:
    """Name a curve at its last point (overlays, where colour tells the branch rather than the quantity)."""
    if len(x):
        ax.annotate(text, (float(x[-1]), float(y[-1])), textcoords="offset points", xytext=(3, 0), fontsize=8,
                    color=colour, va="center")


def _mark_special(ax, s: Any, ys: Sequence[float], label: str | None = None, ms: float = 8) -> None:
    """Markers of a special point at (s.lam, y) for each y: filled when located, hollow when only bracketed."""
    mk, colour = SPECIAL_STYLE.get(s.type, ("o", "k"))
    for y in ys:
        ax.plot(s.lam, y, mk, color=colour, ms=ms, mec="k", mfc=colour if s.located else "none", label=label,
                zorder=5)
        label = None


def _label_inside(ax: Any, text: str, x: float, y: float, color: Any, dy: float = 8) -> None:
    """Label a point on the side that faces the middle of what is drawn so far: a special point in the right
    fifth of the speed range (where a branch run downwards in speed often has its Neimark-Sacker point) is
    labelled to its left, so that the text is not cut off by the axes' edge."""
    x0, x1 = ax.dataLim.intervalx
    left = bool(np.isfinite(x0) and np.isfinite(x1) and x1 > x0 and x > x0 + 0.8 * (x1 - x0))
    ax.annotate(text, (x, y), textcoords="offset points", xytext=(-6 if left else 6, dy), fontsize=8, color=color,
                ha="right" if left else "left")


def _special_text(s: Any) -> str:
    # the estimated error where it reaches the printed digits: a location is no more certain than that
    err = getattr(s, "lam_error", math.nan)
    tail = f" +- {err:.1e}" if np.isfinite(err) and err >= 5e-5 else ""
    return f"{s.type}{'' if s.located else '?'} {s.lam:.4f}{tail}"


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


def plot_bifurcation(branch: Branches, *, names: Sequence[str] = ("x_j", "y_j"), columns: Sequence[int] = (0, 1),
                     c_um: float | None = None, title: str | None = None, path: str | Path | None = None,
                     ax: Any = None, spec: Any = None, rpm_per_omega_bar: float | None = None):
    """Bifurcation diagram of a cycle branch: max and min over the cycle of the journal vertical (top) and
    horizontal (bottom) displacement against Omega_bar; stable solid, unstable dashed; special points marked
    (located filled, only bracketed hollow with a "?"), points with a doubtful stability label
    (``branch.flagged``) as grey crosses.

    ``branch``: one :class:`gfbjax.cont.Branch` (max red, min blue), or several as a ``{label: Branch}`` dict or
    ``(label, Branch)`` pairs, overlaid with one colour per branch (its max and min) and its label in the legend.
    ``columns`` are the columns of ``branch.xmax`` holding ``names`` (the recorded rotor components are
    x_j, y_j[, x_d, y_d]).  ``ax``: None (a new figure) or 2 Axes (vertical, horizontal panel) to draw into; then
    their figure is returned and gets a suptitle only when ``title`` is given.  A secondary speed axis in rpm is
    drawn on top when the conversion is known: ``rpm_per_omega_bar``, a ``spec`` (SystemSpec), or the branch's
    ``meta["rpm_per_omega_bar"]``."""
    items, several = labelled(branch, _is_branch)
    col_of = dict(zip(names, columns))
    panels = [("y_j", "vertical $y_j/c$"), ("x_j", "horizontal $x_j/c$")]
    fig, axes, new = axes_grid(ax, 2, 1, figsize=(8, 7), sharex=True)
    axes = axes[:, 0]
    for a, (name, label) in zip(axes, panels):
        k = col_of[name]
        seen: set[str] = set()
        for (blabel, b), colour in zip(items, colours(len(items))):
            lam = np.asarray(b.lam, float)
            stable = np.asarray(b.stable, bool)
            for arr, c, ext in ((b.xmax, colour if several else "tab:red", "max"),
                                (b.xmin, colour if several else "tab:blue", "min")):
                _stability_lines(a, lam, np.asarray(arr, float)[:, k], stable, c,
                                 None if several else f"{ext} (stable)", None if several else f"{ext} (unstable)")
            if several:
                _overlay_legend(a, blabel, colour)
            flagged = np.asarray(b.flagged, bool)
            if flagged.any():  # accuracy (trivial multiplier, mesh, multipliers) or film in doubt
                key = "flagged (accuracy or contact)"
                a.plot(lam[flagged], np.asarray(b.xmax, float)[flagged, k], "x", color="0.4", ms=6, zorder=4,
                       label=key if key not in seen else None)
                seen.add(key)
            for s, row in _special_rows(b):
                if row is None:
                    continue
                key = s.type if s.located else f"{s.type} (not located)"
                ys = [float(np.asarray(arr)[row, k]) for arr in (b.xmax, b.xmin)]
                _mark_special(a, s, ys, label=key if key not in seen else None)
                seen.add(key)
                _label_inside(a, _special_text(s), s.lam, ys[0], SPECIAL_STYLE.get(s.type, ("o", "k"))[1])
        a.set_ylabel(label + (f"  (c = {c_um:.1f} um)" if c_um else ""))
        a.grid(alpha=0.3)
    if several:
        _style_legend(axes[0])
    axes[0].legend(loc="best", fontsize=7, ncol=2)
    axes[1].set_xlabel(r"speed $\bar\Omega$")
    rpm_axis(axes[0], rpm_factor(rpm_per_omega_bar, spec, [b for _, b in items]))
    return finish(fig, path, new=new, title=title, default="Limit cycles: bifurcation diagram", tight=True, dpi=130)


def plot_multipliers(branch: Branches, *, n_show: int | None = 8, title: str | None = None,
                     path: str | Path | None = None, ax: Any = None):
    """Floquet multipliers of every point of a cycle branch in the complex plane with the unit circle, coloured
    by Omega_bar (with a colour bar); the multipliers of the special points are ringed.  ``n_show``: the largest
    in modulus per point (None: all).

    ``branch``: one :class:`gfbjax.cont.Branch`, or several as a ``{label: Branch}`` dict or ``(label, Branch)``
    pairs: then each branch's multipliers get one colour and its label in the legend (no speed colour bar).
    ``ax``: None (a new figure) or one Axes to draw into (its figure is returned); ``title`` is the axes title."""
    items, several = labelled(branch, _is_branch)
    fig, axes, new = axes_grid(ax, 1, 1, figsize=(6.8, 6))
    a = axes[0, 0]
    th = np.linspace(0, 2 * np.pi, 400)
    a.plot(np.cos(th), np.sin(th), "k-", lw=0.8, label="unit circle")
    for (blabel, b), colour in zip(items, colours(len(items))):
        lam = np.asarray(b.lam, float)
        mu = np.asarray(b.multipliers)
        if n_show is not None:
            mu = mu[:, :n_show]
        if mu.size and several:
            a.scatter(mu.real.ravel(), mu.imag.ravel(), s=9, color=colour, label=blabel)
        elif mu.size:
            cc = np.repeat(lam[:, None], mu.shape[1], axis=1)
            sc = a.scatter(mu.real.ravel(), mu.imag.ravel(), c=cc.ravel(), s=9, cmap="viridis")
            fig.colorbar(sc, ax=a, label=r"speed $\bar\Omega$")
        for s in b.special:
            m = s.spectrum
            if m is None:
                continue
            m = np.asarray(m)
            if m.ndim == 2:  # [re, im] pairs from JSON
                m = m[:, 0] + 1j * m[:, 1]
            m = m[:n_show] if n_show is not None else m
            _, c = SPECIAL_STYLE.get(s.type, ("o", "k"))
            a.scatter(m.real, m.imag, s=70, facecolors="none", edgecolors=c, lw=1.5,
                      label=(f"{blabel}: " if several else "") + f"{s.type} at {s.lam:.4f}")
    a.set_aspect("equal", adjustable="datalim")
    a.set_xlabel(r"Re $\mu$")
    a.set_ylabel(r"Im $\mu$")
    a.grid(alpha=0.3)
    a.legend(loc="upper left", fontsize=7)
    a.set_title(title or "Floquet multipliers")
    return finish(fig, path, new=new, title=None, tight=True, dpi=130)


def critical_real_part(branch: Any) -> np.ndarray:
    """Largest real part of the eigenvalues at each point of an equilibrium branch."""
    ev = np.asarray(branch.multipliers)
    return ev.real.max(axis=1) if ev.size else np.zeros(0)


def plot_equilibria(branch: Branches, *, names: Sequence[str] = ("x_j", "y_j"), columns: Sequence[int] = (0, 1),
                    title: str | None = None, path: str | Path | None = None, ax: Any = None, spec: Any = None,
                    rpm_per_omega_bar: float | None = None):
    """Equilibrium branch of the balanced rotor: journal position (x_j, y_j over c; top) and the real part of the
    critical eigenvalue (bottom) against Omega_bar (stable solid, unstable dashed), Hopf and fold points marked
    (located filled, only bracketed hollow with a "?").

    ``branch``: one :class:`gfbjax.cont.Branch` (x_j blue, y_j red), or several as a ``{label: Branch}`` dict or
    ``(label, Branch)`` pairs, overlaid with one colour per branch and its label in the legend (the components
    are then named at the end of their lines).  ``ax``: None (a new figure) or 2 Axes (position, eigenvalue) to
    draw into; then their figure is returned and gets a suptitle only when ``title`` is given.  Secondary rpm axis
    on top as in :func:`plot_bifurcation` (``spec``, ``rpm_per_omega_bar`` or the branch's meta)."""
    items, several = labelled(branch, _is_branch)
    fig, axes, new = axes_grid(ax, 2, 1, figsize=(8, 7), sharex=True)
    axes = axes[:, 0]
    for (blabel, b), colour in zip(items, colours(len(items))):
        lam = np.asarray(b.lam, float)
        stable = np.asarray(b.stable, bool)
        for name, k, c in zip(names, columns, (colour, colour) if several else ("tab:blue", "tab:red")):
            v = np.asarray(b.xmax, float)[:, k]
            if several:
                _stability_lines(axes[0], lam, v, stable, c)
                _end_label(axes[0], lam, v, f"${name[0]}_j$", c)
            else:
                _stability_lines(axes[0], lam, v, stable, c, f"${name[0]}_j/c$ (stable)", f"${name[0]}_j/c$ (unstable)")
        if several:
            _overlay_legend(axes[0], blabel, colour)
        re = critical_real_part(b)
        axes[1].plot(lam, re, "-", color=colour if several else "k", lw=1.4,
                     label=blabel if several else r"max Re $\lambda$")
        for s, row in _special_rows(b):
            if row is None:
                continue
            lab = (f"{blabel}: " if several else "") + _special_text(s)
            _mark_special(axes[0], s, [float(np.asarray(b.xmax)[row, k]) for k in columns], ms=10)
            _label_inside(axes[0], _special_text(s), s.lam, float(np.asarray(b.xmax)[row, columns[-1]]),
                          SPECIAL_STYLE.get(s.type, ("o", "k"))[1])
            _mark_special(axes[1], s, [float(re[row])], label=lab, ms=10)
    if several:
        _style_legend(axes[0])
    axes[1].axhline(0.0, color="0.5", lw=0.8)
    axes[0].set_ylabel("journal position over c")
    axes[1].set_ylabel(r"critical eigenvalue Re $\lambda$ (per $\tau$)")
    axes[1].set_xlabel(r"speed $\bar\Omega$")
    for a in axes:
        a.grid(alpha=0.3)
        a.legend(loc="best", fontsize=7)
    rpm_axis(axes[0], rpm_factor(rpm_per_omega_bar, spec, [b for _, b in items]))
    return finish(fig, path, new=new, title=title, default="Equilibria of the balanced rotor", tight=True, dpi=130)


_ENERGY_STYLE = {"W_fu": ("$W_{fu}$", "k"), "W_cf": ("$W_{cf}$", "tab:green"), "W_cb": ("$W_{cb}$", "tab:red")}


def plot_energy(branches: Any, *, overlay: bool = False, quantities: Sequence[str] = ("W_fu", "W_cf", "W_cb"),
                title: str | None = None, path: str | Path | None = None, ax: Any = None, spec: Any = None,
                rpm_per_omega_bar: float | None = None):
    """Energy flow along cycle branches (paper Fig. 12): W_fu, W_cf and W_cb [p0 R L c] against Omega_bar, one
    panel per design; stable solid, unstable dashed; NS points and the sign changes of W_cb marked.

    ``branches``: ``(label, branch, energy)`` triples, a ``{label: (branch, energy)}`` dict, or one
    ``(branch, energy)`` pair, with ``energy`` the :class:`gfbjax.analyses.energy.CycleEnergy` of the branch's
    points.  ``overlay``: all designs in one panel, one colour per design with its label in the legend (each
    curve named at its end) instead of one panel each.  ``quantities``: which of W_fu, W_cf, W_cb to draw.
    ``ax``: None (a new figure: panels in two columns) or one Axes per panel (one per design, or one with
    ``overlay``) to draw into; then their figure is returned and gets a suptitle only when ``title`` is given.
    Secondary rpm axis on top of each panel as in :func:`plot_bifurcation`."""
    from ..analyses.energy import sign_changes

    items, _ = labelled(branches, lambda o: isinstance(o, tuple) and len(o) == 2 and _is_branch(o[0]))
    unknown = set(quantities) - set(_ENERGY_STYLE)
    if unknown:
        raise ValueError(f"quantities: unknown {sorted(unknown)}; choose from {list(_ENERGY_STYLE)}")
    k = 1 if overlay else len(items)
    ncol = 2 if k > 1 else 1
    nrow = (k + ncol - 1) // ncol
    if ax is None:
        fig, axes, new = axes_grid(None, nrow, ncol, figsize=(6.5 * ncol, 4.2 * nrow))
    else:
        fig, axes, new = axes_grid(ax, 1, k)
    panels = list(axes.ravel())
    for i, ((label, (b, E)), colour) in enumerate(zip(items, colours(len(items)))):
        a = panels[0 if overlay else i]
        lam = np.asarray(b.lam, float)
        stable = np.asarray(b.stable, bool)
        for q in quantities:
            name, c = _ENERGY_STYLE[q]
            W = np.asarray(getattr(E, q), float)
            _stability_lines(a, lam, W, stable, colour if overlay else c, None if overlay else name, lw=(1.6, 1.1))
            if overlay:
                _end_label(a, lam, W, name, colour)
        if overlay:
            _overlay_legend(a, label, colour)
        for s in b.special_of("NS"):
            a.axvline(s.lam, color=SPECIAL_STYLE["NS"][1], ls=":", lw=1.2)
            _label_inside(a, f"NS {s.lam:.4f}", s.lam, 0.0, SPECIAL_STYLE["NS"][1], dy=10)
        for c in sign_changes(lam, E.W_cb):
            a.plot(c["Omega_bar"], 0.0, "o", mfc="none", mec=colour if overlay else "tab:red", ms=8)
        if not overlay:
            a.set_title(label or "", fontsize=10)
    factor = rpm_factor(rpm_per_omega_bar, spec, [b for _, (b, _E) in items])
    for a in panels[:k]:
        rpm_axis(a, factor)
        if overlay:
            _style_legend(a)
        a.axhline(0.0, color="0.5", lw=0.6)
        a.set_xlabel(r"speed $\bar\Omega$")
        a.set_ylabel(r"work per cycle [$p_0 R L c$]")
        a.grid(alpha=0.3)
        a.legend(fontsize=8, loc="best")
    for a in panels[k:]:
        a.set_visible(False)
    return finish(fig, path, new=new, title=title, tight=True, dpi=130,
                  default="Energy flow of the limit cycles (solid stable, dashed unstable; o: W_cb = 0)")


def plot_schedule(schedules: Any, *, n_show: int | None = 8, title: str | None = None,
                  path: str | Path | None = None, ax: Any = None, spec: Any = None,
                  rpm_per_omega_bar: float | None = None):
    """Optimised foil schedules along the speed (paper Figs. 16-19), one line (colour) per schedule:

    a) journal orbit extent, the max and min over the cycle of y_j (solid) and x_j (dotted) [c];
    b) the optimum alpha_f and c) eta (log scale, the bounds of :data:`gfbjax.design.evaluate.FOIL_BOUNDS` dotted);
    d) the largest non-trivial Floquet multiplier modulus with the stability limit |mu| = 1;
    e) W_cb [p0 R L c], the net gas-film dissipation per cycle;
    f) the ``n_show`` largest multipliers of every speed in the complex plane with the unit circle.

    Unstable optimised cycles (where a march ends) are marked with a cross.  ``schedules``: (label,
    :class:`gfbjax.design.schedule.Schedule`) pairs, a ``{label: Schedule}`` dict or one Schedule.  ``ax``: None
    (a new figure) or 6 Axes (a-f, a 3 x 2 layout in row-major order) to draw into; then their figure is returned
    and gets a suptitle only when ``title`` is given.  With ``spec`` or ``rpm_per_omega_bar`` the speed panels
    get a secondary rpm axis on top."""
    from ..design.evaluate import FOIL_BOUNDS

    items, _ = labelled(schedules, lambda o: hasattr(o, "alpha_f") and hasattr(o, "omega"))
    fig, axes, new = axes_grid(ax, 3, 2, figsize=(12, 11.5))
    ax_j, ax_a, ax_e, ax_mu, ax_w, ax_c = axes.ravel()
    th = np.linspace(0, 2 * np.pi, 400)
    ax_c.plot(np.cos(th), np.sin(th), "k-", lw=0.8, label="unit circle")
    ax_mu.axhline(1.0, color="k", ls="--", lw=0.9, label=r"$|\mu| = 1$")
    ax_w.axhline(0.0, color="0.5", lw=0.6)
    for ax, name in ((ax_a, "alpha_f"), (ax_e, "eta")):
        for v in FOIL_BOUNDS[name]:
            ax.axhline(v, color="0.5", ls=":", lw=0.9)
    any_unstable = False
    for (label, s), colour in zip(items, colours(len(items))):
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
            line(ax_j, jmax[:, k], ls, f"{label}: ${name}_j$" if label else f"${name}_j$")
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
    factor = rpm_factor(rpm_per_omega_bar, spec)
    for ax, head, ylabel in panels:
        rpm_axis(ax, factor)
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
    return finish(fig, path, new=new, title=title, tight=True, dpi=130,
                  default="Optimised foil along the speed (x: unstable optimised cycle)")
