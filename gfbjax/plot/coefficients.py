"""Figure of the linearised bearing coefficients against speed (:mod:`gfbjax.analyses.coefficients`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ._common import axes_grid, finish, rpm_axis, rpm_factor

__all__ = ["plot_coefficients"]

_ENTRIES = (("xx", 0, 0, "tab:blue", "-"), ("yy", 1, 1, "tab:red", "-"), ("xy", 0, 1, "tab:green", "--"),
            ("yx", 1, 0, "tab:purple", "--"))


def plot_coefficients(coefficients: Any, *, spec: Any = None, title: str | None = None,
                      path: str | Path | None = None, ax: Any = None):
    """Stiffness (left) and damping (right) of one bearing against speed: the four entries xx, yy (solid), xy, yx
    (dashed) of a :class:`gfbjax.analyses.coefficients.BearingCoefficients`.

    With ``spec`` (the SystemSpec they were computed for) the values are in N/m and N s/m and a secondary speed axis
    in rpm is drawn on top; without it they are dimensionless (``p0 R L / c``, ``p0 R L t* / c``).  ``ax``: None
    (a new figure) or 2 Axes to draw into."""
    om = np.asarray(coefficients.omega, float)
    if spec is not None:
        si = coefficients.si(spec)
        K, C = si["K_N_per_m"], si["C_Ns_per_m"]
        units = ("N/m", "N s/m")
    else:
        K, C = np.asarray(coefficients.K), np.asarray(coefficients.C)
        units = (r"$p_0 R L / c$", r"$p_0 R L t^* / c$")
    fig, axes, new = axes_grid(ax, 1, 2, figsize=(12, 4.6))
    for a, M, name, unit in ((axes[0, 0], K, "stiffness k", units[0]), (axes[0, 1], C, "damping c", units[1])):
        for tag, i, j, colour, ls in _ENTRIES:
            a.plot(om, M[:, i, j], ls, color=colour, marker="o", ms=3, lw=1.4, label=f"{name[-1]}$_{{{tag}}}$")
        a.axhline(0.0, color="0.5", lw=0.6)
        a.set_xlabel(r"speed $\bar\Omega$")
        a.set_ylabel(f"{name} [{unit}]")
        a.grid(alpha=0.3)
        a.legend(fontsize=8, loc="best")
        rpm_axis(a, rpm_factor(None, spec))
    r = float(coefficients.whirl_ratio)
    default = ("Synchronous bearing coefficients (whirl = running speed)" if r == 1.0 else
               f"Bearing coefficients at whirl ratio {r:.4g}")
    return finish(fig, path, new=new, title=title, default=default, tight=True, dpi=130)
