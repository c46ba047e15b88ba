"""Subcommands of the ``gfbjax`` command line.

Each public module of this package (a name without a leading underscore) is one subcommand and exposes

    def register(subparsers) -> argparse.ArgumentParser

which adds its parser with ``subparsers.add_parser(NAME, ...)`` and sets ``parser.set_defaults(func=run)``, where
``run(args) -> int`` returns the exit status.  Modules are found automatically (:func:`discover`), so adding a
command means adding one file here; nothing else needs editing.  Options shared by all commands that build a
system (``--system``, ``--set``, ``--nx``, ``--nz``, ``--out``) come from :mod:`gfbjax.cli.commands._common`.

Commands from other packages can be added with :func:`gfbjax.cli.register_command`.
"""

from __future__ import annotations

import importlib
import pkgutil
from types import ModuleType

__all__ = ["discover"]


def discover() -> tuple[list[ModuleType], list[tuple[str, BaseException]]]:
    """Import every public module of this package that defines ``register``.

    Returns the modules (sorted by name) and the ``(module name, exception)`` of those that failed to import, so
    that one broken command does not take the whole command line down with it.
    """
    mods: list[ModuleType] = []
    failed: list[tuple[str, BaseException]] = []
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
        if info.name.startswith("_"):
            continue
        try:
            mod = importlib.import_module(f"{__name__}.{info.name}")
        except Exception as exc:  # noqa: BLE001 - reported by the caller, one line per module
            failed.append((info.name, exc))
            continue
        if callable(getattr(mod, "register", None)):
            mods.append(mod)
    return mods, failed
