"""Checks of the engine's inputs, each kind written once: numbers in a range, flags, orientations, choices from a
set, indices into a branch's points, and the start of a branch (down to every node of a start orbit).  Every
settings class, problem, solver and entry point of :mod:`gfbjax.cont` uses these, so that a value is refused the
same way wherever it is given, before any work, by a ``ValueError`` that names the field, the value and what is
allowed.

Values are also normalised: NumPy scalars become Python numbers and a list of choices a tuple, so that frozen
settings stay hashable and print the way they were meant (``grow=1.2``, not ``grow=np.float64(1.2)``).
Booleans are never numbers here (``dlam_max=True`` is refused), and a float is never an integer or an
orientation (``direction=1.0`` is refused), because such values are almost always a field given the wrong thing.
"""
from __future__ import annotations

import functools
import numbers
from typing import Any, Iterable

import numpy as np

__all__ = ["check_range", "check_flag", "check_sign", "check_choices", "check_index", "check_field_at",
           "check_field_at_nodes", "check_mesh", "check_finite", "check_located_state", "check_nodes", "check_start",
           "store", "store_range"]


def _is_bool(value: Any) -> bool:
    return isinstance(value, (bool, np.bool_))


def _scalar(value: Any) -> Any:
    """A concrete 0-d NumPy or JAX array as its Python number (an orbit's lam is one); anything else as it is."""
    if not isinstance(value, numbers.Number) and getattr(value, "shape", None) == ():
        try:
            return value.item()
        except Exception:  # a JAX tracer has no value yet: left for the type check to refuse
            return value
    return value


def check_range(name: str, value: Any, lo: float, hi: float, *, lo_open: bool = False,
                hi_open: bool = False, integer: bool = False) -> int | float:
    """``value`` as a Python int (``integer``) or float; ``ValueError`` naming ``name`` unless lo <= value <= hi
    (either end open).  Python and NumPy numbers and 0-d arrays are accepted; booleans, NaN, and (with
    ``integer``) 16.0 are not."""
    value = _scalar(value)
    kind = numbers.Integral if integer else numbers.Real
    ok = isinstance(value, kind) and not _is_bool(value)
    ok = ok and (value > lo if lo_open else value >= lo) and (value < hi if hi_open else value <= hi)
    if not ok:
        rng = f"{'(' if lo_open else '['}{lo}, {hi}{')' if hi_open else ']'}"
        raise ValueError(f"{name} must be {'an int' if integer else 'a number'} in {rng}, got {value!r}")
    return int(value) if integer else float(value)


def check_flag(name: str, value: Any) -> bool:
    """``value`` as a bool; ``ValueError`` unless it is True or False (Python, NumPy, 0-d array): ``'yes'``, 1 and
    None are refused."""
    value = _scalar(value)
    if not _is_bool(value):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def check_sign(name: str, value: Any) -> int:
    """``value`` as +1 or -1 (an orientation); ``ValueError`` for anything else, 1.0 and True included."""
    value = _scalar(value)
    if _is_bool(value) or not isinstance(value, numbers.Integral) or value not in (1, -1):
        raise ValueError(f"{name} must be the int +1 or -1, got {value!r}")
    return int(value)


def check_choices(name: str, value: Any, allowed: Iterable[str]) -> tuple[str, ...]:
    """``value`` (a tuple, list or set of strings) as a tuple without repeats, in the given order; ``ValueError``
    for a bare string (``"HOPF"`` would read as its letters) or an entry outside ``allowed``."""
    allowed = tuple(allowed)
    if isinstance(value, str) or not isinstance(value, (tuple, list, set, frozenset)):
        raise ValueError(f"{name} must be a tuple of entries from {allowed}, got {value!r}")
    bad = [v for v in value if v not in allowed]
    if bad:
        raise ValueError(f"{name} entries must be in {allowed}, got {bad!r}")
    return tuple(dict.fromkeys(str(v) for v in value))


