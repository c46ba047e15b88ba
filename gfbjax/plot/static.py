"""Matplotlib figures of gfbjax results.

Every function returns the :class:`matplotlib.figure.Figure` and, given ``path``, also saves it (the format follows
the file suffix, e.g. ``.png`` or ``.pdf``).  Given ``ax`` (the Axes of an existing figure, as many as the figure
has panels, in row-major order), a function draws into them and returns their figure instead of making one.
Figures are made with ``pyplot`` so that they show inline in notebooks; scripts that make many figures should
``plt.close(fig)`` after saving.  Importing this module leaves the matplotlib backend as it is (matplotlib itself
falls back to the non-interactive Agg backend without a display; the ``gfbjax`` command line selects Agg
explicitly).

Conventions (docs/model.md): lengths over the radial clearance ``c``, pressures over ambient ``p0``, time over
``t* = 6 mu R^2 / (p0 c^2)``; y points up, gravity and the extra load act downwards; theta is measured from the
horizontal x axis towards y, in the direction of rotation; the foil is clamped at ``theta0`` (default 90 deg, top).

Figures:

* :func:`plot_load_displacement` — paper Fig. 4: vertical journal displacement against specific load.
* :func:`plot_equilibrium_locus` — paper Fig. 5: equilibrium locus, mid-plane pressure and foil deflection.
* :func:`plot_static_summary` — one equilibrium: pressure field, profiles, film and the Jacobian's eigenvalues.

Stable equilibria are drawn with filled markers and solid lines, unstable ones with hollow markers and dashed lines.
"""

from __future__ import annotations

import math
import os
from typing import Any, Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ._common import axes_grid, finish, save_figure

__all__ = ["plot_load_displacement", "plot_equilibrium_locus", "plot_static_summary", "save_figure"]

_STABLE_COLOR = "tab:blue"
_UNSTABLE_COLOR = "tab:red"
_CONTACT_COLOR = "black"


# -- helpers -------------------------------------------------------------------------------------------------


def _nested(curves: Any) -> dict[float | None, dict[float, list]]:
    """Normalise curve inputs to ``{alpha_f: {omega: [StaticResult, ...]}}``.

    Accepted: that nested mapping; ``{omega: [results]}`` (one alpha_f, key ``None``); a list of results (one
    curve); a list of lists of results (one curve each, keyed by the speed of their first result).
    """
    def is_result(x: Any) -> bool:
        return hasattr(x, "y_j") and hasattr(x, "outcome")

    if isinstance(curves, Mapping):
        vals = list(curves.values())
        if vals and isinstance(vals[0], Mapping):
            return {a: {o: list(rs) for o, rs in d.items()} for a, d in curves.items()}
        return {None: {o: list(rs) for o, rs in curves.items()}}
    curves = list(curves)
    if curves and is_result(curves[0]):
        return {None: {curves[0].omega: curves}}
    return {None: {rs[0].omega: list(rs) for rs in curves if len(rs)}}


def _alpha_label(alpha: float | None) -> str:
    return "" if alpha is None else rf"$\bar\alpha_f = {alpha:g}$"


def _gravity_w(spec: Any) -> float | None:
    """Specific gravity load per bearing ``W_g / (p0 L D)`` of a SystemSpec (None without one)."""
    if spec is None:
        return None
    return spec.bearing_weight / (spec.p0 * spec.L * 2.0 * spec.R)


def _carried_w(r: Any, w_g: float | None) -> float | None:
    """Extra specific load actually carried by a result's (possibly partially loaded) state.

    The load ramp scales gravity and the extra load together: the state of a "contact" result carries
    ``f (w_g + w)`` in total, i.e. ``f (w_g + w) - w_g`` beyond gravity (None without the gravity load).
    """
    if r.converged:
        return r.w
    if w_g is None:
        return None
    return r.load_fraction * (w_g + r.w) - w_g


def _split_curve(rs: Sequence[Any]) -> tuple[list[Any], Any | None]:
    conv = [r for r in rs if r.converged]
    bad = next((r for r in rs if not r.converged), None)
    return conv, bad


