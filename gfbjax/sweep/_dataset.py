"""The consolidated result of a sweep as an ``xarray.Dataset`` (layout in :func:`gfbjax.sweep.run_sweep`)."""

from __future__ import annotations

import json
import math
from typing import Any, Sequence

import numpy as np

from ._analyses import Analysis
from ._designs import DesignSet

__all__ = ["build_dataset", "FORMAT"]

FORMAT = "gfbjax.sweep"


def _coord(values: Sequence[Any]) -> np.ndarray:
    """A coordinate array: floats (None, an unset optional field, as NaN), ints or strings."""
    if all(isinstance(v, str) for v in values):
        return np.asarray(values, dtype=str)
    if all(isinstance(v, int) and not isinstance(v, bool) for v in values):
        return np.asarray(values, dtype=np.int64)
    return np.asarray([math.nan if v is None else float(v) for v in values], dtype=float)


def _float(v: Any) -> float:
    if v is None:
        return math.nan
    if isinstance(v, str):  # JSON's names of the infinities (see _store._jsonable)
        return float(v) if v in ("inf", "-inf") else math.nan
    return float(v)


def build_dataset(designs: DesignSet, analyses: Sequence[Analysis], records: Sequence[dict[str, Any]],
                  attrs: dict[str, Any]) -> Any:
    """The Dataset of a sweep from one record per design (in the order of ``designs``)."""
    import xarray as xr

    from .. import __version__

    shape, dims = designs.shape, designs.dims
    n = len(designs)
    coords: dict[str, Any] = {}
    if designs.kind == "grid":
        for f in designs.fields:
            coords[f] = ((f,), _coord(designs.values[f]), {"long_name": f"SystemSpec.{f} (swept)"})
    else:
        coords["design"] = (("design",), np.arange(n))
        for f in designs.fields:
            coords[f] = (("design",), _coord(designs.values[f]), {"long_name": f"SystemSpec.{f} of each design"})
    data: dict[str, Any] = {}
    for a in analyses:
        speed_dim = f"{a.name}_omega_bar"
        if a.speeds:
            coords[speed_dim] = ((speed_dim,), np.asarray(a.speeds, float),
                                 {"units": "Omega_bar = Omega t*", "long_name": f"speeds of the {a.name} analysis"})
        for fig in a.figures:
            extra = (len(a.speeds),) if fig.per_speed else ()
            vdims = dims + ((speed_dim,) if fig.per_speed else ())
            flat = [rec["figures"].get(fig.name) for rec in records]
            if fig.text:
                arr = np.full((n,) + extra, "", dtype=object)
                for i, v in enumerate(flat):
                    if v is not None:
                        arr[i] = v
                arr = arr.astype(str)
            else:
                arr = np.full((n,) + extra, math.nan)
                for i, v in enumerate(flat):
                    if v is not None:
                        arr[i] = [_float(x) for x in v] if fig.per_speed else _float(v)
            vattrs = {"long_name": fig.long_name, "analysis": a.name}
            if fig.units:
                vattrs["units"] = fig.units
            data[fig.name] = (vdims, arr.reshape(shape + extra), vattrs)
    data["outcome"] = (dims, np.asarray([r["outcome"] for r in records], dtype=str).reshape(shape),
                       {"long_name": "ok: every analysis ran; partial: some raised; failed: all raised (see message)"})
    data["message"] = (dims, np.asarray([r["message"] for r in records], dtype=str).reshape(shape),
                       {"long_name": "why analyses of the design failed ('' when none did)"})
    data["seconds"] = (dims, np.asarray([_float(r.get("seconds")) for r in records]).reshape(shape),
                       {"units": "s", "long_name": "wall time of the design's analyses when it was computed "
                                                   "(NaN: its task was lost)"})
    data["design_key"] = (dims, np.asarray([r["key"] for r in records], dtype=str).reshape(shape),
                          {"long_name": "name of the design's stored record (designs/<key>.json)"})
    base_attrs = {
        "format": FORMAT, "version": 1, "gfbjax_version": __version__,
        "designs_kind": designs.kind, "swept_fields": json.dumps(list(designs.fields)),
        "analyses": json.dumps([a.name for a in analyses]),
        "analyses_settings": json.dumps([a.settings() for a in analyses]),
        "units": json.dumps({name: v[2].get("units", "") for name, v in data.items()}),
        "n_designs": n, "n_failed": int(sum(r["outcome"] == "failed" for r in records)),
        "n_partial": int(sum(r["outcome"] == "partial" for r in records)),
    }
    base_attrs.update(attrs)
    return xr.Dataset(data, coords=coords, attrs=base_attrs)
