"""Start-up of ``gfbjax cycles`` with and without JAX's persistent compilation cache: wall time from the command's
start to its first point (compilation, static equilibrium and the start's correction), and of the whole command.

Three runs of the same command in fresh processes, in this order:

* ``off``: cache switched off (``GFBJAX_CACHE_DIR=off``), what every run cost before the cache;
* ``cold``: an empty cache folder (compiles and writes the cache);
* ``warm``: the same folder again (loads the kernels).

Writes benchmarks/results/startup_cache.json and prints a table.

    python benchmarks/startup_cache.py [--nx 48 --nz 8 --N 16 --points 3]
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def run(args: list[str], cache: str, out: Path) -> dict:
    env = {**os.environ, "GFBJAX_CACHE_DIR": cache}
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "gfbjax", "cycles", *args, "--out", str(out), "--quiet",
                           "--no-figures", "--no-checkpoint"], env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode not in (0, 1):
        raise SystemExit(f"gfbjax cycles failed ({proc.returncode}):\n{proc.stdout}\n{proc.stderr}")
    t = json.loads((out / "cycles.json").read_text())["timings_s"]
    return {"process_wall_s": wall, "first_point_s": t["first_point"], "command_total_s": t["total"]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nx", type=int, default=48)
    ap.add_argument("--nz", type=int, default=8)
    ap.add_argument("--N", type=int, default=16)
    ap.add_argument("--points", type=int, default=3)
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "startup_cache.json")
    a = ap.parse_args()
    cmd = ["--nx", str(a.nx), "--nz", str(a.nz), "--N", str(a.N), "--max-points", str(a.points)]
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        cache = str(Path(tmp) / "cache")
        for name, folder in (("off", "off"), ("cold", cache), ("warm", cache)):
            rows[name] = run(cmd, folder, Path(tmp) / name)
            print(f"  {name:5s} done", flush=True)
    print(f"\n gfbjax cycles {' '.join(cmd)}  (start-up with JAX's persistent compilation cache)")
    print(f" {'cache':6s} {'to first point [s]':>19s} {'command [s]':>12s} {'process [s]':>12s}")
    for name, r in rows.items():
        print(f" {name:6s} {r['first_point_s']:19.1f} {r['command_total_s']:12.1f} {r['process_wall_s']:12.1f}")
    ratio = rows["off"]["first_point_s"] / rows["warm"]["first_point_s"]
    print(f"\n first point: warm cache {ratio:.1f}x sooner than no cache (target: under 10 s warm)")
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps({"command": ["gfbjax", "cycles", *cmd], "runs": rows, "first_point_ratio": ratio,
                                 "machine": {"cpus": os.cpu_count(), "platform": platform.platform()},
                                 "date": time.strftime("%Y-%m-%d %H:%M")}, indent=1) + "\n")
    print(f" wrote {a.out}")


if __name__ == "__main__":
    main()
