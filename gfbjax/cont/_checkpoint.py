"""Checkpoints of a continuation: every accepted step is appended to a folder, and a later run resumes from it.

Why: a branch of the bearing model takes minutes to hours, and a batch system's kill, a reboot or ``kill -9``
must not lose the points already computed.  The driver (:func:`._driver.continue_curve`) hands the journal each
accepted step: the rows it added to the branch (one, or more where an event was located and inserted), the special
points it found, and the driver's own state after the step (the point, the previous point for the secant, the
tangent, the test functions and the next step length).  That state is what makes a resumed branch equal to an
uninterrupted one: the next prediction is made from exactly the same data.

Folder layout (plain numpy + JSON)::

    journal.json        what is being continued: format, kind, the caller's identity and the settings
    step_00000.npz      one file per accepted step, written to a temporary name and renamed (atomic on POSIX), so
    step_00001.npz      a kill leaves either the whole step or none of it
    ...
    end.json            why the branch ended (absent while it runs, and after an interruption)

A step file holds ``rows`` (JSON: the scalar fields of each new :class:`~._branch.PointRecord`) with their arrays
``row<i>_<field>`` and ``row<i>_state_<key>``, ``special`` (JSON: the new :class:`~._results.SpecialPoint` records)
with their states ``special<i>_<key>``, and the driver state: ``X_<key>``, ``Xprev_<key>`` (absent on the first
step), ``tau_<key>``, ``tests`` (JSON), ``ds`` and ``driver`` (JSON: the event-refinement counters, so that a
resumed branch refines exactly as an uninterrupted one; or ``ended`` and ``message`` when that step ended the
branch, e.g. at a Hopf point where a family of cycles ends, so that a run interrupted before ``end.json`` was
written resumes to that end).

Resuming: opening a folder that holds steps with the same identity continues after the last step; one that
ended (``end.json``, any outcome but ``interrupted`` or ``stopped``) returns the stored branch without computing.
A folder written for another problem or other settings is refused (:class:`CheckpointError`), never mixed.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from ._branch import PointRecord
from ._results import Outcome, SpecialPoint

__all__ = ["Checkpoint", "CheckpointError", "Restored", "as_checkpoint"]

FORMAT = "gfbjax.cont.Checkpoint"
#: 2: the BPC and NS test functions changed orientation and carry the UNSTABLE count; a version-1 folder's stored
#: test values would fake a sign change at the first resumed step, so it is refused
VERSION = 2

_SCALARS = tuple(f.name for f in fields(PointRecord) if f.name not in ("xmax", "xmin", "multipliers", "state"))


class CheckpointError(ValueError):
    """A checkpoint folder that cannot be used: written for another problem or settings, or unreadable.  The
    message names the folder and what differs."""


@dataclass
class Restored:
    """What a checkpoint folder holds: the rows, special points and the driver state after the last step."""

    points: list[PointRecord]
    special: list[SpecialPoint]
    special_states: list[dict[str, np.ndarray]]
    X: dict[str, np.ndarray]
    X_prev: dict[str, np.ndarray] | None
    tau: dict[str, np.ndarray]
    tests: dict[str, float] | None
    ds: float
    outcome: Outcome | None = None  # set when the branch had ended (end.json)
    message: str = ""
    driver: dict[str, float | str] = field(default_factory=dict)  # the driver's counters, or the end it recorded


def _plain(value: Any) -> Any:
    """JSON-able copy of an identity value (NumPy scalars and arrays become numbers and lists)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


