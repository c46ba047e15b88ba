"""Figures of a sweep's Dataset (:func:`gfbjax.sweep.run_sweep`): a heat map of one figure over two swept fields,
lines over one field, and :func:`plot_sweep`, which picks the one that fits the sweep.

Every function takes ``ax=`` (draw into given axes; None: a new figure), ``path=`` (save, format from the suffix)
and ``title=``, and returns the matplotlib figure.  Designs whose analyses raised are marked with a red cross, so a
failed design is never mistaken for a missing value (NaN without a cross: the figure does not exist for that
design, e.g. no Hopf point in the speed range).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..plot._common import axes_grid, finish

__all__ = ["DEFAULT_FIGURES", "default_variable", "numeric_variables", "plot_variables", "heatmap", "lines", "plot_sweep"]

#: The figures :func:`plot_sweep` shows by default, in order of preference (the first one the sweep has).
DEFAULT_FIGURES = ("cycles_loss_omega_bar", "hopf_omega_bar", "energy_W_cb", "optimum_W_cb", "static_eccentricity",
                   "cycles_first_special_omega_bar")


def numeric_variables(ds: Any) -> list[str]:
    """The data variables that can be plotted (numbers, not texts), bookkeeping (``seconds``) last."""
    names = [k for k, v in ds.data_vars.items() if np.issubdtype(v.dtype, np.number)]
    return sorted(names, key=lambda k: k == "seconds")


def plot_variables(analyses: Sequence[Any]) -> list[str]:
    """What :func:`numeric_variables` will return for a sweep of ``analyses`` (objects of :mod:`._analyses`),
    known before any design is computed: their numeric figures, then ``seconds``."""
    return [f.name for a in analyses for f in a.figures if not f.text] + ["seconds"]


def default_variable(ds: Any) -> str:
    """The first of :data:`DEFAULT_FIGURES` that the sweep has with at least one finite value (else the first
    that it has, else the first numeric variable)."""
    have = [v for v in DEFAULT_FIGURES if v in ds.data_vars]
    for v in have:
        if np.isfinite(np.asarray(ds[v], float)).any():
            return v
    if have:
        return have[0]
    nums = numeric_variables(ds)
    if not nums:
        raise ValueError("the Dataset has no numeric variable to plot")
    return nums[0]


def _variable(ds: Any, var: str | None) -> str:
    var = default_variable(ds) if var is None else var
    nums = numeric_variables(ds)
    if var not in nums:
        raise ValueError(f"var = {var!r} is not a numeric variable of the sweep; choose one of {nums}")
    return var


def _design_dims(ds: Any) -> list[str]:
    return list(ds["outcome"].dims)


def _reduce(ds: Any, var: str, keep: Sequence[str], select: dict[str, Any] | None) -> tuple[Any, Any, str]:
    """``ds[var]`` and the outcome with every dimension except ``keep`` fixed: by ``select`` (``{dim: value}``),
    else at its first index; returns them and a note of what was fixed, for the title."""
    da, oc = ds[var], ds["outcome"]
    select = dict(select or {})
    unknown = set(select) - set(da.dims)
    if unknown:
        raise ValueError(f"select: {sorted(unknown)} are not dimensions of {var} {tuple(da.dims)}")
    notes = []
    for d in da.dims:
        if d in keep:
            continue
        if d in select:
            da = da.sel({d: select[d]})
            if d in oc.dims:
                oc = oc.sel({d: select[d]})
            notes.append(f"{d} = {select[d]:g}" if isinstance(select[d], (int, float)) else f"{d} = {select[d]}")
        else:
            v = da[d].values[0] if d in da.coords else 0
            da = da.isel({d: 0})
            if d in oc.dims:
                oc = oc.isel({d: 0})
            notes.append(f"{d} = {v:g}" if isinstance(v, (int, float, np.number)) else f"{d} = {v}")
    return da, oc, ", ".join(notes)


def _label(da: Any, name: str) -> str:
    units = da.attrs.get("units", "")
    return f"{name} [{units}]" if units and len(units) <= 24 else name


def _short(da: Any, var: str) -> str:
    """The variable's long name up to its first aside (the title of a figure)."""
    return da.attrs.get("long_name", var).split(";")[0].split(" (")[0]


def _ticks(values: np.ndarray) -> list[str]:
    return [f"{v:.4g}" if isinstance(v, (float, np.floating)) else str(v) for v in values]