def _plot_stability_line(ax, x: np.ndarray, y: np.ndarray, stable: np.ndarray, color, label: str | None,
                         marker: str = "o", ms: float = 4.5) -> None:
    """A line through (x, y), solid where both ends are stable, dashed otherwise; filled markers for stable
    points, hollow for unstable ones."""
    if len(x) == 0:
        return
    for k in range(len(x) - 1):
        ls = "-" if (stable[k] and stable[k + 1]) else "--"
        ax.plot(x[k:k + 2], y[k:k + 2], ls=ls, color=color, lw=1.5)
    st = stable.astype(bool)
    ax.plot(x[st], y[st], ls="none", marker=marker, ms=ms, color=color, mfc=color)
    ax.plot(x[~st], y[~st], ls="none", marker=marker, ms=ms, color=color, mfc="white")
    # legend proxy
    ax.plot([], [], ls="-", marker=marker, ms=ms, color=color, label=label)


def _theta_deg(r: Any) -> np.ndarray:
    return np.degrees(np.asarray(r.theta))


def _format_theta_axis(ax, theta_deg: np.ndarray) -> None:
    lo, hi = float(theta_deg[0]), float(theta_deg[-1])
    ax.set_xlim(lo, hi)
    ticks = np.arange(math.ceil(lo / 90.0) * 90.0, hi + 1e-9, 90.0)
    ax.set_xticks(ticks)
    # the load line: straight down, theta = 270 deg (mod 360) inside [lo, hi]
    for t in (270.0, 630.0, -90.0):
        if lo < t < hi:
            ax.axvline(t, color="0.6", lw=0.8, ls=":")
    ax.set_xlabel(r"$\theta$ [deg]  (from $+x$ towards $+y$; load line at 270°)")


def _film(r: Any) -> np.ndarray:
    th = np.asarray(r.theta)
    return 1.0 - r.x_j * np.cos(th) - r.y_j * np.sin(th) + np.asarray(r.foil)


def _load_colors(n: int):
    cmap = plt.get_cmap("viridis")
    return [cmap(v) for v in np.linspace(0.0, 0.85, max(n, 1))]


def _speed_label(omega: float, spec: Any = None) -> str:
    lab = rf"$\bar\Omega = {omega:.4g}$"
    if spec is not None:
        lab += f" ({spec.rpm(omega):.0f} rpm)"
    return lab


def _speed_colors(n: int):
    cmap = plt.get_cmap("plasma")
    return [cmap(v) for v in np.linspace(0.0, 0.8, max(n, 1))]


# -- Fig. 4 -----------------------------------------------------------------------------------------------------


