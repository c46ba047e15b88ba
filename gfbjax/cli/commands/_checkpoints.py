"""Checkpoints and ``--resume`` for the continuation commands (``cycles``, ``equilibria``).

A run writes its options to ``OUT/<command>_args.json`` and appends every accepted point, with the state the next
step starts from, to ``OUT/checkpoint/`` (:class:`gfbjax.cont.Checkpoint`).  ``--resume OUT`` runs the command
again with the options of that run and continues its branch after the last point written: a kill (``kill -9``
included) loses at most the point in progress, and the resumed branch equals an uninterrupted one.  A run without
``--resume`` starts afresh and clears ``OUT/checkpoint/`` when that holds a finished branch; an unfinished one (a
killed or interrupted run: steps and no ``end.json``) is refused unless ``--fresh`` is given, since re-running the
same command without ``--resume`` would otherwise delete the work it was meant to continue.
"""
from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path
from typing import Any, Callable, NamedTuple

from ...params import ParameterError

__all__ = ["add_checkpoint_options", "resume_args", "checkpoint_folder", "interrupted_status", "restored_rows",
           "prepare_run", "Run", "FOLDER"]

FOLDER = "checkpoint"

# options that do not change the computed branch: a resumed run may set them anew
_FREE = frozenset({"quiet", "no_figures", "resume", "no_checkpoint", "out", "fresh"})


def add_checkpoint_options(parser: argparse.ArgumentParser) -> None:
    """Add ``--resume DIR``, ``--fresh`` and ``--no-checkpoint``."""
    g = parser.add_argument_group("checkpoints")
    g.add_argument("--resume", type=Path, default=None, metavar="DIR",
                   help="continue the branch of an earlier run whose --out was DIR, after its last point, with that "
                        "run's options (an option that differs from that run's is refused; --quiet and "
                        "--no-figures are not kept from it: give them again); the results are written to DIR")
    g.add_argument("--fresh", action="store_true",
                   help=f"start afresh even where OUT/{FOLDER}/ holds an unfinished run (deleting it); without "
                        "this, such a folder is refused, to be continued with --resume")
    g.add_argument("--no-checkpoint", action="store_true",
                   help=f"do not append each point to OUT/{FOLDER}/ (then a killed run cannot be resumed)")
    parser.set_defaults(option_default=parser.get_default)


def _saved(args: argparse.Namespace) -> dict[str, Any]:
    """The options of a run that decide its branch, as JSON values."""
    out = {}
    for key, value in vars(args).items():
        if key in _FREE or callable(value):
            continue
        out[key] = str(value) if isinstance(value, Path) else value
    return out


def resume_args(args: argparse.Namespace, command: str) -> argparse.Namespace:
    """``args`` itself, or with ``--resume DIR`` the options of the run that wrote DIR (``--out`` = DIR).

    ParameterError when DIR holds no such run, or when an option given now differs from that run's."""
    if getattr(args, "resume", None) is None:
        return args
    folder = Path(args.resume)
    if args.no_checkpoint:
        raise ParameterError("--resume and --no-checkpoint exclude each other (a resumed run goes on writing its "
                             "checkpoint)")
    if getattr(args, "fresh", False):
        raise ParameterError("--resume and --fresh exclude each other (--fresh deletes what --resume continues)")
    path = folder / f"{command}_args.json"
    if not path.is_file() or not (folder / FOLDER).is_dir():
        owner = _owner(folder)
        missing = " and ".join(name for name, there in ((path.name, path.is_file()),
                                                        (f"{FOLDER}/", (folder / FOLDER).is_dir())) if not there)
        raise ParameterError(f"--resume {folder}: not the --out folder of a 'gfbjax {command}' run with checkpoints "
                             f"(no {missing} there)"
                             + (f"; it holds a 'gfbjax {owner}' run: gfbjax {owner} --resume {folder}"
                                if owner not in (None, command) and (folder / FOLDER).is_dir() else ""))
    try:
        saved = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ParameterError(f"--resume {folder}: {path.name} unreadable ({exc})") from None
    if Path(args.out) != Path(args.option_default("out")) and Path(args.out) != folder:
        raise ParameterError(f"--out {args.out}: a resumed run writes to its own folder, --resume {folder}")
    given = {k: v for k, v in _saved(args).items() if v != args.option_default(k)}
    clash = [k for k, v in given.items() if k in saved and saved[k] != v]
    if clash:
        opts = ", ".join(f"--{k.replace('_', '-')} {given[k]} (that run: {saved[k]})" for k in clash)
        raise ParameterError(f"--resume {folder} continues that run with its own options; these differ: {opts}")
    merged = argparse.Namespace(**{**vars(args), **saved})
    merged.out = folder
    return merged


