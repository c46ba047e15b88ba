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
from ...params import PRESETS, VARIATIONS, ParameterError, SystemSpec, system_from_name_or_file

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
    "add_speed_option",
    "resolve_speeds",
    "speed_si",
    "work_unit_J",
    "branch_row_um",
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


def _folder(text: str) -> Path:
    """An argparse ``type`` for ``--out``: ``Path("")`` would be the current folder, so an empty string (an unset
    shell variable, say) is refused instead of writing the results there."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a folder, got an empty string")
    return Path(text)


def add_system_options(parser: argparse.ArgumentParser, command: str) -> None:
    """Add ``--system``, ``--preset``, ``--set``, ``--nx``, ``--nz`` and ``--out`` (default ``results/<command>``)."""
    g = parser.add_argument_group("system", "which rotor-bearing system to analyse (SI inputs; see gfbjax.SystemSpec)")
    g.add_argument(
        "--system", default="reference", metavar="NAME|FILE.toml",
        help=("named system: " + ", ".join(SYSTEM_NAMES) + " (the paper's design variations of the reference "
              "system, docs/model.md; validation10N/15N: rigid rotor of Table 1), or a .toml file of SystemSpec fields "
              "with an optional 'base' key naming one of these (default: %(default)s)"))
    g.add_argument(
        "--preset", default=None, choices=tuple(PRESETS),
        help=("convention preset applied to the system before --set (gfbjax.params.PRESETS, docs/model.md): "
              "'corrected' (foil damping c_f = eta k_f / Omega_bar, unbalance e_u / c on the disc, omega_r in "
              "rad/s: the defaults) or 'paper' (the paper read literally: c_f = eta k_f, the unbalance "
              "(m_d + 2 m_j) e_u carried by the disc, omega_r in rpm); default: the system's own"))
    g.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="FIELD=VALUE",
        help=("override a SystemSpec field, repeatable, e.g. --set alpha_f=0.3 --set rotor=rigid; the value is "
              "converted to the field's type ('none' for an optional field). Fields: " + _field_doc()))
    g.add_argument("--nx", type=int, default=None, metavar="N",
                   help="circumferential finite-difference intervals over the 2 pi of the foil (SystemSpec.Nx; "
                        f"default {SystemSpec.Nx}, in {limits.NX.interval()})")
    g.add_argument("--nz", type=int, default=None, metavar="N",
                   help="axial intervals over the half length, edge to mid-plane (SystemSpec.Nz; "
                        f"default {SystemSpec.Nz}, in {limits.NZ.interval()}); the grid's (Nx - 1)(Nz + 1) "
                        "states (about twice as many with axial_domain = \"full\") plus the "
                        f"rotor's must not exceed {limits.MAX_DENSE_UNKNOWNS} (dense Jacobians)")
    g.add_argument("--out", type=_folder, default=Path("results") / command, metavar="DIR",
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
    """The SystemSpec of ``--system`` with ``--preset``, then ``--set``, ``--nx`` and ``--nz`` applied (all
    checked)."""
    spec = system_from_name_or_file(args.system)
    if getattr(args, "preset", None) is not None:
        spec = spec.with_preset(args.preset)
    changes = parse_set(getattr(args, "overrides", []) or [])
    for field, option in (("Nx", "nx"), ("Nz", "nz")):
        value = getattr(args, option, None)
        if value is None:
            continue
        if field in changes and changes[field] != value:  # one would silently win over the other
            raise ParameterError(f"--{option} {value} and --set {field}={changes[field]} disagree: give the grid once")
        changes[field] = value
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
    :class:`gfbjax.limits.Range`), none repeated (a repeated speed or load would be computed twice) and none
    empty (``0.2,,0.4`` is a typo, not two numbers); argparse reports errors with the option's name."""
    def parse(text: str) -> list[float]:
        items = text.replace(" ", "").split(",")
        if "" in items:
            raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got an empty item in {text!r}")
        try:
            vals = [float(v) for v in items]
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None
        repeated = sorted({v for v in vals if vals.count(v) > 1})
        if repeated:
            raise argparse.ArgumentTypeError(f"values must be distinct, {', '.join(f'{v:g}' for v in repeated)} "
                                             f"repeated in {text!r}")
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


def add_step_options(group: Any, *, arclength: bool = True) -> None:
    """The cycle branch's discretisation and step options, with the defaults of ``analyses.cycles.CYCLE_DEFAULTS``
    (the ``sweep`` command leaves out the arclength steps: ``arclength=False``)."""
    from ...analyses.cycles import CYCLE_DEFAULTS as D

    group.add_argument("--m", type=int, default=D["m"], metavar="M",
                       help=f"collocation points per mesh interval, in {limits.COLLOCATION_M.interval()} "
                            f"(default {D['m']})")
    group.add_argument("--N", type=int, default=D["N"], metavar="N",
                       help=f"collocation mesh intervals, in {limits.MESH_N.interval()} (default {D['N']})")
    if arclength:
        group.add_argument("--ds", type=float, default=D["ds"], help=f"initial arclength step (default {D['ds']:g}; "
                           "the first speed step is also capped by --dlam-max)")
        group.add_argument("--ds-max", type=float, default=D["ds_max"],
                           help=f"largest arclength step (default {D['ds_max']:g})")
    group.add_argument("--dlam-max", type=float, default=D["dlam_max"], metavar="DLAM",
                       help=f"largest change of Omega_bar in one step (default {D['dlam_max']:g})")
    group.add_argument("--chord-tol", type=float, default=D["chord_tol"], metavar="TOL",
                       help="straight lines between the points stay within TOL of the plotted curves, each scaled "
                            f"by its range: points gather where the branch bends (default {D['chord_tol']:g}; "
                            "inf: steps set by the step options alone; --chord-tol inf --dlam-max 0.02 gives the "
                            "fixed speed step of versions before 2026-12)")
    group.add_argument("--max-points", type=int, default=D["max_points"], metavar="P",
                       help=f"most points on the branch, in [2, 10^6] (default {D['max_points']})")


