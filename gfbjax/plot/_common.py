"""Helpers shared by the figure modules: make-or-use axes, "one branch or several", finishing and saving."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np


def save_figure(fig: Any, path: str | os.PathLike | None, dpi: int = 150) -> Any:
    """Save ``fig`` to ``path`` (folders created; format from the suffix) when ``path`` is given; return it.

    For a subfigure (axes given inside ``Figure.subfigures``) the whole figure is saved."""
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        root = fig if hasattr(fig, "savefig") else fig.figure
        root.savefig(path, dpi=dpi, bbox_inches="tight")
    return fig


def axes_grid(ax: Any, nrows: int, ncols: int, **subplots_kw) -> tuple[Any, np.ndarray, bool]:
    """The figure and an (nrows, ncols) object array of axes to draw into, and whether the figure is new.

    ``ax`` None: a new figure from ``plt.subplots(nrows, ncols, **subplots_kw)``.  Otherwise one Axes or a
    sequence / array of ``nrows * ncols`` Axes of one figure, taken in row-major order (any nesting); anything
    else raises a ValueError that names ``ax``."""
    if ax is None:
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(nrows, ncols, squeeze=False, **subplots_kw)
        return fig, axes, True
    from matplotlib.axes import Axes

    flat = [ax] if isinstance(ax, Axes) else list(np.ravel(np.asarray(ax, dtype=object)))
    n = nrows * ncols
    shape = f"{nrows} x {ncols}" if nrows > 1 and ncols > 1 else ("one Axes" if n == 1 else f"{n} Axes")
    if len(flat) != n or not all(isinstance(a, Axes) for a in flat):
        got = f"{len(flat)} item(s)" if all(isinstance(a, Axes) for a in flat) else "something other than Axes"
        raise ValueError(f"ax: this figure has {n} panel(s) ({shape}, row-major); pass that many matplotlib Axes "
                         f"(or None for a new figure), got {got}")
    fig = flat[0].figure
    if any(a.figure is not fig for a in flat):
        raise ValueError("ax: all the given Axes must belong to one figure")
    return fig, np.array(flat, dtype=object).reshape(nrows, ncols), False


def finish(fig: Any, path: Any, *, new: bool, title: str | None, default: str | None = None,
           tight: bool = False, dpi: int = 150) -> Any:
    """Title, layout and save.  A new figure gets ``title`` (``default`` when None) as suptitle and, with
    ``tight``, ``tight_layout``; a figure of given axes keeps its layout and gets a suptitle only from an
    explicit ``title``."""
    if new and title is None:
        title = default
    if title:
        fig.suptitle(title)
    if new and tight:
        fig.tight_layout()
    return save_figure(fig, path, dpi)


def labelled(obj: Any, single: Callable[[Any], bool]) -> tuple[list[tuple[str | None, Any]], bool]:
    """Normalise "one item or several" to ``[(label, item), ...]`` and whether several were given.

    ``single(obj)`` true: ``[(None, obj)]``.  Else a mapping ``{label: item}`` or a sequence of ``(label, item)``
    pairs; a longer tuple ``(label, a, b)`` gives the item ``(a, b)``."""
    if single(obj):
        return [(None, obj)], False
    if isinstance(obj, Mapping):
        out = [(str(k), v) for k, v in obj.items()]
    else:
        out = []
        for p in obj:
            if not (isinstance(p, (tuple, list)) and len(p) >= 2 and isinstance(p[0], str)):
                raise TypeError(f"expected one item, a {{label: item}} dict or (label, item) pairs; got {p!r:.80}")
            out.append((p[0], p[1] if len(p) == 2 else tuple(p[1:])))
    if not out:
        raise ValueError("nothing to plot: an empty collection was given")
    return out, True


def colours(n: int) -> list:
    """``n`` distinct colours from the current property cycle (repeating when it is shorter)."""
    import matplotlib.pyplot as plt

    cyc = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    return [cyc[i % len(cyc)] for i in range(n)]


def rpm_factor(rpm_per_omega_bar: float | None = None, spec: Any = None, branches: Any = ()) -> float | None:
    """rpm per unit Omega_bar: ``rpm_per_omega_bar`` if given, else ``spec.rpm(1.0)`` of a SystemSpec, else the
    ``rpm_per_omega_bar`` a branch records in its ``meta`` (branches computed with ``spec=``); None if unknown."""
    if rpm_per_omega_bar is not None:
        f = float(rpm_per_omega_bar)
        if not (np.isfinite(f) and f > 0):
            raise ValueError(f"rpm_per_omega_bar must be a positive number, got {rpm_per_omega_bar!r}")
        return f
    if spec is not None:
        return float(spec.rpm(1.0))
    for b in branches:
        f = (getattr(b, "meta", None) or {}).get("rpm_per_omega_bar")
        if f:
            return float(f)
    return None


def rpm_axis(ax: Any, factor: float | None, label: str = "speed [rpm]") -> Any:
    """A secondary x axis on top of ``ax`` (whose x is Omega_bar) in rpm, ``rpm = factor * Omega_bar``; nothing
    when ``factor`` is None.  Returns the secondary axis or None."""
    if factor is None:
        return None
    sec = ax.secondary_xaxis("top", functions=(lambda x: x * factor, lambda r: r / factor))
    sec.set_xlabel(label)
    return sec