def _owner(folder: Path) -> str | None:
    """The command whose options ``folder`` holds (``<command>_args.json``; the newest where there are several), or
    None."""
    found = sorted(folder.glob("*_args.json"), key=lambda p: p.stat().st_mtime)
    return found[-1].name[:-len("_args.json")] if found else None


def checkpoint_folder(args: argparse.Namespace, out: Path, command: str) -> Path | None:
    """The checkpoint folder of this run (None with ``--no-checkpoint``); writes ``<command>_args.json``.  A fresh
    run (no ``--resume``) clears an old checkpoint in ``out``: that of a finished branch always, that of an
    unfinished one only with ``--fresh`` (ParameterError otherwise, naming ``--resume``)."""
    folder = out / FOLDER
    if getattr(args, "resume", None) is None and folder.exists():
        steps = len(list(folder.glob("step_*.npz")))
        if steps and not (folder / "end.json").exists() and not getattr(args, "fresh", False):
            owner = command if (out / f"{command}_args.json").is_file() else _owner(out) or command
            raise ParameterError(
                f"--out {out}: {folder} holds an unfinished 'gfbjax {owner}' run ({steps} accepted "
                f"step{'s' * (steps != 1)}, no end recorded: killed or interrupted). Continue it with 'gfbjax "
                f"{owner} --resume {out}', start afresh with --fresh (deletes it), or choose another --out")
        shutil.rmtree(folder)
    if args.no_checkpoint:
        return None
    (out / f"{command}_args.json").write_text(json.dumps(_saved(args), indent=1) + "\n")
    return folder


def restored_rows(folder: Path | None) -> int:
    """Rows that a run with checkpoint ``folder`` restores before computing (0 for a fresh run, which has cleared
    the folder, and with ``--no-checkpoint``)."""
    from ...cont import Checkpoint

    return 0 if folder is None or not folder.exists() else Checkpoint(folder).stored_rows()


def interrupted_status(branch: Any, reached: bool, out: Path, folder: Path | None, command: str) -> int:
    """Exit status of a continuation command: 130 when interrupted (printing how to resume), 0 when the branch
    ``reached`` the end of the range, 1 when it ended before."""
    from ...cont import Outcome

    if branch.outcome is Outcome.INTERRUPTED:
        if folder is not None:
            print(f"gfbjax {command}: interrupted; continue with: gfbjax {command} --resume {out}", flush=True)
        return 130
    return 0 if reached else 1


class Run(NamedTuple):
    """What a continuation command has checked and set up before its computation."""

    args: argparse.Namespace
    spec: Any
    settings: Any
    out: Path
    params: Any
    contact: dict[str, Any]
    checkpoint: Path | None


def prepare_run(args: argparse.Namespace, command: str, settings_of: Callable[[argparse.Namespace], Any]) -> Run:
    """The set-up shared by ``cycles``, ``equilibria`` and ``energy``, in the order that loses nothing: the options
    of a resumed run, the system, the speeds (rpm twins), the settings, the output folder and the contact options
    are all checked before an old checkpoint in the output folder is cleared."""
    from ._common import output_dir, resolve_speeds, spec_from_args, traced_params
    from ._contact import contact_kwargs

    args = resume_args(args, command)
    spec = spec_from_args(args)
    resolve_speeds(args, spec, "--start", "--end")
    settings = settings_of(args)
    out = output_dir(args)
    params = traced_params(spec)
    contact = contact_kwargs(args, spec)
    return Run(args, spec, settings, out, params, contact, checkpoint_folder(args, out, command))
