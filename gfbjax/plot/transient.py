"""Figures of transient runs (paper Figs. 7-11, panels a-c): run-up time history against speed with optional
max/min of continuation cycles, STFT spectrogram against speed in multiples of the running frequency, and the
orbit + Poincare points + FFT at one speed.  Every function takes ``ax=``: None (a new figure) or the Axes to draw
into (as many as the figure has panels; their figure is returned), and ``path=`` to save."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..analyses.signals import Spectrogram, spectrum
from ._common import axes_grid, finish, rpm_axis, rpm_factor

__all__ = ["plot_runup", "plot_spectrogram", "plot_orbit_poincare_fft"]


def plot_runup(result: Any, cycles: Mapping[str, np.ndarray] | None = None, *, c_um: float | None = None,
               title: str | None = None, path: str | Path | None = None, ax: Any = None, spec: Any = None,
               rpm_per_omega_bar: float | None = None):
    """Journal vertical (a) and horizontal (b) displacement against speed during a run-up (paper Fig. 7a/7b).

    Args:
        result: a run-up :class:`gfbjax.analyses.transient.TransientResult`.
        cycles: optional max/min of limit cycles from continuation: a mapping with ``speed`` and any of
            ``y_max``, ``y_min``, ``x_max``, ``x_min`` (over c), optionally ``stable`` (bool per speed; unstable
            cycles are drawn dashed).
        c_um: clearance in um for a secondary axis label (None: over c only).
        ax: None (a new figure) or 2 Axes (vertical, horizontal) to draw into; then their figure is returned and
            gets a suptitle only when ``title`` is given.
        spec, rpm_per_omega_bar: the SystemSpec or the factor rpm / Omega_bar; either draws a secondary speed axis
            in rpm on top (none without them).
    """
    fig, axes, new = axes_grid(ax, 2, 1, figsize=(8, 6.5), sharex=True)
    axes = axes[:, 0]
    for ax, key, label in ((axes[0], "y", "vertical $y_j/c$"), (axes[1], "x", "horizontal $x_j/c$")):
        sig = result.y_j if key == "y" else result.x_j
        ax.plot(result.speed, sig, lw=0.4, color="0.35", label="time integration (run-up)")
        if cycles is not None and "speed" in cycles:
            sp = np.asarray(cycles["speed"])
            stable = np.asarray(cycles.get("stable", np.ones(sp.size, bool)), bool)
            for ext, col in (("max", "tab:red"), ("min", "tab:blue")):
                k = f"{key}_{ext}"
                if k in cycles:
                    v = np.asarray(cycles[k], float)
                    ax.plot(sp, np.where(stable, v, np.nan), "-", color=col, lw=1.5, label=f"cycle {ext} (stable)")
                    ax.plot(sp, np.where(~stable, v, np.nan), "--", color=col, lw=1.2, label=f"cycle {ext} (unstable)")
        ylab = label + (f"  (c = {c_um:.1f} um)" if c_um else "")
        ax.set_ylabel(ylab)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="best", fontsize=7)
    axes[1].set_xlabel(r"speed $\bar\Omega$")
    rpm_axis(axes[0], rpm_factor(rpm_per_omega_bar, spec))
    return finish(fig, path, new=new, title=title, tight=True, dpi=130,
                  default="Run-up: journal response against speed (paper Fig. 7a/b)")


def plot_spectrogram(sg: Spectrogram, *, max_order: float | None = None, db_range: float = 60.0,
                     subsync: list | None = None, title: str | None = None, path: str | Path | None = None,
                     ax: Any = None, spec: Any = None, rpm_per_omega_bar: float | None = None):
    """STFT amplitude against speed and order (multiples of the running frequency; paper Fig. 7c) with the 1X
    line; ``subsync`` ranges (from :func:`gfbjax.analyses.signals.subsynchronous`) are marked.  ``ax``: None (a
    new figure) or one Axes to draw into (its figure is returned, with the colour bar beside the Axes);
    ``title`` is the axes title.  ``spec`` or ``rpm_per_omega_bar``: a secondary speed axis in rpm on top."""
    o = sg.order if max_order is None else sg.order[sg.order <= max_order]
    A = sg.order_amplitude[:, : o.size]
    ref = max(float(A.max()), 1e-300)
    db = 20 * np.log10(np.maximum(A / ref, 10 ** (-db_range / 20)))
    fig, axes, new = axes_grid(ax, 1, 1, figsize=(8, 4.8))
    ax = axes[0, 0]
    m = ax.pcolormesh(sg.speed, o, db.T, shading="nearest", cmap="viridis", vmin=-db_range, vmax=0)
    fig.colorbar(m, ax=ax, label="amplitude [dB re max]")
    ax.axhline(1.0, color="w", ls="--", lw=0.8, label="1X")
    ax.axhline(0.5, color="w", ls=":", lw=0.6, label="0.5X")
    for r in subsync or []:
        ax.plot([r.speed_start, r.speed_end], [r.order, r.order], color="tab:red", lw=2)
    ax.set_xlabel(r"speed $\bar\Omega$")
    ax.set_ylabel("frequency / running frequency")
    ax.legend(loc="upper right", fontsize=7)
    rpm_axis(ax, rpm_factor(rpm_per_omega_bar, spec))
    ax.set_title(title or "STFT of the run-up (paper Fig. 7c)", pad=24 if (spec or rpm_per_omega_bar) else None)
    return finish(fig, path, new=new, title=None, tight=True, dpi=130)


def plot_orbit_poincare_fft(result: Any, *, last: int = 100, max_order: float = 4.0, classification: Any = None,
                            title: str | None = None, path: str | Path | None = None, ax: Any = None):
    """Journal orbit over the last ``last`` revolutions with its Poincare points (once per revolution) and the FFT
    of the vertical response in multiples of the running speed (paper Fig. 8c style).  ``ax``: None (a new figure)
    or 3 Axes (orbit, Poincare map, FFT) to draw into; then their figure is returned and gets a suptitle only when
    ``title`` is given."""
    spr = result.samples_per_rev
    sl = result.window(last)
    fig, axes, new = axes_grid(ax, 1, 3, figsize=(13, 4.2))
    axes = axes[0]
    ax = axes[0]
    ax.plot(result.x_j[sl], result.y_j[sl], lw=0.5, color="0.3")
    P = result.poincare(last=last)
    ax.plot(P[:, 0], P[:, 1], "o", ms=3, color="tab:red", label=f"Poincare ({len(P)} pts)")
    th = np.linspace(0, 2 * np.pi, 200)
    ax.plot(np.cos(th), np.sin(th), color="0.7", lw=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("$x_j/c$")
    ax.set_ylabel("$y_j/c$")
    ax.legend(fontsize=7)
    ax.set_title("orbit")
    ax = axes[1]
    ax.plot(P[:, 0], P[:, 1], "o", ms=3, color="tab:red")
    ax.set_xlabel("$x_j/c$")
    ax.set_ylabel("$y_j/c$")
    ax.ticklabel_format(useOffset=False)
    ax.set_title("Poincare map" + (f": {classification.kind}" if classification is not None else ""))
    ax = axes[2]
    n = (result.tau.size - 1) // spr * spr
    n = min(n, last * spr)
    dtau = float(result.tau[1] - result.tau[0])
    for sig, lab in ((result.y_j, "$y_j$"), (result.x_j, "$x_j$")):
        s = spectrum(sig[-n - 1:-1] if n < sig.size else sig, dtau, float(result.speed[-1]))
        m = s.order <= max_order
        ax.semilogy(s.order[m], np.maximum(s.amplitude[m], 1e-12), lw=0.8, label=lab)
    ax.set_xlabel("frequency / running frequency")
    ax.set_ylabel("amplitude / c")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    ax.set_title("FFT")
    return finish(fig, path, new=new, title=title, tight=True, dpi=130,
                  default=rf"$\bar\Omega$ = {result.speed[-1]:.4g}: last {last} revolutions")