def heatmap(ds: Any, var: str | None = None, x: str | None = None, y: str | None = None, *,
            select: dict[str, Any] | None = None, annotate: bool | None = None, cmap: str = "viridis",
            ax: Any = None, path: Any = None, title: str | None = None) -> Any:
    """Heat map of ``var`` over two swept fields, one cell per design (cells equally spaced, labelled with the
    field values, so uneven and logarithmic grids read alike).

    Args:
        ds: a grid sweep's Dataset with at least two swept fields (or one field and a speed dimension).
        var: a numeric variable (default :func:`default_variable`, e.g. ``hopf_omega_bar``).
        x, y: dimensions on the axes (default: the first two of ``var``'s).
        select: values of the other dimensions (``{dim: value}``); default their first.
        annotate: write the values into the cells (default: when there are at most 144 cells).
    Raises ValueError naming the argument for a variable or dimension the Dataset lacks.
    """
    var = _variable(ds, var)
    dims = list(ds[var].dims)
    if len(dims) < 2:
        raise ValueError(f"heatmap needs two dimensions; {var} has {tuple(dims)} (use lines)")
    x = dims[0] if x is None else x
    y = ([d for d in dims if d != x] or [None])[0] if y is None else y
    for name, d in (("x", x), ("y", y)):
        if d not in dims:
            raise ValueError(f"{name} = {d!r} is not a dimension of {var} {tuple(dims)}")
    if x == y:
        raise ValueError("x and y must be different dimensions")
    da, oc, note = _reduce(ds, var, (x, y), select)
    da = da.transpose(y, x)
    Z = np.asarray(da, float)
    fig, axes, new = axes_grid(ax, 1, 1, figsize=(6.4, 4.8))
    a = axes[0, 0]
    finite = np.isfinite(Z)
    mesh = a.pcolormesh(np.arange(Z.shape[1] + 1) - 0.5, np.arange(Z.shape[0] + 1) - 0.5,
                        np.ma.masked_invalid(Z), cmap=cmap, shading="flat")
    a.set_facecolor("0.85")  # NaN cells: the figure does not exist there
    fig.colorbar(mesh, ax=a, label=_label(da, var))
    a.set_xticks(range(Z.shape[1]), _ticks(da[x].values) if x in da.coords else range(Z.shape[1]))
    a.set_yticks(range(Z.shape[0]), _ticks(da[y].values) if y in da.coords else range(Z.shape[0]))
    a.set_xlabel(x)
    a.set_ylabel(y)
    if annotate is None:
        annotate = Z.size <= 144
    if annotate and finite.any():
        mid = np.nanmean(Z[finite])
        for (i, j), v in np.ndenumerate(Z):
            if np.isfinite(v):
                a.text(j, i, f"{v:.4g}", ha="center", va="center", fontsize=8,
                       color="black" if v > mid else "white")
    if set(oc.dims) >= {x, y}:
        bad = np.asarray(oc.transpose(y, x)) != "ok"
        if bad.any():
            jj, ii = np.nonzero(bad.T)
            a.plot(jj, ii, "x", color="red", ms=12, mew=2, ls="none", label="analysis failed")
            a.legend(loc="upper right", fontsize=8)
    default = _short(da, var) + (f" ({note})" if note else "")
    return finish(fig, path, new=new, title=title, default=default, tight=True)


def lines(ds: Any, var: str | None = None, x: str | None = None, hue: str | None = None, *,
          select: dict[str, Any] | None = None, ax: Any = None, path: Any = None, title: str | None = None) -> Any:
    """``var`` against one dimension ``x`` (a swept field, ``design`` or a speed dimension), one line per value of
    ``hue`` (another dimension; default: the next one of ``var``'s, if any).  Failed designs: red crosses at the
    bottom of the axes."""
    var = _variable(ds, var)
    dims = list(ds[var].dims)
    x = dims[0] if x is None else x
    if x not in dims:
        raise ValueError(f"x = {x!r} is not a dimension of {var} {tuple(dims)}")
    if hue is None:
        hue = next((d for d in dims if d != x), None)
    elif hue not in dims or hue == x:
        raise ValueError(f"hue = {hue!r} must be another dimension of {var} {tuple(dims)}")
    keep = (x,) if hue is None else (x, hue)
    da, oc, note = _reduce(ds, var, keep, select)
    fig, axes, new = axes_grid(ax, 1, 1, figsize=(6.4, 4.2))
    a = axes[0, 0]
    xs = np.asarray(da[x].values) if x in da.coords else np.arange(da.sizes[x])
    numeric_x = np.issubdtype(np.asarray(xs).dtype, np.number)
    pos = xs if numeric_x else np.arange(len(xs))
    groups = [(None, da, oc)] if hue is None else [
        (da[hue].values[k] if hue in da.coords else k, da.isel({hue: k}), oc.isel({hue: k}) if hue in oc.dims else oc)
        for k in range(da.sizes[hue])]
    for label, d, o in groups:
        ys = np.asarray(d.transpose(x), float)
        text = None if label is None else (f"{hue} = {label:.4g}" if isinstance(label, (float, np.floating))
                                           else f"{hue} = {label}")
        a.plot(pos, ys, "o-", ms=4, label=text)
        if x in o.dims:
            bad = np.asarray(o.transpose(x)) != "ok"
            if bad.any():
                a.plot(np.asarray(pos)[bad], np.zeros(bad.sum()), "x", color="red", ms=10, mew=2,
                       transform=a.get_xaxis_transform(), clip_on=False)
    if not numeric_x:
        a.set_xticks(pos, _ticks(xs))
    elif np.issubdtype(np.asarray(xs).dtype, np.integer) and len(xs) <= 30:  # design numbers, grid sizes
        a.set_xticks(pos)
    elif np.all(xs > 0) and len(xs) > 2 and xs.max() / xs.min() > 50:
        a.set_xscale("log")
    a.set_xlabel(x)
    a.set_ylabel(_label(da, var))
    if hue is not None:
        a.legend(fontsize=8)
    a.grid(alpha=0.3)
    default = _short(da, var) + (f" ({note})" if note else "")
    return finish(fig, path, new=new, title=title, default=default, tight=True)


def plot_sweep(ds: Any, var: str | None = None, *, ax: Any = None, path: Any = None, title: str | None = None) -> Any:
    """The figure that fits the sweep: a heat map over the first two swept fields of length > 1, else lines over
    the one swept field (or the designs of a list), with the speeds of a per-speed figure as the other axis."""
    var = _variable(ds, var)
    dims = [d for d in ds[var].dims if ds.sizes[d] > 1]
    design_dims = [d for d in dims if d in _design_dims(ds)]
    if len(design_dims) >= 2:
        return heatmap(ds, var, x=design_dims[0], y=design_dims[1], ax=ax, path=path, title=title)
    if len(dims) >= 2:
        return heatmap(ds, var, x=dims[0], y=dims[1], ax=ax, path=path, title=title)
    x = dims[0] if dims else ds[var].dims[0]
    return lines(ds, var, x=x, hue=None, ax=ax, path=path, title=title)
