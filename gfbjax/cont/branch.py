"""Continuation results: ``Branch`` (stacked numpy arrays) with npz + JSON storage.

File format (readable with plain numpy + json, no gfbjax needed)
---------------------------------------------------------------
``save(path)`` writes ``<path>.npz`` and ``<path>.json``.

npz keys (P = number of points):

- ``lam`` (P,), ``period`` (P,) (NaN for equilibria), ``l2`` (P,) L2 norm
  sqrt(int_0^1 |x|^2 dt) of the cycle (|x| for equilibria),
- ``xmax``/``xmin`` (P, k): max/min over the cycle of the recorded components,
- ``multipliers`` (P, n) complex: Floquet multipliers sorted by decreasing
  modulus (eigenvalues of df/dx for equilibria, sorted by decreasing real part),
- ``stable`` (P,) bool, ``trivial_error`` (P,) |mu_trivial - 1| (NaN for equilibria),
- ``newton_iterations`` (P,) int, ``ds`` (P,) step length that produced the point,
- ``tangent_lam`` (P,) lam-component of the normalised tangent,
- optional ``state_<name>`` arrays (full states of every point: ``xm`` (P,N+1,n),
  ``xi`` (P,N,m-1,n), ``T``, ``lam``, ``mesh`` (N+1,) for cycles; ``x`` (P,n) for
  equilibria), and ``special<i>_<name>`` for the state of special point i.

JSON sidecar: ``kind`` ("cycles"|"equilibria"), ``components`` (recorded state
indices), ``reason`` (why the branch ended), ``special`` (list of dicts with
``type`` in {"LPC","PD","NS","HOPF","FOLD","BP"}, ``index`` (row in the arrays),
``lam``, ``period``, ``multipliers`` as [re, im] pairs, ``angle`` (NS: arg mu in
radians, HOPF: omega), ``m`` (collocation degree) and ``keys`` (this list).
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

ARRAY_KEYS = ("lam", "period", "l2", "xmax", "xmin", "multipliers", "stable", "trivial_error",
              "newton_iterations", "ds", "tangent_lam")


@dataclass
class PointRecord:
    lam: float
    period: float
    l2: float
    xmax: np.ndarray
    xmin: np.ndarray
    multipliers: np.ndarray
    stable: bool
    trivial_error: float
    newton_iterations: int
    ds: float
    tangent_lam: float
    state: dict[str, np.ndarray] | None = None


@dataclass
class Branch:
    """A computed branch; every array has the point index as leading axis."""

    kind: str
    components: list[int]
    lam: np.ndarray
    period: np.ndarray
    l2: np.ndarray
    xmax: np.ndarray
    xmin: np.ndarray
    multipliers: np.ndarray
    stable: np.ndarray
    trivial_error: np.ndarray
    newton_iterations: np.ndarray
    ds: np.ndarray
    tangent_lam: np.ndarray
    special: list[dict[str, Any]] = field(default_factory=list)
    reason: str = ""
    states: dict[str, np.ndarray] | None = None
    special_states: list[dict[str, np.ndarray]] = field(default_factory=list)
    m: int | None = None

    def __len__(self) -> int:
        return len(self.lam)

    @classmethod
    def from_points(cls, kind: str, components: list[int], points: list[PointRecord],
                    special: list[dict[str, Any]], special_states: list[dict[str, np.ndarray]],
                    reason: str, m: int | None = None, shared_state: dict[str, np.ndarray] | None = None) -> "Branch":
        def stack(name, dtype=float, shape=(0,)):
            vals = [getattr(p, name) for p in points]
            return np.array(vals, dtype=dtype) if vals else np.zeros(shape, dtype)

        k = len(components)
        nmu = len(points[0].multipliers) if points else 0
        states = None
        if points and all(p.state is not None for p in points):
            states = {key: np.stack([p.state[key] for p in points]) for key in points[0].state}
            if shared_state:
                states.update(shared_state)
        return cls(kind, list(components), stack("lam"), stack("period"), stack("l2"),
                   stack("xmax", shape=(0, k)), stack("xmin", shape=(0, k)),
                   stack("multipliers", complex, (0, nmu)), stack("stable", bool),
                   stack("trivial_error"), stack("newton_iterations", int), stack("ds"),
                   stack("tangent_lam"), list(special), reason, states, list(special_states), m)

    # ------------------------------------------------------------------ io
    def save(self, path: str | Path) -> tuple[Path, Path]:
        path = Path(path)
        base = path.with_suffix("") if path.suffix in (".npz", ".json") else path
        arrays = {key: getattr(self, key) for key in ARRAY_KEYS}
        if self.states is not None:
            arrays.update({f"state_{k}": v for k, v in self.states.items()})
        for i, st in enumerate(self.special_states):
            arrays.update({f"special{i}_{k}": v for k, v in st.items()})
        npz = base.with_name(base.name + ".npz")
        js = base.with_name(base.name + ".json")
        np.savez(npz, **arrays)
        meta = {"kind": self.kind, "components": self.components, "reason": self.reason, "m": self.m,
                "special": [_jsonable(s) for s in self.special], "keys": sorted(arrays)}
        js.write_text(json.dumps(meta, indent=1))
        return npz, js

    @classmethod
    def load(cls, path: str | Path) -> "Branch":
        path = Path(path)
        base = path.with_suffix("") if path.suffix in (".npz", ".json") else path
        meta = json.loads(base.with_name(base.name + ".json").read_text())
        with np.load(base.with_name(base.name + ".npz")) as z:
            data = {k: z[k] for k in z.files}
        states = {k[6:]: v for k, v in data.items() if k.startswith("state_")} or None
        sp_states: list[dict[str, np.ndarray]] = []
        i = 0
        while any(k.startswith(f"special{i}_") for k in data):
            pre = f"special{i}_"
            sp_states.append({k[len(pre):]: v for k, v in data.items() if k.startswith(pre)})
            i += 1
        special = []
        for s in meta["special"]:
            s = dict(s)
            if "multipliers" in s and s["multipliers"] is not None:
                s["multipliers"] = np.array([complex(a, b) for a, b in s["multipliers"]])
            special.append(s)
        return cls(meta["kind"], meta["components"], *(data[k] for k in ARRAY_KEYS), special=special,
                   reason=meta["reason"], states=states, special_states=sp_states, m=meta.get("m"))

    def special_of(self, kind: str) -> list[dict[str, Any]]:
        return [s for s in self.special if s["type"] == kind]


def _jsonable(d: dict[str, Any]) -> dict[str, Any]:
    out = {}
    for k, v in d.items():
        if isinstance(v, np.ndarray) and np.iscomplexobj(v):
            out[k] = [[float(z.real), float(z.imag)] for z in v]
        elif isinstance(v, np.ndarray):
            out[k] = v.tolist()
        elif isinstance(v, (np.floating, np.integer, np.bool_)):
            out[k] = v.item()
        else:
            out[k] = v
    return out