class Checkpoint:
    """A folder that one continuation appends to, step by step (module docstring).

    Args:
        folder: created if missing.
        identity: JSON-able description of what is continued beyond the engine's settings, e.g. the system and
            the speed range; a resumed run must give the same.

    The driver calls :meth:`open` (checks or writes ``journal.json``; returns the stored state or None),
    :meth:`append` after each accepted step and :meth:`finish` when the branch ends.
    """

    def __init__(self, folder: str | os.PathLike, identity: dict[str, Any] | None = None):
        self.folder = Path(folder)
        self.identity = _plain(identity or {})
        self._next = 0
        self._rows = 0
        self._special = 0

    # -- reading ----------------------------------------------------------------------------------------------
    def _head(self, kind: str, settings: Any) -> dict[str, Any]:
        return {"format": FORMAT, "version": VERSION, "kind": kind, "identity": self.identity,
                "settings": repr(settings)}

    def _steps(self) -> list[Path]:
        return sorted(self.folder.glob("step_*.npz"))

    def open(self, kind: str, settings: Any) -> Restored | None:
        """Check the folder against this run (or start it); the stored state, or None when there is none.

        Raises :class:`CheckpointError` when the folder belongs to another continuation."""
        head = self._head(kind, settings)
        journal = self.folder / "journal.json"
        if journal.exists():
            try:
                old = json.loads(journal.read_text())
            except (OSError, json.JSONDecodeError) as exc:
                raise CheckpointError(f"checkpoint {self.folder}: journal.json unreadable ({exc})") from None
            if old.get("format") == head["format"] and old.get("version") != head["version"]:
                raise CheckpointError(f"checkpoint {self.folder} has format version {old.get('version')}, this "
                                      f"gfbjax writes version {head['version']} (its test functions differ): it "
                                      "cannot be resumed; rerun without resuming, or use a new folder")
            diff = [k for k in ("format", "kind", "settings") if old.get(k) != head[k]]
            ident_old = old.get("identity", {})
            diff += [f"identity.{k}" for k in sorted(set(ident_old) | set(self.identity))
                     if _canonical(ident_old.get(k)) != _canonical(self.identity.get(k))]
            if diff:
                raise CheckpointError(f"checkpoint {self.folder} was written by another continuation ({', '.join(diff)} "
                                      "differ); resume with the same problem and settings, or use a new folder")
        else:
            self.folder.mkdir(parents=True, exist_ok=True)
            _write_atomic(journal, json.dumps(head, indent=1).encode())
        steps = self._steps()
        if not steps:
            return None
        restored = self._read(steps)
        end = self.folder / "end.json"
        if end.exists():
            d = json.loads(end.read_text())
            restored.outcome, restored.message = Outcome(d["outcome"]), d["message"]
        return restored

    def stored_rows(self) -> int:
        """How many rows of a branch the folder holds (0 without steps): where a resumed run starts.  Reads only
        the steps' row lists; an unreadable step ends the count (:meth:`open` then names it)."""
        n = 0
        for path in self._steps():
            try:
                with np.load(path, allow_pickle=False) as z:
                    n += len(json.loads(str(z["rows"])))
            except Exception:
                break
        return n

    def _read(self, steps: list[Path]) -> Restored:
        points: list[PointRecord] = []
        special: list[SpecialPoint] = []
        states: list[dict[str, np.ndarray]] = []
        last = None
        for i, path in enumerate(steps):
            if path.name != f"step_{i:05d}.npz":
                raise CheckpointError(f"checkpoint {self.folder}: step {i} is missing (found {path.name})")
            try:
                with np.load(path, allow_pickle=False) as z:
                    data = {k: z[k] for k in z.files}
            except Exception as exc:  # a truncated file cannot occur (atomic rename) unless the disk was damaged
                raise CheckpointError(f"checkpoint {self.folder}: {path.name} unreadable ({exc})") from None
            for j, row in enumerate(json.loads(str(data["rows"]))):
                st = _group(data, f"row{j}_state_")
                points.append(PointRecord(**row, xmax=data[f"row{j}_xmax"], xmin=data[f"row{j}_xmin"],
                                          multipliers=data[f"row{j}_multipliers"], state=st or None))
            for j, sp in enumerate(json.loads(str(data["special"]))):
                states.append(_group(data, f"special{j}_"))
                sp["state"] = len(states) - 1
                special.append(SpecialPoint.from_json(sp))
            last = data
        self._next, self._rows, self._special = len(steps), len(points), len(special)
        X_prev = _group(last, "Xprev_") or None
        driver = json.loads(str(last["driver"])) if "driver" in last else {}
        return Restored(points, special, states, _group(last, "X_"), X_prev, _group(last, "tau_"),
                        _decode_tests(json.loads(str(last["tests"]))), float(last["ds"]), driver=driver)

    # -- writing ----------------------------------------------------------------------------------------------
    def append(self, points: list[PointRecord], special: list[SpecialPoint],
               special_states: list[dict[str, np.ndarray]], X: dict[str, np.ndarray],
               X_prev: dict[str, np.ndarray] | None, tau: dict[str, np.ndarray], tests: dict[str, float] | None,
               ds: float, driver: dict[str, float | str] | None = None) -> None:
        """Write one step: the rows and special points added since the last call, and the driver state."""
        arrays: dict[str, np.ndarray] = {}
        rows = []
        for j, p in enumerate(points[self._rows:]):
            rows.append({k: _scalar(getattr(p, k)) for k in _SCALARS})
            arrays.update({f"row{j}_xmax": np.asarray(p.xmax), f"row{j}_xmin": np.asarray(p.xmin),
                           f"row{j}_multipliers": np.asarray(p.multipliers)})
            arrays.update({f"row{j}_state_{k}": np.asarray(v) for k, v in (p.state or {}).items()})
        sps = []
        for j, sp in enumerate(special[self._special:]):
            sps.append(sp.to_json())
            arrays.update({f"special{j}_{k}": np.asarray(v) for k, v in special_states[sp.state].items()})
        arrays.update({f"X_{k}": np.asarray(v) for k, v in X.items()})
        arrays.update({f"Xprev_{k}": np.asarray(v) for k, v in (X_prev or {}).items()})
        arrays.update({f"tau_{k}": np.asarray(v) for k, v in tau.items()})
        arrays["rows"] = np.array(json.dumps(rows))
        arrays["special"] = np.array(json.dumps(sps))
        arrays["tests"] = np.array(json.dumps(_encode_tests(tests)))
        arrays["ds"] = np.array(float(ds))
        arrays["driver"] = np.array(json.dumps({k: v if isinstance(v, str) else float(v)
                                                for k, v in (driver or {}).items()}))
        path = self.folder / f"step_{self._next:05d}.npz"
        tmp = path.with_name(path.name + ".tmp")
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
        self._next += 1
        self._rows, self._special = len(points), len(special)

    def finish(self, outcome: Outcome, message: str) -> None:
        """Record why the branch ended; an interruption is not an end (a later run continues)."""
        end = self.folder / "end.json"
        if outcome in (Outcome.INTERRUPTED, Outcome.STOPPED):
            end.unlink(missing_ok=True)
            return
        _write_atomic(end, json.dumps({"outcome": str(outcome), "message": message}).encode())