def check_index(name: str, value: Any, count: int, items: str, where: str = "the branch") -> int:
    """``value`` as an index in [0, count) into the ``count`` ``items`` of ``where``; negative values count from
    the end, as in Python.  ``ValueError`` naming ``name``, how many items there are and the allowed range, for an
    index outside [-count, count), a float or a bool (True would silently pick item 1), and for any index when
    there are no items; ``where`` names the container in the message (default ``"the branch"``)."""
    value = _scalar(value)
    plural = items if count == 1 else items + "s"
    if count == 0:
        raise ValueError(f"{name} = {value!r} cannot index {where}: it has no {plural}")
    if _is_bool(value) or not isinstance(value, numbers.Integral) or not -count <= value < count:
        raise ValueError(f"{name} must be an int in [{-count}, {count - 1}] ({where} has {count} {plural}), "
                         f"got {value!r}")
    return int(value) % count


def check_mesh(name: str, mesh: Any) -> np.ndarray:
    """A collocation mesh as a float array; ``ValueError`` naming ``name`` unless it runs from 0 to 1, strictly
    increasing, with at least 2 intervals (a start on another mesh would converge to a wrong period)."""
    arr = np.asarray(mesh, dtype=float)
    ok = (arr.ndim == 1 and arr.size >= 3 and np.all(np.isfinite(arr)) and arr[0] == 0.0 and arr[-1] == 1.0
          and np.all(np.diff(arr) > 0.0))
    if not ok:
        raise ValueError(f"{name} must increase strictly from 0 to 1 with at least 2 intervals, got "
                         f"{np.array2string(arr, threshold=8, precision=4)}")
    return arr


def check_finite(name: str, values: Any) -> np.ndarray:
    """``values`` as a float array (complex ones stay complex); ``ValueError`` naming the first non-finite entries
    (NaN or inf)."""
    arr = np.asarray(values)
    # a cast to float would drop the imaginary part of an eigenvector, with only a warning
    arr = arr.astype(complex if np.iscomplexobj(arr) else float, copy=False)
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        shown = ", ".join(f"[{int(i)}] = {arr.flat[i]}" for i in bad[:5]) + (" ..." if bad.size > 5 else "")
        raise ValueError(f"{name} must be finite; {bad.size} of its {arr.size} entries are not: {shown}")
    return arr


def check_field_at(f: Any, x: Any, lam: float, args: Any, where: str) -> None:
    """``ValueError`` when the vector field is NaN or inf at the start state ``x`` (``where`` names it), naming the
    first such components: the corrections would fail there with nothing to say why."""
    import jax.numpy as jnp

    out = np.asarray(f(jnp.asarray(x, float), lam, args), float)
    bad = np.flatnonzero(~np.isfinite(out))
    if bad.size:
        shown = ", ".join(str(int(i)) for i in bad[:5]) + (" ..." if bad.size > 5 else "")
        raise ValueError(f"f(x, lam, args) is NaN or inf at {where} (lam = {lam:g}), in components {shown}: check "
                         "the vector field and the start")


def _node_report(bad: np.ndarray, times: np.ndarray, mesh: np.ndarray, noun: str = "node") -> tuple[str, str, str]:
    """Where the earliest flagged ``noun`` lies (``bad`` (K, n), at ``times`` (K,) on ``mesh``), how many more are
    flagged, and the flagged components of the earliest one: the three parts of a node message."""
    rows = np.flatnonzero(bad.any(axis=1))
    first = rows[np.argmin(times[rows])]
    t = float(times[first])
    j = int(np.searchsorted(mesh, t, side="right")) - 1
    if mesh[j] == t:
        place = f"{'first node' if t == mesh[0] else noun} t = {t:.4g} (mesh[{j}])"
    else:
        place = f"{noun} t = {t:.4g} (in mesh interval [mesh[{j}], mesh[{j + 1}]] = [{mesh[j]:.4g}, {mesh[j + 1]:.4g}])"
    more = f", and at {rows.size - 1} more of its {len(times)} {noun}s" if rows.size > 1 else ""
    comps = np.flatnonzero(bad[first])
    return place, more, ", ".join(str(int(c)) for c in comps[:5]) + (" ..." if comps.size > 5 else "")


