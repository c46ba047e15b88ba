"""Incremental storage of a sweep in an output folder, so that an interrupted or extended sweep resumes.

Layout of the folder::

    manifest.json          what the folder holds: base spec, analyses with their settings, the designs
    designs/<key>.json     one finished design each, written the moment it finishes
    sweep.nc               the consolidated xarray Dataset (netCDF-3, scipy engine)

``<key>`` is a stable hash of the design's full SystemSpec and of the analyses' settings (:func:`design_key`), so a
design computed once is found again by any sweep that asks the same question of the same system, whatever the
grid around it.  Every file is written to a temporary file in the same folder and moved into place with
``os.replace``: a killed process leaves either the old file or the new one, never half of one.

A folder belongs to one base system and one set of analysis settings (:func:`sweep_identity`); a sweep with
other settings is refused (:class:`ParameterError`) instead of mixing results.  The designs may change: a
grid extended by a value reuses every design already in the folder.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
from pathlib import Path
from typing import Any, Sequence

from ..params import ParameterError, SystemSpec

__all__ = ["SweepStore", "design_key", "sweep_identity", "RECORD_FORMAT", "MANIFEST_FORMAT"]

RECORD_FORMAT = "gfbjax.sweep.design"
MANIFEST_FORMAT = "gfbjax.sweep"
VERSION = 1


def _canonical(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=True)


def design_key(spec: SystemSpec, analyses_settings: Sequence[dict[str, Any]]) -> str:
    """Stable name of one design's results: SHA-256 (first 24 hex digits) of the spec's fields and the analyses'
    settings, as canonical JSON (sorted keys; floats in their shortest round-trip form)."""
    text = _canonical({"spec": spec.to_dict(), "analyses": list(analyses_settings)})
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def sweep_identity(base: SystemSpec, analyses_settings: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """What a folder is bound to: the base spec and the analyses' settings."""
    return {"base": base.to_dict(), "analyses": list(analyses_settings)}


def _jsonable(v: Any) -> Any:
    """NaN and infinities as null / strings (strict JSON), recursively."""
    if isinstance(v, float) and not math.isfinite(v):
        return None if math.isnan(v) else ("inf" if v > 0 else "-inf")
    if isinstance(v, dict):
        return {k: _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    return v


def atomic_write(path: Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder and ``os.replace``."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _differences(old: dict[str, Any], new: dict[str, Any]) -> str:
    """A short account of how two identities differ, for the refusal message."""
    parts = []
    ob, nb = old.get("base", {}), new.get("base", {})
    for k in sorted(set(ob) | set(nb)):
        if ob.get(k) != nb.get(k):
            parts.append(f"base {k}: {ob.get(k)!r} there, {nb.get(k)!r} now")
    oa = {a.get("analysis"): a for a in old.get("analyses", [])}
    na = {a.get("analysis"): a for a in new.get("analyses", [])}
    if set(oa) != set(na):
        parts.append(f"analyses: {sorted(oa)} there, {sorted(na)} now")
    for name in sorted(set(oa) & set(na)):
        for k in sorted(set(oa[name]) | set(na[name])):
            if oa[name].get(k) != na[name].get(k):
                parts.append(f"{name}.{k}: {oa[name].get(k)!r} there, {na[name].get(k)!r} now")
    return "; ".join(parts[:6]) + ("; ..." if len(parts) > 6 else "")


class SweepStore:
    """The output folder of one sweep (module docstring).

    Raises ParameterError on construction when ``folder`` is a file or cannot be created or written, or when it
    holds a sweep of another base system or other analysis settings (the message names what differs).
    """

    def __init__(self, folder: str | os.PathLike, identity: dict[str, Any]):
        self.folder = Path(folder)
        if self.folder.exists() and not self.folder.is_dir():
            raise ParameterError(f"out = {str(self.folder)!r} is not a folder")
        self.identity = _jsonable(identity)
        self.designs_dir = self.folder / "designs"
        manifest = self.folder / "manifest.json"
        if manifest.exists():
            try:
                old = json.loads(manifest.read_text(encoding="utf-8"))
            except (OSError, ValueError) as exc:
                raise ParameterError(f"out = {str(self.folder)!r}: its manifest.json cannot be read ({exc}); use "
                                     "another folder or remove it") from None
            if old.get("format") != MANIFEST_FORMAT:
                raise ParameterError(f"out = {str(self.folder)!r}: manifest.json is not a gfbjax sweep manifest")
            if old.get("identity") != self.identity:
                raise ParameterError(
                    f"out = {str(self.folder)!r} holds a sweep of another system or other analysis settings "
                    f"({_differences(old.get('identity', {}), self.identity)}); results are never mixed: choose "
                    "another output folder, or remove that one to start again")
        elif self.designs_dir.exists() and any(self.designs_dir.iterdir()):
            raise ParameterError(f"out = {str(self.folder)!r} has design results but no manifest.json, so it is "
                                 "not known what they were computed for; use another folder")
        try:
            self.designs_dir.mkdir(parents=True, exist_ok=True)
            with tempfile.TemporaryFile(dir=self.designs_dir):
                pass
        except OSError as exc:
            raise ParameterError(f"out = {str(self.folder)!r} cannot be created or written: "
                                 f"{exc.strerror or exc}") from None

    @property
    def manifest_path(self) -> Path:
        return self.folder / "manifest.json"

    @property
    def dataset_path(self) -> Path:
        return self.folder / "sweep.nc"

    def write_manifest(self, extra: dict[str, Any]) -> Path:
        """Bind the folder to this sweep (``identity``) and record ``extra`` (the designs, the version)."""
        doc = {"format": MANIFEST_FORMAT, "version": VERSION, "identity": self.identity, **_jsonable(extra)}
        return atomic_write(self.manifest_path, (json.dumps(doc, indent=1) + "\n").encode())

    def path_of(self, key: str) -> Path:
        return self.designs_dir / f"{key}.json"

    def load(self, key: str) -> dict[str, Any] | None:
        """The stored record of design ``key``, or None when there is none (or it is not a record of that key:
        such a file is recomputed and overwritten)."""
        path = self.path_of(key)
        try:
            rec = json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            return None
        except (OSError, ValueError):
            return None
        if not isinstance(rec, dict) or rec.get("format") != RECORD_FORMAT or rec.get("key") != key:
            return None
        return rec

    def save(self, record: dict[str, Any]) -> Path:
        """Write one finished design (atomically)."""
        rec = {"format": RECORD_FORMAT, "version": VERSION, **_jsonable(record)}
        return atomic_write(self.path_of(record["key"]), (json.dumps(rec, indent=1) + "\n").encode())

    def write_dataset(self, ds: Any) -> Path:
        """Write the consolidated Dataset as netCDF-3 (scipy engine) through a temporary file."""
        fd, tmp = tempfile.mkstemp(dir=self.folder, prefix=".sweep.nc.", suffix=".tmp")
        os.close(fd)
        try:
            ds.to_netcdf(tmp, engine="scipy")
            os.replace(tmp, self.dataset_path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        return self.dataset_path