def fingerprint(*objects: Any) -> str:
    """A digest of functions (by module and qualified name) and pytrees of numbers (by their values): what tells
    one continuation's problem and start from another's when a folder is resumed."""
    import hashlib

    import jax

    h = hashlib.sha256()
    for obj in objects:
        for leaf in jax.tree_util.tree_leaves(obj):
            if callable(leaf):
                h.update(f"{getattr(leaf, '__module__', '')}.{getattr(leaf, '__qualname__', repr(leaf))}".encode())
            else:
                try:
                    a = np.asarray(leaf)
                    h.update(str(a.dtype).encode() + str(a.shape).encode() + a.tobytes())
                except (TypeError, ValueError):
                    h.update(repr(leaf).encode())
    return h.hexdigest()[:24]


def as_checkpoint(checkpoint: "Checkpoint | str | os.PathLike | None", **engine: Any) -> "Checkpoint | None":
    """A :class:`Checkpoint` from a folder name (or the one given), with the engine's own identity (e.g. the
    state dimension) added to the caller's."""
    if checkpoint is None:
        return None
    if not isinstance(checkpoint, Checkpoint):
        checkpoint = Checkpoint(checkpoint)
    checkpoint.identity = {**checkpoint.identity, **_plain(engine)}
    return checkpoint


def _canonical(value: Any) -> str:
    """Comparable text of an identity value (NaN equals NaN, key order does not matter)."""
    return json.dumps(value, sort_keys=True)


def _group(data: dict[str, np.ndarray], prefix: str) -> dict[str, np.ndarray]:
    return {k[len(prefix):]: v for k, v in data.items() if k.startswith(prefix)}


def _scalar(v: Any) -> Any:
    v = v.item() if isinstance(v, np.generic) else v
    return v


def _write_atomic(path: Path, data: bytes) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)


def _encode_tests(tests: dict[str, Any] | None) -> dict[str, Any] | None:
    """The driver's test data as JSON: numbers as floats, arrays (the members of the spectrum nearest the
    stability boundary) as lists of [real, imag]."""
    if tests is None:
        return None
    return {k: (float(v) if np.ndim(v) == 0 else [[float(z.real), float(z.imag)] for z in np.asarray(v, complex)])
            for k, v in tests.items()}


def _decode_tests(data: dict[str, Any] | None) -> dict[str, Any] | None:
    """Inverse of :func:`_encode_tests`."""
    if data is None:
        return None
    return {k: (float(v) if not isinstance(v, list) else np.array([complex(r, i) for r, i in v], complex))
            for k, v in data.items()}