def check_nodes(name: str, values: Any, times: Any, mesh: Any) -> None:
    """``ValueError`` when states at nodes of an orbit are NaN or inf: ``values`` (K, n) at the scaled times
    ``times`` (K,) in [0, 1] on the collocation ``mesh``.  The message names ``name``, the earliest such node by
    its time and its mesh point or interval, its components and how many nodes are affected (a flat index into an
    (N, m-1, n) array says none of this)."""
    arr = np.asarray(values, float)
    bad = ~np.isfinite(arr)
    if bad.any():
        place, more, comps = _node_report(bad, np.asarray(times, float), np.asarray(mesh, float))
        raise ValueError(f"{name} must be finite; it is NaN or inf at its {place}, in components {comps}{more}")


@functools.cache
def _field_on_rows() -> Any:
    import jax

    # f static: compiled once per vector field, like the engine's own kernels
    return jax.jit(lambda f, X, lam, args: jax.vmap(lambda x: f(x, lam, args))(X), static_argnums=0)


def check_field_at_nodes(f: Any, nodes: Any, times: Any, mesh: Any, lam: float, args: Any, where: str) -> None:
    """:func:`check_field_at` at points of an orbit (``nodes`` (K, n): its nodes and collocation points, at the
    scaled ``times`` (K,) on ``mesh``; ``where`` names the orbit), in one compiled, vmapped evaluation:
    ``ValueError`` naming the earliest point where f is NaN or inf, by its time and mesh point or interval, its
    components and how many points are affected.  A field that fails on part of an orbit only passes a check at its first node, and Newton then
    fails there with nothing to say why."""
    import jax.numpy as jnp

    out = np.asarray(_field_on_rows()(f, jnp.asarray(nodes, float), lam, args), float)
    bad = ~np.isfinite(out)
    if bad.any():
        place, more, comps = _node_report(bad, np.asarray(times, float), np.asarray(mesh, float), "point")
        raise ValueError(f"f(x, lam, args) is NaN or inf at {where}'s {place}, in components {comps}{more} (lam = "
                         f"{lam:g}): check the vector field and the start")


def check_located_state(branch: Any, point: Any, advice: str) -> dict:
    """The stored state of the special ``point`` of ``branch``, to start from; ``ValueError`` when the point was not
    located (its state is then not the bifurcation: ``advice`` says what to do) or has no stored state."""
    if not point.located:
        raise ValueError(f"the {point.type} point near lam = {point.lam:.6g} was not located ({point.localisation}): "
                         f"its state is not the bifurcation; {advice}")
    if not (isinstance(point.state, numbers.Integral) and 0 <= point.state < len(branch.special_states)):
        raise ValueError(f"the {point.type} point near lam = {point.lam:.6g} has no stored state in branch (state = "
                         f"{point.state!r}, {len(branch.special_states)} stored)")
    return branch.special_states[point.state]


def check_start(settings: Any, lam0: Any, name: str = "lam0") -> float:
    """The start parameter as a float; ``ValueError`` naming ``name`` when it is not finite or lies outside the
    settings' [lam_min, lam_max] (a branch that starts outside its bounds would record a point there and then
    jump to the bound)."""
    lam = check_range(name, lam0, -np.inf, np.inf, lo_open=True, hi_open=True)
    if not settings.lam_min <= lam <= settings.lam_max:
        raise ValueError(f"{name} = {lam:g} lies outside the continuation's bounds [lam_min, lam_max] = "
                         f"[{settings.lam_min:g}, {settings.lam_max:g}]; start inside them or widen them")
    return lam


def store(obj: Any, name: str, value: Any) -> None:
    """Set a checked, normalised field on a frozen dataclass (inside its ``__post_init__``)."""
    object.__setattr__(obj, name, value)


def store_range(obj: Any, name: str, lo: float, hi: float, **kw: Any) -> None:
    """:func:`check_range` of the field ``name`` of ``obj`` (its own name in the message), stored normalised."""
    store(obj, name, check_range(name, getattr(obj, name), lo, hi, **kw))
