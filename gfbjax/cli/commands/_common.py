"""Options and helpers shared by the ``gfbjax`` subcommands.

Use in a command module::

    from ._common import add_system_options, spec_from_args, output_dir, traced_params

    def register(subparsers):
        p = subparsers.add_parser("mycmd", help="...", description="...")
        add_system_options(p, command="mycmd")
        p.add_argument(...)
        p.set_defaults(func=run)
        return p

    def run(args) -> int:
        spec = spec_from_args(args)          # SystemSpec, checked; ParameterError names the bad field
        params = traced_params(spec)         # Params with array leaves (no recompilation per value)
        out = output_dir(args)               # pathlib.Path, created
        ...
        return 0

Errors in the input are raised as :class:`gfbjax.ParameterError`; :func:`gfbjax.cli.main` turns them into a one-line
message and exit status 2.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import tempfile
import types
import typing
from pathlib import Path
from typing import Any, Iterable

from ... import limits
from ...params import VARIATIONS, ParameterError, SystemSpec, system_from_name_or_file

__all__ = [
    "SYSTEM_NAMES",
    "add_system_options",
    "spec_from_args",
    "parse_set",
    "output_dir",
    "traced_params",
    "float_list",
    "check_option",
    "check_range",
    "write_json",
    "write_summary",
    "to_jsonable",
]

SYSTEM_NAMES = tuple(VARIATIONS) + ("validation10N", "validation15N")


def _field_doc() -> str:
    """Field names of SystemSpec with their type, for the --set help."""
    hints = typing.get_type_hints(SystemSpec)
    parts = []
    for f in dataclasses.fields(SystemSpec):
        t = hints[f.name]
        name = getattr(t, "__name__", None) or str(t).replace("typing.", "")
        parts.append(f"{f.name} ({name})")
    return ", ".join(parts)


def add_system_options(parser: argparse.ArgumentParser, command: str) -> None:
    """Add ``--system``, ``--set``, ``--nx``, ``--nz`` and ``--out`` (default ``results/<command>``)."""
    g = parser.add_argument_group("system", "which rotor-bearing system to analyse (SI inputs; see gfbjax.SystemSpec)")
    g.add_argument(
        "--system", default="reference", metavar="NAME|FILE.toml",
        help=("named system: " + ", ".join(SYSTEM_NAMES) + " (the paper's design variations of the reference "
              "system, DESIGN.md; validation10N/15N: rigid rotor of Table 1), or a .toml file of SystemSpec fields "
              "with an optional 'base' key naming one of these (default: %(default)s)"))
    g.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="FIELD=VALUE",
        help=("override a SystemSpec field, repeatable, e.g. --set alpha_f=0.3 --set rotor=rigid; the value is "
              "converted to the field's type ('none' for an optional field). Fields: " + _field_doc()))
    g.add_argument("--nx", type=int, default=None, metavar="N",
                   help="circumferential finite-difference intervals over the 2 pi of the foil (SystemSpec.Nx; "
                        f"default {SystemSpec.Nx}, in {limits.NX.interval()})")
    g.add_argument("--nz", type=int, default=None, metavar="N",
                   help="axial intervals over the half length, edge to mid-plane (SystemSpec.Nz; "
                        f"default {SystemSpec.Nz}, in {limits.NZ.interval()}); the grid's (Nx - 1)(Nz + 1) states "
                        f"plus the rotor's must not exceed {limits.MAX_DENSE_UNKNOWNS} (dense Jacobians)")
    g.add_argument("--out", type=Path, default=Path("results") / command, metavar="DIR",
                   help="output folder, created if needed and checked to be writable before any computation "
                        "(default: %(default)s)")


def _convert(name: str, text: str, tp: Any) -> Any:
    """Convert ``text`` to the type ``tp`` of field ``name`` (float, int, str, bool, or an Optional of these)."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if text.strip().lower() in ("none", "null", ""):
            return None
        if len(args) == 1:
            return _convert(name, text, args[0])
    if tp is bool:
        low = text.strip().lower()
        if low in ("1", "true", "yes", "on"):
            return True
        if low in ("0", "false", "no", "off"):
            return False
        raise ParameterError(f"--set {name}: expected true or false, got {text!r}")
    if tp is int:
        try:
            return int(text)
        except ValueError:
            try:
                v = float(text)
            except ValueError:
                v = math.nan
            if math.isfinite(v) and v == int(v):
                return int(v)
            raise ParameterError(f"--set {name}: expected an integer, got {text!r}") from None
    if tp is float:
        try:
            return float(text)
        except ValueError:
            low = text.strip().lower()
            consts = {"pi": math.pi, "-pi": -math.pi, "pi/2": math.pi / 2, "-pi/2": -math.pi / 2,
                      "2pi": 2 * math.pi, "3pi/2": 1.5 * math.pi}
            if low in consts:
                return consts[low]
            raise ParameterError(f"--set {name}: expected a real number, got {text!r}") from None
    if tp is str:
        return text
    raise ParameterError(f"--set {name}: fields of type {tp} cannot be set from the command line")


