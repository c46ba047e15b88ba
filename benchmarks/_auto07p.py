"""A small driver for AUTO-07p (the Fortran continuation code) from Python, without its interactive shell.

Used by ``benchmarks/peer_auto.py`` (and the optional AUTO check of ``tests/cont/test_cont_brusselator.py``); not
part of the gfbjax package.

How AUTO-07p runs a problem, as used here:

* the *equations file* (free-form Fortran) defines ``FUNC`` (the vector field), ``STPNT`` (the starting point
  and parameter values) and empty ``BCND``, ``ICND``, ``FOPT``, ``PVLS``; it is compiled with gfortran and linked
  with the object files of the installed library (``$AUTO_DIR/lib/*.o``, OpenMP-enabled, hence ``-fopenmp``);
* the executable reads the *constants* (``NDIM``, ``IPS``, ``ICP``, ``NTST``, ...; ``key = value`` lines) from
  ``fort.2`` in its working directory and, when ``IRS`` is not 0, the solution to restart from in ``fort.3``;
* it writes the bifurcation diagram to ``fort.7``, labelled solutions to ``fort.8`` (the restart file of the
  next run) and diagnostics to ``fort.9`` (Newton iterations, eigenvalues / Floquet multipliers of every point).

So a run is: write ``fort.2`` (and ``fort.3``) into a scratch folder, run the executable there, read the three
files back.  :func:`parse_b` reads the rows of ``fort.7``, :func:`parse_multipliers` the multipliers of
``fort.9``; both read what AUTO prints (``fort.7`` keeps 11 significant digits, ``fort.9`` six).

``AUTO_DIR`` (environment) overrides the installation folder (default ``/usr/lib/auto-07p``, the Debian/Ubuntu
package ``auto-07p``); ``FC`` the Fortran compiler (default ``gfortran``).
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

#: fort.7 type codes -> AUTO's labels.
TYPE_NAMES = {1: "BP", 2: "LP", 3: "HB", 4: "RG", -4: "UZ", 5: "LP", 6: "BP", 7: "PD", 8: "TR", 9: "EP", -9: "MX"}


@dataclass(frozen=True)
class AutoInstall:
    """An AUTO-07p installation that can build equations files: its folder, the Fortran compiler, a version."""

    dir: Path
    fc: str
    version: str

    def objects(self) -> list[str]:
        return sorted(str(p) for p in (self.dir / "lib").glob("*.o"))

    def build(self, source: str, workdir: Path, name: str = "eqn") -> Path:
        """Compile the equations file ``source`` (free-form Fortran text) in ``workdir``; returns the executable."""
        workdir.mkdir(parents=True, exist_ok=True)
        src = workdir / f"{name}.f90"
        src.write_text(source)
        exe = workdir / f"{name}.exe"
        cmd = [self.fc, "-O2", "-fopenmp", str(src), "-o", str(exe), *self.objects()]
        proc = subprocess.run(cmd, cwd=workdir, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"building the AUTO equations file failed ({' '.join(cmd[:4])} ...):\n{proc.stderr}")
        return exe


def locate() -> tuple[AutoInstall | None, str]:
    """The installation, or None and the reason it cannot be used."""
    adir = Path(os.environ.get("AUTO_DIR", "/usr/lib/auto-07p"))
    if not (adir / "lib").is_dir() or not list((adir / "lib").glob("*.o")):
        where = shutil.which("auto-07p")
        return None, (f"AUTO-07p not found: no library objects in {adir / 'lib'} (auto-07p on PATH: "
                      f"{where or 'no'}); install the 'auto-07p' package or set AUTO_DIR")
    fc = os.environ.get("FC", "gfortran")
    if shutil.which(fc) is None:
        return None, f"AUTO-07p found in {adir} but no Fortran compiler '{fc}' to build equations files"
    return AutoInstall(adir, fc, _version(adir)), ""


def _version(adir: Path) -> str:
    """The installed version: from the Debian package database when there is one, else 'unknown'."""
    try:
        out = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "auto-07p"], capture_output=True, text=True,
                             timeout=10)
        if out.returncode == 0 and out.stdout.strip():
            return f"AUTO-07p {out.stdout.strip()} (Debian package)"
    except (OSError, subprocess.SubprocessError):
        pass
    return f"AUTO-07p, version unknown ({adir})"


def fortran_double(x: float) -> str:
    """A double-precision Fortran literal of x (exact to the last bit)."""
    return f"{float(x):.17E}".replace("E", "D")


def format_constants(c: dict[str, Any]) -> str:
    """The text of a constants file: one ``key = value`` line each, values written as AUTO reads them (numbers,
    'strings', [lists], {index: value} dicts)."""
    def val(v: Any) -> str:
        if isinstance(v, str):
            return repr(v)
        if isinstance(v, dict):
            return "{" + ", ".join(f"{k}: {val(w)}" for k, w in v.items()) + "}"
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(val(w) for w in v) + "]"
        if isinstance(v, float):
            return repr(v)
        return str(v)
    return "".join(f"{k} = {val(v)}\n" for k, v in c.items())


@dataclass
class AutoRun:
    """The outputs of one AUTO run (``b``: fort.7, ``s``: fort.8, ``d``: fort.9) and its wall time."""

    wall_s: float
    returncode: int
    stdout: str
    stderr: str
    b: str = ""
    s: str = ""
    d: str = ""
    rows: list[dict[str, Any]] = field(default_factory=list)

    def labelled(self) -> list[dict[str, Any]]:
        """The rows with a label (type other than 0 / RG)."""
        return [r for r in self.rows if r["type"] not in ("", "RG")]


def run(exe: Path, constants: dict[str, Any], start: str | None = None, *, threads: int = 1,
        timeout: float | None = None) -> AutoRun:
    """Run the AUTO executable ``exe`` in its own folder with ``constants`` (fort.2) and the restart file
    ``start`` (fort.3, the ``s`` text of an earlier run) when given.  ``threads``: OMP_NUM_THREADS (AUTO's
    collocation solver is OpenMP-parallel)."""
    wd = exe.parent
    for name in ("fort.3", "fort.7", "fort.8", "fort.9"):
        (wd / name).unlink(missing_ok=True)
    (wd / "fort.2").write_text(format_constants(constants))
    if start is not None:
        (wd / "fort.3").write_text(start)
    env = {**os.environ, "OMP_NUM_THREADS": str(threads)}
    t0 = time.perf_counter()
    proc = subprocess.run([str(exe)], cwd=wd, capture_output=True, text=True, env=env, timeout=timeout)
    wall = time.perf_counter() - t0
    out = AutoRun(wall, proc.returncode, proc.stdout, proc.stderr)
    for attr, name in (("b", "fort.7"), ("s", "fort.8"), ("d", "fort.9")):
        p = wd / name
        setattr(out, attr, p.read_text() if p.exists() else "")
    out.rows = parse_b(out.b)
    return out


def parse_b(text: str) -> list[dict[str, Any]]:
    """The solution rows of a fort.7 file: ``branch``, ``pt`` (>0), ``stable`` (AUTO's sign of PT), ``type``
    (label name, '' for none), ``lab``, and one entry per printed column (e.g. ``PAR(5)``, ``L2-NORM``,
    ``PERIOD``) under the header's names."""
    rows: list[dict[str, Any]] = []
    names: list[str] = []
    for line in text.splitlines():
        tok = line.split()
        if not tok:
            continue
        if tok[0] == "0":
            if len(tok) > 1 and tok[1] == "PT":  # column header: names separated by two or more spaces
                names = re.split(r"\s{2,}", line.strip())[4:]
            continue
        try:
            br, pt, ty, lab = (int(t) for t in tok[:4])
            vals = [float(t.replace("D", "E")) for t in tok[4:]]
        except ValueError:
            continue
        row = {"branch": abs(br), "pt": abs(pt), "stable": pt < 0, "type": TYPE_NAMES.get(ty, "" if ty == 0 else
                                                                                          str(ty)), "lab": lab}
        row.update(zip(names, vals))
        rows.append(row)
    return rows


_MULT = re.compile(r"^\s*-?\d+\s+(-?\d+)\s+Multiplier\s+(\d+)\s+(\S+)\s+(\S+)\s+Abs\. Val\.")
_ITER = re.compile(r"^\s*-?\d+\s+(-?\d+)\s+Iterations\s*:\s*(\d+)")


def parse_multipliers(text: str) -> dict[int, np.ndarray]:
    """Floquet multipliers (or, for equilibria, nothing) per point number, from a fort.9 file: the last block
    printed for each point (a located special point reuses the number of the step it replaces)."""
    out: dict[int, np.ndarray] = {}
    cur: dict[int, list[complex]] = {}
    for line in text.splitlines():
        m = _MULT.match(line)
        if not m:
            continue
        pt, k = abs(int(m.group(1))), int(m.group(2))
        z = complex(float(m.group(3)), float(m.group(4)))
        if k == 1:
            cur[pt] = [z]
        else:
            cur.setdefault(pt, []).append(z)
        out[pt] = np.array(cur[pt])
    return out


def newton_iterations(text: str) -> int:
    """Sum of the Newton iterations of the 'Iterations' lines of a fort.9 file: one per step, retried steps
    included; the iterations of special-point location are not counted."""
    return sum(int(m.group(2)) for m in map(_ITER.match, text.splitlines()) if m)