def check_chord_tol(value: float) -> float:
    """--chord-tol in [CHORD_TOL_MIN, inf] (inf: no chord limit); ParameterError naming the option otherwise."""
    from ...cont._settings import CHORD_TOL_MIN

    if not (isinstance(value, float) and CHORD_TOL_MIN <= value <= math.inf):
        raise ParameterError(f"--chord-tol = {value!r} is outside the allowed range [{CHORD_TOL_MIN:g}, inf] "
                             "(inf: no chord limit)")
    return value


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


# -- speeds in Omega_bar or rpm -------------------------------------------------------------------------------------
# One scheme for every command: each speed option --X (Omega_bar) has a twin --X-rpm (rev/min), mutually exclusive;
# resolve_speeds() converts the rpm twin with the system's t* and writes Omega_bar back into args.X.


def add_speed_option(group: Any, flag: str, *, default: float | None, help: str, rpm_flag: str | None = None,
                     metavar: str = "OMEGA_BAR") -> None:
    """Add ``flag`` (a speed in Omega_bar) and its rpm twin (``rpm_flag``, default ``flag + "-rpm"``) as a mutually
    exclusive pair to ``group``; :func:`resolve_speeds` turns the twin into Omega_bar."""
    ex = group.add_mutually_exclusive_group()
    ex.add_argument(flag, type=float, default=default, metavar=metavar, help=help)
    ex.add_argument(rpm_flag or flag + "-rpm", type=float, default=None, metavar="RPM",
                    help=f"{flag} in rev/min instead, converted with the system's time scale t* "
                         "(rpm = Omega_bar / t* * 60 / (2 pi))")


def _dest(flag: str) -> str:
    return flag.lstrip("-").replace("-", "_")


def resolve_speeds(args: argparse.Namespace, spec: SystemSpec, *flags: str | tuple[str, str],
                   rng: limits.Range = limits.SPEED) -> None:
    """Set each speed option of ``flags`` (``"--start"`` or a pair ``("--speed", "--rpm")``: the Omega_bar option
    and its rpm twin) in Omega_bar on ``args``: from the rpm twin when given (checked against ``rng`` in rev/min),
    else the Omega_bar value (checked against ``rng``; when it is out of range but would be a valid rpm, the
    message suggests the twin, e.g. ``--start = 10000 is outside the allowed range (0, 50] (Omega_bar); did you mean
    --start-rpm 10000 (= Omega_bar 0.28)?``).  Options that are None stay None."""
    for item in flags:
        flag, rpm_flag = item if isinstance(item, tuple) else (item, item + "-rpm")
        rpm = getattr(args, _dest(rpm_flag), None)
        if rpm is not None:
            lo = spec.rpm(rng.lo) if rng.lo is not None else None
            hi = spec.rpm(rng.hi) if rng.hi is not None else None
            rpm_rng = rng.with_bounds(lo=lo, hi=hi, unit="rev/min", what=f"Omega_bar in {rng.interval()}")
            setattr(args, _dest(flag), spec.omega_bar(check_range(rpm_flag, rpm, rpm_rng)))
            continue
        value = getattr(args, _dest(flag), None)
        if value is None:
            continue
        try:
            check_range(flag, value, rng)
        except ParameterError as exc:
            hint = ""
            try:
                om = spec.omega_bar(float(value))
            except (ParameterError, TypeError, ValueError):
                om = None
            if om is not None and rng.contains(om):
                hint = f"; did you mean {rpm_flag} {value:g} (= Omega_bar {om:.4g})?"
            raise ParameterError(f"{exc}{hint}") from None


def work_unit_J(spec: SystemSpec) -> float:
    """``p0 R L c`` [J]: the unit of the works per cycle of :mod:`gfbjax.analyses.energy`."""
    return spec.p0 * spec.R * spec.L * spec.c


def branch_row_um(branch: Any, index: Any, spec: SystemSpec) -> dict[str, Any]:
    """Journal max and min over a branch row (x_j, y_j) in um, ``{}`` when the row is not stored."""
    import numpy as np

    if index is None or not 0 <= int(index) < len(branch.lam):
        return {}
    c_um = spec.c * 1e6
    return {"xj_yj_max_um": (np.asarray(branch.xmax)[int(index), :2] * c_um).tolist(),
            "xj_yj_min_um": (np.asarray(branch.xmin)[int(index), :2] * c_um).tolist()}


def speed_si(spec: SystemSpec, omega_bar: float | None) -> dict[str, float | None]:
    """``{"rpm": ..., "running_frequency_Hz": ...}`` of a speed in Omega_bar (None stays None)."""
    if omega_bar is None:
        return {"rpm": None, "running_frequency_Hz": None}
    om = float(omega_bar)
    return {"rpm": spec.rpm(om), "running_frequency_Hz": om / spec.t_star / (2 * math.pi)}