def plot_load_displacement(curves: Any, *, spec: Any = None, c_um: float | None = None,
                           path: str | os.PathLike | None = None, title: str | None = None,
                           sharey: bool = False, ax: Any = None) -> Figure:
    """Vertical journal displacement against specific load (paper Fig. 4).

    One panel per foil compliance alpha_f, one line per speed Omega_bar.  A curve that ended because the film
    closed (``outcome == "contact"``) ends in a black cross at the load actually carried when the ramp stopped
    (needs ``spec`` for the gravity load; otherwise at the last converged point) and a "contact" label.

    Args:
        curves: ``{alpha_f: {omega: [StaticResult, ...]}}`` (results in order of increasing load, as returned by
            :func:`gfbjax.analyses.static.load_displacement`); also ``{omega: [...]}`` or a list of results.
        spec: the :class:`gfbjax.SystemSpec` (optional): adds a micrometre axis (right) and a newton axis (top).
        c_um: radial clearance in micrometres, for the right axis when no ``spec`` is given.
        path: file to save to (optional).
        title: figure title (optional).
        sharey: share the displacement axis between panels (new figure only).
        ax: None (a new figure) or one Axes per alpha_f panel (a row of them) to draw into; then their figure is
            returned and gets a suptitle only when ``title`` is given.

    Returns:
        The figure.  Axes: x = extra specific load ``W/(p0 L D)`` per bearing beyond gravity [-];
        y = journal centre ``y_j / c`` [-] (negative: downwards).
    """
    data = _nested(curves)
    if spec is not None and c_um is None:
        c_um = spec.c * 1e6
    w_g = _gravity_w(spec)
    n = len(data)
    fig, axes, new = axes_grid(ax, 1, n, figsize=(4.6 * n + 0.6, 4.2), sharey=sharey, constrained_layout=True)
    for ax, (alpha, by_speed) in zip(axes[0], data.items()):
        colors = _speed_colors(len(by_speed))
        contact_any = False
        for col, (omega, rs) in zip(colors, sorted(by_speed.items())):
            conv, bad = _split_curve(rs)
            x = np.array([r.w for r in conv])
            y = np.array([r.y_j for r in conv])
            st = np.array([r.stable for r in conv], bool)
            _plot_stability_line(ax, x, y, st, col, _speed_label(omega, spec))
            if bad is not None and bad.outcome == "contact":
                contact_any = True
                wc = _carried_w(bad, w_g)
                if wc is not None and (len(x) == 0 or wc > x[-1]):
                    xs, ys = (np.r_[x[-1], wc], np.r_[y[-1], bad.y_j]) if len(x) else ([wc], [bad.y_j])
                    ax.plot(xs, ys, ls=":", color=col, lw=1.2)
                    xc, yc = wc, bad.y_j
                elif len(x):
                    xc, yc = x[-1], y[-1]
                else:
                    continue
                ax.plot([xc], [yc], marker="X", ms=9, color=_CONTACT_COLOR, mec="white", mew=0.8, zorder=5)
                ax.annotate("contact", (xc, yc), xytext=(4, -10), textcoords="offset points", fontsize=8)
        ax.axhline(-1.0, color="0.5", lw=0.8, ls="--")
        ax.annotate("nominal clearance $y_j = -c$", (0.01, -1.0), xycoords=("axes fraction", "data"),
                    xytext=(0, 2), textcoords="offset points", va="bottom", ha="left", fontsize=7, color="0.4")
        ax.set_xlabel(r"specific load $\bar W = W/(p_0 L D)$ beyond gravity [-]")
        ax.set_ylabel(r"journal displacement $y_j/c$ [-]")
        ax.set_title(_alpha_label(alpha) or "load-displacement")
        ax.grid(True, alpha=0.3)
        handles, labels = ax.get_legend_handles_labels()
        handles += [Line2D([], [], ls="-", marker="o", color="0.3", mfc="0.3"),
                    Line2D([], [], ls="--", marker="o", color="0.3", mfc="white")]
        labels += ["stable", "unstable"]
        if contact_any:
            handles.append(Line2D([], [], ls="none", marker="X", ms=8, color=_CONTACT_COLOR))
            labels.append("contact (film closes)")
        ax.legend(handles, labels, fontsize=7.5, loc="upper right", framealpha=0.85)
        if c_um:
            sec = ax.secondary_yaxis("right", functions=(lambda v, c=c_um: v * c, lambda v, c=c_um: v / c))
            sec.set_ylabel(r"$y_j$ [µm]")
        if spec is not None:
            f_n = spec.p0 * spec.L * 2.0 * spec.R
            top = ax.secondary_xaxis("top", functions=(lambda v, f=f_n: v * f, lambda v, f=f_n: v / f))
            top.set_xlabel("extra load per bearing $W$ [N]", fontsize=8)
    return finish(fig, path, new=new, title=title)


# -- Fig. 5 -----------------------------------------------------------------------------------------------------