def parse_set(items: Iterable[str]) -> dict[str, Any]:
    """``["FIELD=VALUE", ...]`` -> ``{field: typed value}``; unknown fields and bad values raise ParameterError."""
    hints = typing.get_type_hints(SystemSpec)
    out: dict[str, Any] = {}
    for item in items:
        if "=" not in item:
            raise ParameterError(f"--set expects FIELD=VALUE, got {item!r}")
        name, text = (s.strip() for s in item.split("=", 1))
        if name not in hints:
            raise ParameterError(f"--set {name}: unknown SystemSpec field; allowed: {', '.join(hints)}")
        out[name] = _convert(name, text, hints[name])
    return out


def spec_from_args(args: argparse.Namespace) -> SystemSpec:
    """The SystemSpec of ``--system`` with ``--set``, ``--nx`` and ``--nz`` applied (all checked)."""
    spec = system_from_name_or_file(args.system)
    changes = parse_set(getattr(args, "overrides", []) or [])
    if getattr(args, "nx", None) is not None:
        changes["Nx"] = args.nx
    if getattr(args, "nz", None) is not None:
        changes["Nz"] = args.nz
    return spec.replace(**changes) if changes else spec


def traced_params(spec: SystemSpec):
    """``spec.nondim()`` with every float leaf a JAX array (:meth:`gfbjax.Params.traced`)."""
    return spec.nondim().traced()


def output_dir(args: argparse.Namespace) -> Path:
    """``--out`` as a created, writable folder (checked by writing a probe file, so that a read-only folder or
    file system fails here, before the computation, and not when the results are written)."""
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ParameterError(f"--out {str(out)!r} is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"--out {str(out)!r} cannot be created: {exc.strerror or exc}") from None
    if not out.is_dir():
        raise ParameterError(f"--out {str(out)!r} is not a folder")
    try:
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as exc:
        raise ParameterError(f"--out {str(out)!r} is not writable: {exc.strerror or exc}") from None
    return out


def float_list(option: str, rng: limits.Range | None = None, *, increasing: bool = False):
    """An argparse ``type`` for comma-separated numbers, each checked against ``rng`` (a
    :class:`gfbjax.limits.Range`); argparse reports errors with the option's name."""
    def parse(text: str) -> list[float]:
        try:
            vals = [float(v) for v in text.replace(" ", "").split(",") if v != ""]
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None
        if not vals:
            raise argparse.ArgumentTypeError("expected at least one number")
        for v in vals:
            try:
                check_range(option, v, rng)
            except ParameterError as exc:
                raise argparse.ArgumentTypeError(str(exc).removeprefix(f"{option} = ")) from None
        if increasing and any(b <= a for a, b in zip(vals, vals[1:])):
            raise argparse.ArgumentTypeError(f"values must increase, got {text!r}")
        return vals
    return parse


def check_range(option: str, value: Any, rng: limits.Range | None) -> Any:
    """Check an option against a named range of :mod:`gfbjax.limits` (None: any finite number); the message names
    the option, e.g. ``--speed = 60 is outside the allowed range (0, 50] (dimensionless speed ...)``."""
    return (rng or limits.Range(option)).check(value, option)


def check_option(option: str, value: float, lo: float | None = None, hi: float | None = None, *,
                 lo_open: bool = False, what: str = "", integer: bool = False) -> Any:
    """Check a numeric option that has no named range in :mod:`gfbjax.limits` (a step size, a count of points);
    ParameterError naming ``option`` and the range."""
    return limits.Range(option, lo, hi, lo_open=lo_open, what=what, integer=integer).check(value)


def to_jsonable(obj: Any) -> Any:
    """Convert numpy/jax scalars and arrays, complex numbers, paths and dataclasses to JSON types."""
    import numpy as np

    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, complex):
        return [obj.real, obj.imag]
    if isinstance(obj, (np.generic,)):
        return to_jsonable(obj.item())
    if hasattr(obj, "__array__") and not isinstance(obj, (str, bytes)):
        return to_jsonable(np.asarray(obj).tolist())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None if math.isnan(obj) else ("inf" if obj > 0 else "-inf")
    return obj


def write_json(path: Path, data: Any) -> Path:
    path.write_text(json.dumps(to_jsonable(data), indent=2) + "\n")
    return path


def write_summary(out: Path, name: str, data: dict) -> Path:
    """Write a command's summary ``out/name`` and report ``data['files']`` and ``data['timings_s']['total']``."""
    path = write_json(out / name, data)
    print(f"  wrote             {out}/: " + ", ".join(data["files"]) + f"  ({data['timings_s']['total']:.1f} s)",
          flush=True)
    return path


def check_continuation_options(args: argparse.Namespace) -> None:
    """Checks shared by the continuation commands: speed range --start/--end, steps --ds/--ds-max, --max-points."""
    check_range("--start", args.start, limits.SPEED)
    check_range("--end", args.end, limits.SPEED)
    if args.start == args.end:
        raise ParameterError("--end must differ from --start")
    check_option("--ds", args.ds, 0.0, None, lo_open=True, what="arclength step")
    check_option("--ds-max", args.ds_max, 0.0, None, lo_open=True, what="arclength step")
    if args.ds_max < args.ds:
        raise ParameterError(f"--ds-max = {args.ds_max:g} must be at least --ds = {args.ds:g}")
    check_option("--max-points", args.max_points, 2, 10**6, what="points", integer=True)
