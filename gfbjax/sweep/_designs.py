"""The designs of a sweep: a grid (outer product of per-field value lists) or an explicit list of field changes,
each one checked and turned into a :class:`~gfbjax.params.SystemSpec` before anything is computed."""

from __future__ import annotations

import dataclasses
import itertools
import math
import types
import typing
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from ..params import ParameterError, SystemSpec

__all__ = ["DesignSet", "design_set", "field_types", "normalize_value"]


def field_types() -> dict[str, Any]:
    """``{field: type}`` of every :class:`SystemSpec` field (``float``, ``int``, ``str`` or ``float | None``)."""
    return typing.get_type_hints(SystemSpec)


def _allowed() -> str:
    return ", ".join(f.name for f in dataclasses.fields(SystemSpec))


def normalize_value(name: str, value: Any, label: str) -> Any:
    """``value`` as the Python type of field ``name`` (float fields get floats, so that ``1`` and ``1.0`` name one
    design and one stored result); ParameterError naming ``label`` for an unknown field or a value of the wrong
    kind.  Ranges are checked by :class:`SystemSpec` itself."""
    hints = field_types()
    if name not in hints:
        raise ParameterError(f"{label}: {name!r} is not a SystemSpec field; allowed: {_allowed()}")
    tp = hints[name]
    optional = False
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        optional, tp = True, args[0]
    if value is None:
        if optional:
            return None
        raise ParameterError(f"{label}: {name} = None is not allowed (a {tp.__name__} is needed)")
    if isinstance(value, np.generic):
        value = value.item()
    if tp is str:
        if not isinstance(value, str):
            raise ParameterError(f"{label}: {name} must be a string, got {value!r}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{label}: {name} must be a{'n integer' if tp is int else ' real number'}, "
                             f"got {value!r}")
    if tp is int:
        if isinstance(value, float) and not (math.isfinite(value) and value == int(value)):
            raise ParameterError(f"{label}: {name} must be an integer, got {value!r}")
        return int(value)
    return float(value)


@dataclass(frozen=True)
class DesignSet:
    """Checked designs of a sweep.

    Attributes:
        kind: ``"grid"`` (outer product; the Dataset has one dimension per swept field) or ``"list"`` (one
            dimension ``design``).
        fields: the swept fields, in order (grid: the dimension order; list: every field that any design sets).
        values: grid: ``{field: tuple of values}`` (the coordinates); list: ``{field: per-design values}``, the
            base value where a design leaves the field alone.
        changes: one dict of field changes per design, in C order of the grid.
        specs: the SystemSpec of each design (``base.replace(**changes)``), all validated.
    """

    kind: str
    fields: tuple[str, ...]
    values: dict[str, tuple[Any, ...]]
    changes: tuple[dict[str, Any], ...]
    specs: tuple[SystemSpec, ...]

    @property
    def shape(self) -> tuple[int, ...]:
        """Shape of the Dataset's design dimensions: one length per grid field, or ``(n_designs,)``."""
        if self.kind == "grid":
            return tuple(len(self.values[f]) for f in self.fields)
        return (len(self.changes),)

    @property
    def dims(self) -> tuple[str, ...]:
        return self.fields if self.kind == "grid" else ("design",)

    def __len__(self) -> int:
        return len(self.changes)

    def to_json(self) -> dict[str, Any]:
        return {"kind": self.kind, "fields": list(self.fields),
                "values": {k: list(v) for k, v in self.values.items()},
                "changes": [dict(c) for c in self.changes]}


def _spec(base: SystemSpec, changes: dict[str, Any], label: str) -> SystemSpec:
    try:
        return base.replace(**changes)
    except ParameterError as exc:
        raise ParameterError(f"{label}: {exc}") from None
    except (TypeError, ValueError) as exc:  # a value SystemSpec's checks cannot even compare (e.g. a list)
        raise ParameterError(f"{label}: {exc}") from None


def design_set(base: SystemSpec, grid: Mapping[str, Sequence[Any]] | None = None,
               designs: Sequence[Mapping[str, Any]] | None = None) -> DesignSet:
    """Check and expand the designs of a sweep: exactly one of ``grid`` and ``designs``.

    Args:
        base: the system every design starts from.
        grid: ``{field: values}``; the designs are the outer product, the first field varying slowest.  Each field
            needs at least one value and no repeated values.
        designs: a list of ``{field: value}`` dicts, one per design (an empty dict is the base system).

    Raises:
        ParameterError: naming the field and the allowed values or range, for an unknown field, a value of the
            wrong kind or out of range (as :class:`SystemSpec` checks it), an empty or repeated list; before any
            computation.
    """
    if not isinstance(base, SystemSpec):
        raise ParameterError(f"base must be a SystemSpec, got {type(base).__name__}")
    if (grid is None) == (designs is None):
        raise ParameterError("give either grid={field: values} or designs=[{field: value}, ...], not both or "
                             "neither")
    if grid is not None:
        return _grid(base, grid)
    return _list(base, designs)


def _grid(base: SystemSpec, grid: Mapping[str, Sequence[Any]]) -> DesignSet:
    if not isinstance(grid, Mapping) or not grid:
        raise ParameterError("grid must be a non-empty dict {field: list of values}")
    values: dict[str, tuple[Any, ...]] = {}
    for name, vals in grid.items():
        label = f"grid {name}"
        if isinstance(vals, (str, bytes)) or not hasattr(vals, "__iter__"):
            raise ParameterError(f"{label}: expected a list of values, got {vals!r}")
        if isinstance(vals, np.ndarray) and vals.ndim != 1:
            raise ParameterError(f"{label}: expected a 1-D list of values, got an array of shape {vals.shape}")
        norm = tuple(normalize_value(name, v, label) for v in vals)
        if not norm:
            raise ParameterError(f"{label}: needs at least one value")
        seen = [v for i, v in enumerate(norm) if v in norm[:i]]
        if seen:
            raise ParameterError(f"{label}: repeated value(s) {seen} (each grid value must be distinct)")
        for v in norm:  # the range of each value on its own, so that the message names the value, not a design
            _spec(base, {name: v}, label)
        values[name] = norm
    fields = tuple(values)
    changes = tuple(dict(zip(fields, combo)) for combo in itertools.product(*(values[f] for f in fields)))
    specs = tuple(_spec(base, c, f"grid design {c}") for c in changes)  # combinations (c <= 5% R, e_u <= c)
    return DesignSet("grid", fields, values, changes, specs)


def _list(base: SystemSpec, designs: Sequence[Mapping[str, Any]]) -> DesignSet:
    if isinstance(designs, Mapping) or not hasattr(designs, "__iter__"):
        raise ParameterError("designs must be a list of {field: value} dicts")
    designs = list(designs)
    if not designs:
        raise ParameterError("designs must hold at least one design")
    changes = []
    for i, d in enumerate(designs):
        label = f"designs[{i}]"
        if not isinstance(d, Mapping):
            raise ParameterError(f"{label}: expected a dict {{field: value}}, got {d!r}")
        changes.append({k: normalize_value(k, v, label) for k, v in d.items()})
    specs = tuple(_spec(base, c, f"designs[{i}]") for i, c in enumerate(changes))
    for i, s in enumerate(specs):
        if s in specs[:i]:
            raise ParameterError(f"designs[{i}] = {changes[i]} is the same system as designs[{specs.index(s)}] = "
                                 f"{changes[specs.index(s)]}; each design must be distinct")
    fields = tuple(dict.fromkeys(k for c in changes for k in c))
    values = {f: tuple(getattr(s, f) for s in specs) for f in fields}
    return DesignSet("list", fields, values, tuple(changes), specs)
