"""The command line: help texts, a small static run end to end, and input errors (exit 2, one line, no traceback).

Runs in-process through ``gfbjax.cli.main`` to avoid interpreter and JAX start-up per call; one subprocess test
checks ``python -m gfbjax``.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from gfbjax.cli import main

SMALL = ["--nx", "24", "--nz", "3"]


def _run(argv, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def test_top_level_help_lists_commands(capsys):
    code, out, _ = _run(["--help"], capsys)
    assert code == 0
    assert "static" in out and "COMMAND" in out


def test_no_command_prints_help(capsys):
    code, out, _ = _run([], capsys)
    assert code == 0
    assert "usage: gfbjax" in out


def test_static_help_lists_every_option(capsys):
    code, out, _ = _run(["static", "--help"], capsys)
    assert code == 0
    for opt in ["--system", "--set", "--nx", "--nz", "--out", "--speed", "--rpm", "--load", "--w", "--curves",
                "--alphas", "--speeds", "--loads", "--profile-speed", "--no-figures", "--quiet"]:
        assert opt in out, opt
    # the named systems and the SystemSpec fields are documented
    for word in ["reference", "ks0.3", "af1", "G0", "validation10N", "alpha_f (float)", "Nx (int)"]:
        assert word in out, word


@pytest.fixture(scope="module")
def static_run(tmp_path_factory):
    """One small static run shared by the checks below."""
    out = tmp_path_factory.mktemp("static")
    code = main(["static", "--speed", "0.3", *SMALL, "--out", str(out)])
    return code, out


def test_static_writes_json_and_figures(static_run):
    code, out = static_run
    assert code == 0
    data = json.loads((out / "static.json").read_text())
    eq = data["equilibrium"]
    assert eq["outcome"] == "converged"
    assert eq["residual"] < 1e-8
    assert eq["omega_bar"] == pytest.approx(0.3)
    assert eq["n_states"] == 23 * 3 + 23 + 8  # pressures + foil strips + Jeffcott rotor
    assert -1.5 < eq["y_j"] < 0.0  # gravity pulls the journal down
    assert isinstance(eq["stable"], bool)
    assert data["system"]["name"] == "reference"
    assert data["system"]["spec"]["Nx"] == 24 and data["system"]["spec"]["Nz"] == 3
    assert data["system"]["spec"]["alpha_f"] == pytest.approx(0.1)
    assert data["curves"] is None
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert pngs == ["static_summary.png"]
    assert (out / "static_summary.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_static_prints_summary(tmp_path, capsys):
    code, out, err = _run(["static", "--rpm", "12000", "--load", "2", "--set", "G=0", *SMALL, "--no-figures",
                           "--out", str(tmp_path)], capsys)
    assert code == 0, err
    for word in ["journal", "eccentricity", "attitude angle", "h_min", "p_max", "critical eigenvalue", "states",
                 " um", "rpm"]:
        assert word in out, word
    data = json.loads((tmp_path / "static.json").read_text())
    assert data["operating_point"]["speed_rpm"] == pytest.approx(12000.0)
    assert data["equilibrium"]["SI"]["extra_load_N"] == pytest.approx(2.0)
    assert data["system"]["spec"]["G"] == 0.0
    assert not list(tmp_path.glob("*.png"))


def test_static_without_an_equilibrium_gives_no_stability_verdict(tmp_path, capsys):
    """A new user's audit: at Omega_bar = 1e-6 the film carries no load (no_solution, exit 1), yet the summary
    printed the last iterate's critical eigenvalue with "UNSTABLE" and wrote "stable": false; a state that is no
    equilibrium has no stability."""
    code, out, err = _run(["static", "--speed", "1e-6", *SMALL, "--no-figures", "--out", str(tmp_path)], capsys)
    data = json.loads((tmp_path / "static.json").read_text())
    assert code == 1 and data["equilibrium"]["outcome"] != "converged", (code, data["equilibrium"]["outcome"])
    assert data["equilibrium"]["stable"] is None
    assert "no stability verdict" in out and "UNSTABLE" not in out and "STABLE" not in out


def test_static_curves_small(tmp_path, capsys):
    code, out, err = _run(["static", "--speed", "0.3", *SMALL, "--curves", "--alphas", "0.1,1", "--speeds",
                           "0.3,0.6", "--loads", "0,0.2", "--quiet", "--out", str(tmp_path)], capsys)
    assert code == 0, err
    data = json.loads((tmp_path / "static.json").read_text())
    curves = data["curves"]
    assert len(curves) == 4
    assert {(c["alpha_f"], c["omega_bar"]) for c in curves} == {(0.1, 0.3), (0.1, 0.6), (1.0, 0.3), (1.0, 0.6)}
    for c in curves:
        ys = [p["y_j"] for p in c["points"] if p["outcome"] == "converged"]
        assert len(ys) >= 1
        assert all(b < a for a, b in zip(ys, ys[1:]))  # more load, lower journal
    assert {p.name for p in tmp_path.glob("*.png")} == {"static_summary.png", "load_displacement.png",
                                                       "equilibrium_locus.png"}


@pytest.mark.parametrize(
    "argv, word",
    [
        (["--set", "alpha_f=-1"], "alpha_f"),
        (["--set", "alpha_f=abc"], "alpha_f"),
        (["--set", "nonsense=1"], "nonsense"),
        (["--set", "Nx=12.5"], "Nx"),
        (["--set", "alpha_f"], "--set"),
        (["--speed", "-1"], "--speed"),
        (["--speed", "nan"], "--speed"),
        (["--rpm", "0"], "--rpm"),
        (["--w", "-0.5"], "--w"),
        (["--load", "-3"], "--load"),
        (["--nx", "4"], "Nx"),
        (["--system", "nosuchsystem"], "system"),
        (["--system", "missing.toml"], "missing.toml"),
        (["--speeds", "0.2,x"], "--speeds"),
        (["--loads", "0.4,0.2"], "--loads"),
        (["--alphas", "0,1"], "--alphas"),
        (["--speed", "fast"], "--speed"),
        (["--speed", "0.3", "--rpm", "1000"], "--rpm"),
    ],
)
def test_bad_input_exits_2_with_one_line(argv, word, tmp_path, capsys):
    code, out, err = _run(["static", *SMALL, *argv, "--out", str(tmp_path / "o")], capsys)
    assert code == 2
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("gfbjax: warning:")]
    assert len(lines) == 1, err
    assert word in lines[0]
    assert "Traceback" not in err
    assert not (tmp_path / "o" / "static.json").exists()


def test_toml_config(tmp_path, capsys):
    cfg = tmp_path / "sys.toml"
    cfg.write_text('base = "af1"\neta = 0.2\n')
    bad = tmp_path / "bad.toml"
    bad.write_text('base = "af1"\nalpha = 0.2\n')
    code, _, err = _run(["static", "--system", str(bad), *SMALL, "--out", str(tmp_path / "o")], capsys)
    assert code == 2 and "alpha" in err
    from gfbjax.cli.commands._common import parse_set

    assert parse_set(["e_u=none", "Nx=32", "rotor=rigid", "theta0=pi/2"]) == {
        "e_u": None, "Nx": 32, "rotor": "rigid", "theta0": pytest.approx(1.5707963267948966)}


def test_python_dash_m_help():
    r = subprocess.run([sys.executable, "-m", "gfbjax", "static", "--help"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    assert "--speed" in r.stdout


def test_sigterm_is_handled_like_sigint():
    """While a command runs, SIGTERM raises KeyboardInterrupt (a continuation then ends with outcome
    'interrupted' and writes its points, and the command exits 130); the previous handler comes back after."""
    import os
    import signal

    from gfbjax.cli import _terminate_as_interrupt

    before = signal.getsignal(signal.SIGTERM)
    previous = _terminate_as_interrupt()
    try:
        with pytest.raises(KeyboardInterrupt):  # the handler runs as soon as os.kill returns
            os.kill(os.getpid(), signal.SIGTERM)
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert signal.getsignal(signal.SIGTERM) == before
