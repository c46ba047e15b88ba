"""``gfbjax cycles`` and ``gfbjax equilibria``: help texts, input errors (exit 2 naming the option) and one tiny
cycle continuation end to end (branch.npz/json, cycles.json and figures)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from gfbjax import reference_system
from gfbjax.cli import main

TINY = ["--nx", "16", "--nz", "2", "--N", "8", "--m", "3"]


def _run(argv, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def test_cycles_help_lists_options(capsys):
    code, out, _ = _run(["cycles", "--help"], capsys)
    assert code == 0
    for opt in ["--system", "--set", "--nx", "--nz", "--out", "--start", "--end", "--m", "--N", "--ds",
                "--ds-max", "--dlam-max", "--chord-tol", "--max-points", "--no-locate", "--no-figures", "--quiet"]:
        assert opt in out, opt


def test_equilibria_help_lists_options(capsys):
    code, out, _ = _run(["equilibria", "--help"], capsys)
    assert code == 0
    for opt in ["--system", "--nx", "--out", "--start", "--end", "--ds", "--ds-max", "--max-points", "--no-locate"]:
        assert opt in out, opt


@pytest.mark.parametrize("argv, option", [
    (["--m", "9"], "--m"),
    (["--m", "1"], "--m"),
    (["--N", "1"], "--N"),
    (["--start", "-1"], "--start"),
    (["--end", "0"], "--end"),
    (["--start", "0.3", "--end", "0.3"], "--end"),
    (["--ds", "0"], "--ds"),
    (["--ds", "5", "--ds-max", "1"], "--ds-max"),
    (["--dlam-max", "-0.1"], "--dlam-max"),
    (["--chord-tol", "0"], "--chord-tol"),
    (["--chord-tol=-0.01"], "--chord-tol"),
    (["--chord-tol", "nan"], "--chord-tol"),
    (["--chord-tol", "1e-9"], "--chord-tol"),
    (["--max-points", "1"], "--max-points"),
    (["--nx", "4"], "Nx"),
    (["--m", "abc"], "--m"),
])
def test_cycles_bad_input_exits_2(argv, option, capsys, tmp_path):
    code, out, err = _run(["cycles", *argv, "--out", str(tmp_path)], capsys)
    assert code == 2
    assert option in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("argv, option", [(["--start", "-1"], "--start"), (["--ds", "-1"], "--ds")])
def test_equilibria_bad_input_exits_2(argv, option, capsys, tmp_path):
    code, _, err = _run(["equilibria", *argv, "--out", str(tmp_path)], capsys)
    assert code == 2 and option in err


def test_cycles_tiny_run_writes_everything(tmp_path, capsys):
    out = tmp_path / "cyc"
    code, stdout, _ = _run(["cycles", *TINY, "--start", "0.2", "--end", "0.3", "--dlam-max", "0.05",
                            "--max-points", "6", "--quiet", "--out", str(out)], capsys)
    assert code in (0, 1)
    for name in ["branch.npz", "branch.json", "cycles.json", "cycles_bifurcation.png", "cycles_multipliers.png"]:
        assert (out / name).is_file(), name
        assert (out / name).stat().st_size > 0, name
    meta = json.loads((out / "branch.json").read_text())  # plain json, no gfbjax
    assert meta["kind"] == "cycles" and isinstance(meta["special"], list)
    # self-describing: the system with its conventions, the grid, component names, units, rpm conversion
    spec = reference_system(Nx=16, Nz=2)
    assert meta["format"] == "gfbjax.cont.Branch" and meta["meta"]["spec"]["Nx"] == 16
    assert meta["meta"]["spec"]["alpha_f"] == spec.alpha_f and meta["meta"]["problem"] == "unbalance_response"
    assert meta["meta"]["grid"] == {"Nx": 16, "Nz": 2, "n_theta": 15, "n_pressure": 30}
    assert meta["meta"]["rpm_per_omega_bar"] == pytest.approx(spec.rpm(1.0))
    assert meta["component_names"] == ["x_j", "y_j", "x_d", "y_d"] and "Omega_bar" in meta["units"]["lam"]
    with np.load(out / "branch.npz") as z:
        lam = z["lam"]
        assert z["xmax"].shape[0] == lam.size >= 2
        assert z["multipliers"].shape[0] == lam.size
    summary = json.loads((out / "cycles.json").read_text())
    assert summary["counts"]["points"] == lam.size
    assert summary["settings"]["chord_tol"] == 0.01 and summary["settings"]["dlam_max"] == 0.05
    assert summary["outcome"] == meta["outcome"] and summary["message"] == meta["message"]
    assert summary["range"]["reached_end"] == (code == 0)
    assert set(summary["timings_s"]) >= {"continuation", "total"}
    assert "special points" in stdout

    # the branch file is what `gfbjax runup --cycles` overlays on the run-up (paper Fig. 7a/b)
    from gfbjax.cli.commands.runup import _cycle_overlay

    ov = _cycle_overlay(str(out / "branch.npz"), spec, "reference")
    np.testing.assert_array_equal(ov["speed"], lam)
    assert ov["y_max"].shape == ov["y_min"].shape == lam.shape
    assert np.all(ov["y_max"] >= ov["y_min"]) and np.all(ov["x_max"] >= ov["x_min"])


def test_runup_bad_cycles_file_exits_2_before_integrating(tmp_path, capsys):
    code, _, err = _run(["runup", *TINY[:4], "--cycles", str(tmp_path / "missing.npz"), "--out", str(tmp_path)],
                        capsys)
    assert code == 2 and "--cycles" in err and "missing.npz" in err and len(err.strip().splitlines()) == 1


def test_equilibria_hopf_cycles_tiny_run(tmp_path, capsys):
    """Table 1 from the command line: equilibria, their Hopf point and the cycles born there (tiny grid)."""
    out = tmp_path / "eq"
    code, stdout, _ = _run(["equilibria", "--system", "validation10N", "--nx", "16", "--nz", "2", "--start", "0.4",
                            "--end", "0.9", "--hopf-cycles", "4", "--quiet", "--out", str(out)], capsys)
    assert code in (0, 1)
    summary = json.loads((out / "equilibria.json").read_text())
    assert any(d["type"] == "HOPF" for d in summary["special"])
    hc = summary["hopf_cycles"]
    assert hc["points"] >= 2 and hc["criticality"] in ("subcritical", "supercritical", "undetermined")
    for name in ["hopf_cycles.npz", "hopf_cycles.json", "hopf_cycles.png"]:
        assert (out / name).is_file(), name
    for name, problem in (("branch.json", "equilibria"), ("hopf_cycles.json", "self_excited")):
        meta = json.loads((out / name).read_text())["meta"]
        assert meta["problem"] == problem and meta["spec"]["rotor"] == "rigid" and meta["grid"]["Nx"] == 16
        assert meta["rpm_per_omega_bar"] > 0
    assert "Hopf cycles" in stdout


def test_equilibria_bad_hopf_cycles_exits_2(tmp_path, capsys):
    code, _, err = _run(["equilibria", *TINY[:4], "--hopf-cycles", "-3", "--out", str(tmp_path)], capsys)
    assert code == 2 and "--hopf-cycles" in err


def _bar_after(calls, restored=0, t_first=None):
    """A disabled speed bar that has seen the rows ``calls`` (indices), its first computed one at ``t_first``."""
    from gfbjax.cli.commands.cycles import _SpeedBar

    bar = _SpeedBar(0.1, 0.5, False, restored)
    for i in calls:
        bar(i, None)
    bar.t_first = t_first if bar.computed else None
    return bar


def test_summary_time_keeps_the_compilation_out_of_the_per_point_figure():
    from gfbjax.cli.commands.cycles import _time_split

    # 10 s of continuation, the first point after 7 s (compilation), 4 points: 1 s for each later point
    assert (_time_split(10.0, 100.0, _bar_after(range(4), t_first=107.0))
            == " (first point 7.0 s, compilation included; then 1.00 s per point)")
    assert _time_split(10.0, 100.0, _bar_after([0], t_first=107.0)) == " (10.00 s per point)"
    assert _time_split(10.0, 100.0, _bar_after([])) == ""


def test_summary_time_of_a_resumed_run_counts_only_its_own_points():
    from gfbjax.cli.commands.cycles import _time_split

    # 12 rows restored: the first callback is the checkpoint's last row (index 11), then 4 new rows
    assert (_time_split(10.0, 100.0, _bar_after(range(11, 16), restored=12, t_first=107.0))
            == " (resumed after 12 rows; first point 7.0 s, compilation included; then 1.00 s per point)")
    # a finished branch read back: nothing computed, no per-point figure
    assert _time_split(0.5, 100.0, _bar_after([], restored=30)) == " (resumed after 30 rows; no new point)"
