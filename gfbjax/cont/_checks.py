"""Checks of the engine's inputs, each kind written once: numbers in a range, flags, orientations, choices from a
set, and the start of a branch.  Every settings class, problem, solver and entry point of :mod:`gfbjax.cont`
uses these, so that a value is refused the same way wherever it is given, before any work, by a ``ValueError``
that names the field, the value and what is allowed.

Values are also normalised: NumPy scalars become Python numbers and a list of choices a tuple, so that frozen
settings stay hashable and print the way they were meant (``grow=1.2``, not ``grow=np.float64(1.2)``).
Booleans are never numbers here (``dlam_max=True`` is refused), and a float is never an integer or an
orientation (``direction=1.0`` is refused), because such values are almost always a field given the wrong thing.
"""
from __future__ import annotations

import numbers
from typing import Any, Iterable

import numpy as np

__all__ = ["check_range", "check_flag", "check_sign", "check_choices", "check_field_at", "check_mesh", "check_finite",
           "check_start", "store", "store_range"]


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
    """``values`` as a float array; ``ValueError`` naming the first non-finite entries (NaN or inf)."""
    arr = np.asarray(values, dtype=float)
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
