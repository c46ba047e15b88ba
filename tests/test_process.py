"""Process settings (gfbjax._process): importing gfbjax sets the XLA:CPU and OpenBLAS variables only where the user
has not, warns when JAX already started without them, sets no OMP_NUM_THREADS, and leaves the matplotlib backend
alone (issue 11, item 7).  Each case runs in a fresh interpreter, since the test session imported gfbjax already."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

VARS = ("XLA_FLAGS", "NPROC", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MPLBACKEND")


def _python(code: str, **env_set: str) -> dict:
    """Run ``code`` in a fresh interpreter with none of VARS set except ``env_set``; it prints one JSON line."""
    env = {k: v for k, v in os.environ.items() if k not in VARS and k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env.update(env_set)
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=180)
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


RECORD = """
import json, os, warnings
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
{body}
extra = {extra}
print(json.dumps({{"env": {{k: os.environ.get(k) for k in {vars!r}}},
                  "warnings": [[w.category.__name__, str(w.message)] for w in caught], **extra}}))
"""


def _record(body: str, extra: str = "{}", **env_set: str) -> dict:
    """Run ``body`` (lines of code) with warnings recorded; returns the environment afterwards, the warnings and
    the dict expression ``extra`` evaluated at the end."""
    return _python(RECORD.format(body=textwrap.indent(body, "    "), extra=extra, vars=VARS), **env_set)


def test_import_sets_defaults_without_warning():
    out = _record("import gfbjax")
    env = out["env"]
    assert env["XLA_FLAGS"] == "--xla_cpu_enable_concurrency_optimized_scheduler=false"
    assert int(env["NPROC"]) >= 8 and env["OPENBLAS_NUM_THREADS"] == "1"
    assert env["OMP_NUM_THREADS"] is None
    assert out["warnings"] == []


def test_import_after_jax_started_warns_once():
    body = ("import jax; jax.numpy.zeros(1)\nimport gfbjax\n"
            "import gfbjax._process as pr; pr.configure_process()")
    out = _record(body)
    runtime = [m for c, m in out["warnings"] if c == "RuntimeWarning"]
    assert len(runtime) == 1, out["warnings"]
    assert "XLA_FLAGS" in runtime[0] and "NPROC" in runtime[0] and "before" in runtime[0]


def test_user_settings_are_left_untouched():
    mine = {"XLA_FLAGS": "--xla_cpu_enable_concurrency_optimized_scheduler=true", "NPROC": "3",
            "OPENBLAS_NUM_THREADS": "2"}
    out = _record("import jax; jax.numpy.zeros(1)\nimport gfbjax", **mine)
    assert {k: out["env"][k] for k in mine} == mine
    assert out["warnings"] == []  # nothing gfbjax had to set, so nothing came too late


def test_numpy_first_is_quiet_but_an_explicit_call_warns():
    # importing numpy before gfbjax is the normal order: no warning at import (scipy's OpenBLAS, the one the
    # solvers use through jaxlib, is loaded later and still reads the setting)
    body = ("import numpy\nimport gfbjax\nimport os, gfbjax._process as pr\nfirst = list(caught)\n"
            "del os.environ['OPENBLAS_NUM_THREADS']\nchanged = pr.configure_process()")
    out = _record(body, extra='{"first": len(first), "changed": changed}')
    assert out["first"] == 0
    assert out["changed"] == {"OPENBLAS_NUM_THREADS": "1"}
    assert [c for c, m in out["warnings"]] == ["RuntimeWarning"]
    assert "OPENBLAS_NUM_THREADS=1" in out["warnings"][0][1] and "numpy" in out["warnings"][0][1]


def test_plotting_and_cli_leave_the_matplotlib_backend():
    body = ("import matplotlib\nbefore = matplotlib.get_backend()\n"
            "import gfbjax.plot.static, gfbjax.plot.branch, gfbjax.plot.transient, gfbjax.cli\n"
            "gfbjax.cli.build_parser()\nafter = matplotlib.get_backend()")
    out = _record(body, extra='{"before": before, "after": after}', MPLBACKEND="svg")
    assert out["before"].lower() == "svg" and out["after"].lower() == "svg"
    assert out["env"]["OMP_NUM_THREADS"] is None  # registering the commands sets no thread counts either
    # without MPLBACKEND or a display, a backend chosen in code is kept too (plot.static used to switch to Agg)
    body = ("import matplotlib\nmatplotlib.use('svg')\n"
            "import gfbjax.plot.static, gfbjax.plot.branch, gfbjax.plot.transient\n"
            "after = matplotlib.get_backend()")
    out = _record(body, extra='{"after": after}')
    assert out["after"].lower() == "svg"


def test_cli_main_selects_agg():
    body = ("import matplotlib\nmatplotlib.use('svg')\nimport gfbjax.cli\n"
            "code = gfbjax.cli.main(['static', '--nx', '4'])\nafter = matplotlib.get_backend()")
    out = _record(body, extra='{"code": code, "after": after}')
    assert out["code"] == 2 and out["after"].lower() == "agg"
