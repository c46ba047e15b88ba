"""The ``gfbjax`` command line (also ``python -m gfbjax``).

Subcommands live in :mod:`gfbjax.cli.commands`, one module each with ``register(subparsers)``; they are discovered
automatically.  Code elsewhere can add one with :func:`register_command` before calling :func:`main`.

Exit status: what the command returns (0 success, 1 when the computation ended early, e.g. a branch before
``--end``); 2 for invalid input (a one-line message naming the option or field, no traceback); 130 when
interrupted by SIGINT or SIGTERM (a continuation then writes the points it has).

Process settings: :func:`main` is a program's entry point, so it sets what a program may: the XLA:CPU and OpenBLAS
settings of :func:`gfbjax._process.configure_process` (where not set by the user), JAX's persistent compilation
cache (:func:`gfbjax._process.enable_compilation_cache`: ``~/.cache/gfbjax/jax``, or ``$GFBJAX_CACHE_DIR``, ``off``
to disable) and matplotlib's non-interactive Agg backend for the figures the commands write (files only, no window).  The library itself (``import gfbjax``,
the plotting modules) leaves the matplotlib backend alone.
"""

from __future__ import annotations

import argparse
import signal
import sys
from typing import Any, Callable, Sequence

__all__ = ["main", "build_parser", "register_command"]

PROG = "gfbjax"

_EXTRA: list[Callable[[Any], Any]] = []


def register_command(register: Callable[[Any], Any]) -> Callable[[Any], Any]:
    """Add a subcommand defined outside :mod:`gfbjax.cli.commands`; ``register(subparsers)`` adds its parser and sets
    ``func=run`` with ``run(args) -> int``.  Usable as a decorator."""
    if register not in _EXTRA:
        _EXTRA.append(register)
    return register


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``gfbjax static: error: argument --speed: ... (see gfbjax static --help)``."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def build_parser() -> tuple[argparse.ArgumentParser, list[str]]:
    """The parser with every subcommand, and one warning line per command module that failed to import."""
    from .. import __version__
    from .commands import discover

    parser = _Parser(
        prog=PROG,
        description=("gfbjax: nonlinear dynamics of rotors on gas foil bearings in JAX (Papafragkos et al., "
                     "Nonlinear Dynamics 2022): static equilibria, limit cycles, Floquet stability, energy flow "
                     "and foil design.  Inputs are SI or the paper's dimensionless design values; speeds are "
                     "Omega_bar = 6 mu Omega R^2/(p0 c^2).  Run 'gfbjax COMMAND --help' for a command's options."),
        epilog="example: gfbjax static --curves   (quick look at the reference system, results in results/static/)",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", title="commands", parser_class=_Parser)
    mods, failed = discover()
    for mod in mods:
        mod.register(sub)
    for reg in _EXTRA:
        reg(sub)
    warnings = [f"{PROG}: warning: command module gfbjax.cli.commands.{name} failed to import "
                f"({type(exc).__name__}: {exc})" for name, exc in failed]
    return parser, warnings


def _configure_program() -> None:
    """The process settings of a command-line run (module docstring)."""
    import matplotlib

    from .._process import configure_process, enable_compilation_cache

    configure_process()
    enable_compilation_cache()
    matplotlib.use("Agg")  # figures are written to files; no display is needed or opened


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line with ``argv`` (default ``sys.argv[1:]``); returns the exit status."""
    from ..cont import CheckpointError
    from ..params import ParameterError

    argv = list(sys.argv[1:] if argv is None else argv)
    parser, warnings = build_parser()
    for line in warnings:
        print(line, file=sys.stderr)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, usage errors
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    func = getattr(args, "func", None)
    if func is None:
        parser.print_help()
        return 0 if not argv else 2
    prog = f"{PROG} {args.command}"
    _configure_program()
    previous = _terminate_as_interrupt()
    try:
        return int(func(args) or 0)
    except (ParameterError, CheckpointError) as exc:  # bad input, or a checkpoint folder that cannot be resumed
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def _raise_interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt


def _terminate_as_interrupt() -> Any:
    """Treat SIGTERM like SIGINT while a command runs (a batch system's kill then ends a continuation with outcome
    ``interrupted`` and writes what was computed); returns the previous handler (None off the main thread)."""
    try:
        return signal.signal(signal.SIGTERM, _raise_interrupt)
    except ValueError:  # not the main thread (e.g. main() called from a worker): leave signals alone
        return None


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