def plot_equilibrium_locus(results: Any, *, spec: Any = None, profile_speed: float | None = None,
                           max_profiles: int = 6, path: str | os.PathLike | None = None,
                           title: str | None = None, ax: Any = None) -> Figure:
    """Equilibrium locus, mid-plane pressure and foil deflection (paper Fig. 5).

    One row per foil compliance alpha_f.  Left: the journal centre ``(x_j, y_j)/c`` for increasing load, one line
    per speed, inside the clearance circle (the unit circle of a rigid bearing; the compliant foil lets the journal
    go beyond it).  Middle and right: for the speed ``profile_speed`` (default: the middle one), the mid-plane
    pressure ``p/p0`` and the foil deflection ``q/c`` against theta for up to ``max_profiles`` loads, with matching
    coloured rings on the locus.

    Args:
        results: ``{alpha_f: {omega: [StaticResult, ...]}}`` as for :func:`plot_load_displacement`.
        spec: optional :class:`gfbjax.SystemSpec` (for the title's clearance in micrometres).
        profile_speed: speed whose profiles are shown (the nearest available is used).
        max_profiles: most loads shown in the profile panels (evenly picked, always with the first and last).
        path: file to save to (optional).
        title: figure title (optional).
        ax: None (a new figure) or 3 Axes per alpha_f row (locus, pressure, foil; n rows x 3, row-major) to draw
            into; then their figure is returned and gets a suptitle only when ``title`` is given.
    """
    data = _nested(results)
    n = len(data)
    fig, axes, new = axes_grid(ax, n, 3, figsize=(14.0, 3.9 * n + 0.4), constrained_layout=True,
                               gridspec_kw={"width_ratios": [1.0, 1.35, 1.35]})
    for row, (alpha, by_speed) in zip(axes, data.items()):
        ax_l, ax_p, ax_q = row
        speeds = sorted(by_speed)
        colors = _speed_colors(len(speeds))
        # locus
        th = np.linspace(0, 2 * np.pi, 361)
        ax_l.plot(np.cos(th), np.sin(th), color="0.4", lw=1.0, ls="--", label="clearance circle")
        ax_l.axhline(0, color="0.8", lw=0.6)
        ax_l.axvline(0, color="0.8", lw=0.6)
        e_max = 1.0
        for col, omega in zip(colors, speeds):
            conv, bad = _split_curve(by_speed[omega])
            x = np.array([r.x_j for r in conv])
            y = np.array([r.y_j for r in conv])
            st = np.array([r.stable for r in conv], bool)
            _plot_stability_line(ax_l, x, y, st, col, _speed_label(omega), ms=3.5)
            if bad is not None and bad.outcome == "contact":
                ax_l.plot([bad.x_j], [bad.y_j], marker="X", ms=8, color=_CONTACT_COLOR, mec="white", mew=0.8)
                if len(x):
                    ax_l.plot([x[-1], bad.x_j], [y[-1], bad.y_j], ls=":", color=col, lw=1.0)
                e_max = max(e_max, bad.eccentricity)
            if len(x):
                e_max = max(e_max, float(np.max(np.hypot(x, y))))
        lim = 1.08 * e_max
        ax_l.set_xlim(-lim, lim)
        ax_l.set_ylim(-lim, lim)
        ax_l.set_aspect("equal")
        ax_l.set_xlabel(r"$x_j/c$ [-]")
        ax_l.set_ylabel(r"$y_j/c$ [-]")
        ax_l.set_title(f"equilibrium locus  {_alpha_label(alpha)}".strip())
        ax_l.grid(True, alpha=0.25)
        # profiles
        if not speeds:
            continue
        ps = profile_speed if profile_speed is not None else speeds[len(speeds) // 2]
        omega_p = min(speeds, key=lambda o: abs(o - ps))
        conv, _ = _split_curve(by_speed[omega_p])
        if len(conv) > max_profiles:
            idx = np.unique(np.round(np.linspace(0, len(conv) - 1, max_profiles)).astype(int))
            shown = [conv[i] for i in idx]
        else:
            shown = conv
        lcols = _load_colors(len(shown))
        for col, r in zip(lcols, shown):
            tdeg = _theta_deg(r)
            ls = "-" if r.stable else "--"
            lab = rf"$\bar W = {r.w:g}$"
            ax_p.plot(tdeg, r.midplane_pressure(), color=col, ls=ls, lw=1.4, label=lab)
            ax_q.plot(tdeg, r.foil, color=col, ls=ls, lw=1.4, label=lab)
            ax_l.plot([r.x_j], [r.y_j], ls="none", marker="o", ms=9, mfc="none", mec=col, mew=1.6)
        for ax in (ax_p, ax_q):
            if shown:
                _format_theta_axis(ax, _theta_deg(shown[0]))
            ax.grid(True, alpha=0.3)
        ax_p.axhline(1.0, color="0.5", lw=0.8, ls=":")
        ax_p.set_ylabel(r"mid-plane pressure $p/p_0$ [-]")
        ax_p.set_title(f"mid-plane pressure at {_speed_label(omega_p, spec)}")
        ax_q.set_ylabel(r"foil deflection $q/c$ [-]")
        ax_q.set_title(f"foil deflection at {_speed_label(omega_p, spec)}")
        ax_p.legend(fontsize=7.5, loc="upper left", title="specific load", title_fontsize=7.5)
        handles, labels = ax_l.get_legend_handles_labels()
        handles += [Line2D([], [], ls="none", marker="o", ms=8, mfc="none", mec="0.3", mew=1.4)]
        labels += ["profile shown"]
        ax_l.legend(handles, labels, fontsize=7, loc="upper left")
    default = None
    if spec is not None:
        default = f"Equilibrium locus and profiles (c = {spec.c * 1e6:.1f} µm; stable: solid, unstable: dashed)"
    return finish(fig, path, new=new, title=title, default=default)


# -- single equilibrium ------------------------------------------------------------------------------------------


def _zoom_window(ev: np.ndarray, n_modes: int = 12) -> tuple[tuple[float, float], tuple[float, float], int]:
    """Axes limits around the lightly damped modes near the imaginary axis (rotor and foil modes).

    Chosen: eigenvalues with ``Re > -0.5 |Im|`` (damping ratio below about 0.45) or ``Re >= 0``, at most the
    ``n_modes`` with the largest real part; if there are none, the ``n_modes`` least-damped eigenvalues.
    Returns (xlim, ylim, number of modes chosen)."""
    ev = ev[np.argsort(-ev.real)]
    light = ev[(ev.real > -0.5 * np.abs(ev.imag)) | (ev.real >= 0.0)]
    sel = light[:n_modes] if light.size else ev[: min(n_modes, ev.size)]
    re_lo = min(float(np.min(sel.real)), 0.0)
    re_hi = max(float(np.max(sel.real)), 0.0)
    span = max(re_hi - re_lo, 1e-6)
    xlim = (re_lo - 0.25 * span, re_hi + 0.15 * span)
    im = float(np.max(np.abs(sel.imag))) if sel.size else 1.0
    im = im if im > 0 else 1.0
    return xlim, (-1.12 * im, 1.12 * im), int(sel.size)


def _symlog_real_axis(ax, ev: np.ndarray) -> None:
    """Symmetric-log real axis for a spectrum spanning many decades, with one labelled tick per decade or two."""
    re = ev.real
    nz = np.abs(re[re != 0.0])
    if nz.size == 0:
        return
    k_lo = int(np.floor(np.log10(max(float(np.abs(ev[0].real)) if ev[0].real != 0 else nz.min(), 1e-6))))
    k_lo = max(k_lo, int(np.floor(np.log10(nz.max()))) - 8)
    lin = 10.0 ** k_lo
    ax.set_xscale("symlog", linthresh=lin, linscale=1.0)
    neg = re.min() < 0
    pos = re.max() > 0
    k_neg = int(np.ceil(np.log10(max(-re.min(), lin)))) if neg else k_lo
    k_pos = int(np.ceil(np.log10(max(re.max(), lin)))) if pos else k_lo
    step = 1 if max(k_neg, k_pos) - k_lo <= 5 else 2
    # no ticks at +-linthresh: their labels would collide with the one at 0
    ticks = [-(10.0 ** k) for k in range(k_neg, k_lo, -step)] if neg else []
    ticks.append(0.0)
    if pos:
        ticks += [10.0 ** k for k in range(k_pos, k_lo, -step)][::-1]
    ax.set_xticks(ticks)
    lo = -(10.0 ** k_neg) * 1.5 if neg else -lin
    hi = (10.0 ** k_pos) * 1.5 if pos else lin
    ax.set_xlim(lo, hi)


def plot_static_summary(result: Any, spec: Any = None, *, path: str | os.PathLike | None = None,
                        n_modes: int = 12, title: str | None = None, ax: Any = None) -> Figure:
    """One static equilibrium at a glance.

    Panels: (a) pressure field ``p/p0`` over theta and the bearing length (the computed half mirrored about the
    mid-plane); (b) mid-plane pressure; (c) foil deflection ``q/c``; (d) film thickness ``h/c`` with the rigid
    film ``h - q`` for comparison; (e) all eigenvalues of the Jacobian (symmetric-log real axis: the pressure modes
    are damped by orders of magnitude more than the rotor modes); (f) zoom on the ``n_modes`` least-damped
    eigenvalues near the imaginary axis, the critical one (largest real part) highlighted.  Eigenvalues are per
    unit dimensionless time tau = t / t*; with ``spec`` the zoom also has a frequency axis in Hz.

    Args:
        result: a :class:`gfbjax.analyses.static.StaticResult`.
        spec: its :class:`gfbjax.SystemSpec` (optional; adds micrometres, kPa, rpm and Hz).
        path: file to save to (optional).
        n_modes: most eigenvalues in the zoom window.
        title: figure title (default: speed, load, outcome).
        ax: None (a new figure) or 6 Axes (panels a-f, 2 x 3, row-major) to draw into; then their figure is
            returned and gets a suptitle only when ``title`` is given.
    """
    r = result
    fig, axes, new = axes_grid(ax, 2, 3, figsize=(15.0, 8.6), constrained_layout=True)
    (ax_f, ax_p, ax_q), (ax_h, ax_e, ax_z) = axes
    tdeg = _theta_deg(r)

    # (a) pressure field over the full length (mirror the half domain about the mid-plane z = 1/2)
    P = np.asarray(r.pressure)
    z = np.asarray(r.z)
    z_full = np.concatenate([z, 1.0 - z[-2::-1]])
    P_full = np.concatenate([P, P[:, -2::-1]], axis=1)
    levels = np.linspace(min(P_full.min(), 1.0), max(P_full.max(), 1.0 + 1e-6), 21)
    cf = ax_f.contourf(tdeg, z_full, P_full.T, levels=levels, cmap="viridis")
    ax_f.contour(tdeg, z_full, P_full.T, levels=[1.0], colors="w", linewidths=0.8, linestyles="--")
    cb = fig.colorbar(cf, ax=ax_f, pad=0.01)
    cb.set_label(r"$p/p_0$ [-]  (white dashed: ambient)")
    _format_theta_axis(ax_f, tdeg)
    ax_f.set_ylabel(r"axial position $z/L$ [-]")
    ax_f.set_title("(a) pressure field")

    # (b) mid-plane pressure
    pm = r.midplane_pressure()
    ax_p.plot(tdeg, pm, color="tab:blue", lw=1.6)
    ax_p.axhline(1.0, color="0.5", lw=0.8, ls=":")
    ax_p.fill_between(tdeg, 1.0, pm, where=pm < 1.0, color="tab:orange", alpha=0.25,
                      label="sub-ambient (no foil load, no force: Gumbel)")
    _format_theta_axis(ax_p, tdeg)
    ax_p.set_ylabel(r"mid-plane pressure $p/p_0$ [-]")
    ax_p.set_title("(b) mid-plane pressure")
    ax_p.legend(fontsize=7.5, loc="upper left")
    ax_p.grid(True, alpha=0.3)
    if spec is not None:
        sec = ax_p.secondary_yaxis("right", functions=(lambda v, p0=spec.p0: (v - 1.0) * p0 / 1e3,
                                                       lambda v, p0=spec.p0: 1.0 + v * 1e3 / p0))
        sec.set_ylabel("gauge pressure [kPa]")

    # (c) foil deflection
    q = np.asarray(r.foil)
    ax_q.plot(tdeg, q, color="tab:green", lw=1.6)
    ax_q.fill_between(tdeg, 0.0, q, color="tab:green", alpha=0.15)
    _format_theta_axis(ax_q, tdeg)
    ax_q.set_ylabel(r"foil deflection $q/c$ [-]")
    ax_q.set_title("(c) foil deflection (clamped at the fixed end)")
    ax_q.grid(True, alpha=0.3)
    c_um = spec.c * 1e6 if spec is not None else None
    if c_um:
        sec = ax_q.secondary_yaxis("right", functions=(lambda v, c=c_um: v * c, lambda v, c=c_um: v / c))
        sec.set_ylabel("q [µm]")

    # (d) film thickness
    h = _film(r)
    ax_h.plot(tdeg, h, color="tab:purple", lw=1.6, label="film $h/c$")
    ax_h.plot(tdeg, h - q, color="tab:purple", lw=1.0, ls="--", label="rigid film $h - q$")
    i_min = int(np.argmin(h))
    ax_h.plot([tdeg[i_min]], [h[i_min]], "v", color="k", ms=7, label=rf"$h_{{min}} = {h[i_min]:.3g}\,c$")
    ax_h.axhline(0.0, color="0.5", lw=0.8)
    _format_theta_axis(ax_h, tdeg)
    ax_h.set_ylabel(r"film thickness $h/c$ [-]")
    ax_h.set_title("(d) film thickness")
    ax_h.legend(fontsize=7.5, loc="upper left")
    ax_h.grid(True, alpha=0.3)
    if c_um:
        sec = ax_h.secondary_yaxis("right", functions=(lambda v, c=c_um: v * c, lambda v, c=c_um: v / c))
        sec.set_ylabel("h [µm]")

    # (e) full spectrum, (f) zoom
    ev = np.asarray(r.eigenvalues)
    if ev.size:
        lam = r.critical_eigenvalue
        unstable = ev.real > 0
        for ax in (ax_e, ax_z):
            ax.axvline(0.0, color="k", lw=0.8)
            ax.axhline(0.0, color="0.7", lw=0.6)
            ax.plot(ev.real[~unstable], ev.imag[~unstable], "o", ms=4, mfc="none", mec=_STABLE_COLOR,
                    label="stable (Re λ < 0)")
            if unstable.any():
                ax.plot(ev.real[unstable], ev.imag[unstable], "o", ms=5, color=_UNSTABLE_COLOR,
                        label="unstable (Re λ > 0)")
            ax.plot([lam.real, lam.real], [lam.imag, -lam.imag], "*", ms=14,
                    color=_UNSTABLE_COLOR if lam.real > 0 else "tab:orange", mec="k", mew=0.6,
                    label="critical", zorder=5)
            ax.grid(True, alpha=0.3)
            ax.set_xlabel(r"Re $\lambda$ [1/τ]")
            ax.set_ylabel(r"Im $\lambda$ [1/τ]")
        _symlog_real_axis(ax_e, ev)
        ax_e.set_title(f"(e) Jacobian eigenvalues, all {ev.size} (symlog Re axis)")
        ax_e.legend(fontsize=7.5, loc="upper left")
        xlim, ylim, n_sel = _zoom_window(ev, n_modes)
        ax_z.set_xlim(*xlim)
        ax_z.set_ylim(*ylim)
        ax_z.axvspan(0.0, xlim[1], color=_UNSTABLE_COLOR, alpha=0.06)
        for level, ls, label in ((r.omega, ":", r" Im λ = $\bar\Omega$ (synchronous)"),
                                  (0.5 * r.omega, "-.", r" Im λ = $\bar\Omega$/2 (half-frequency whirl)")):
            if level < 0.97 * ylim[1]:
                ax_z.axhline(level, color="0.5", lw=0.8, ls=ls)
                ax_z.text(xlim[0], level, label, va="bottom", fontsize=7, color="0.35", clip_on=True)
        ratio = abs(lam.imag) / r.omega if r.omega else float("nan")
        state = "unstable" if lam.real > 0 else "stable"
        txt = (f"critical λ = {lam.real:.4g} ± {abs(lam.imag):.4g} i\n"
               f"whirl ratio |Im λ|/Ω̄ = {ratio:.3f}\nequilibrium {state}")
        if spec is not None:
            txt += f"\nf = {abs(lam.imag) / spec.t_star / (2 * math.pi):.1f} Hz"
        ax_z.text(0.98, 0.02, txt, transform=ax_z.transAxes, ha="right", va="bottom", fontsize=8,
                  bbox=dict(boxstyle="round", fc="white", ec="0.6", alpha=0.9))
        ax_z.set_title(f"(f) zoom near the imaginary axis: {n_sel} lightly damped modes")
        if spec is not None:
            fhz = 1.0 / spec.t_star / (2 * math.pi)
            sec = ax_z.secondary_yaxis("right", functions=(lambda v, k=fhz: v * k, lambda v, k=fhz: v / k))
            sec.set_ylabel("frequency [Hz]")

    speed = rf"$\bar\Omega = {r.omega:g}$"
    if spec is not None:
        speed += f" ({spec.rpm(r.omega):.0f} rpm)"
    load = rf"$\bar W = {r.w:g}$ beyond gravity"
    pos = rf"$(x_j, y_j) = ({r.x_j:.3f}, {r.y_j:.3f})\,c$, $\epsilon = {r.eccentricity:.3f}$"
    return finish(fig, path, new=new, title=title, default=f"Static equilibrium: {speed}, {load}; {pos}; {r.outcome}")
