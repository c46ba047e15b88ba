"""``gfbjax energy`` and ``gfbjax optimize``: help texts, input errors (exit 2 naming the option, before any
computation), tiny end-to-end runs (energy of a short cycle branch, the foil optimum at one speed, an optimised
continuation over two speeds) and the schedule figure (paper Figs. 16-19)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from gfbjax.cli import build_parser, main

GRID = ["--nx", "16", "--nz", "2", "--N", "8", "--m", "3"]
# the paper's pattern search, capped: a handful of cycle solves (compilation dominates the time)
FEW = ["--method", "pattern", "--max-evals", "2", "--quiet"]


def _run(argv, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def no_computation(monkeypatch):
    """Fail the test if a command gets as far as computing a cycle or a design."""
    import gfbjax.analyses.cycles
    import gfbjax.design.evaluate
    import gfbjax.design.schedule

    def boom(*a, **k):
        raise AssertionError("computation started before the options were checked")

    monkeypatch.setattr(gfbjax.analyses.cycles, "continue_gfb_cycles", boom)
    monkeypatch.setattr(gfbjax.design.evaluate, "FoilDesign", boom)
    monkeypatch.setattr(gfbjax.design.schedule, "optimized_continuation", boom)
    monkeypatch.setattr(gfbjax.design.schedule, "optimize_at_speed", boom)


def test_help_lists_options(capsys):
    code, out, _ = _run(["energy", "--help"], capsys)
    assert code == 0
    for opt in ["--system", "--set", "--nx", "--nz", "--out", "--start", "--end", "--m", "--N", "--ds", "--ds-max",
                "--dlam-max", "--max-points", "--no-locate", "--no-figures", "--quiet", "results/energy"]:
        assert opt in out, opt
    code, out, _ = _run(["optimize", "--help"], capsys)
    assert code == 0
    for opt in ["--system", "--set", "--nx", "--nz", "--out", "--objective", "--method", "--x0", "--max-evals",
                "--speed", "--start", "--end", "--step", "--m", "--N", "--no-figures", "--quiet", "max_mu",
                "pattern"]:
        assert opt in out, opt


def test_choices_and_defaults_agree_with_the_library():
    from gfbjax.cli.commands import optimize
    from gfbjax.design.schedule import METHODS, OBJECTIVES

    assert optimize.OBJECTIVES == OBJECTIVES and optimize.METHODS == METHODS
    parser, _ = build_parser()
    # energy takes the options of cycles from a private copy: the cycles command keeps its own default folder
    assert parser.parse_args(["cycles"]).out == Path("results") / "cycles"
    args = parser.parse_args(["energy"])
    assert args.out == Path("results") / "energy" and args.func.__module__ == "gfbjax.cli.commands.energy"
    args = parser.parse_args(["optimize", "--speed", "0.3"])
    assert (args.objective, args.method, args.x0) == ("max_mu", "gradient", None)


@pytest.mark.parametrize("argv, option", [
    (["--m", "9"], "--m"),
    (["--N", "1"], "--N"),
    (["--start", "-1"], "--start"),
    (["--start", "0.3", "--end", "0.3"], "--end"),
    (["--ds", "5", "--ds-max", "1"], "--ds-max"),
    (["--dlam-max", "0"], "--dlam-max"),
    (["--nx", "4"], "Nx"),
])
def test_energy_bad_input_exits_2(argv, option, capsys, tmp_path, no_computation):
    code, _, err = _run(["energy", *argv, "--out", str(tmp_path)], capsys)
    assert code == 2 and option in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("argv, option", [
    (["--speed", "0.3", "--x0", "3", "0.1"], "--x0"),
    (["--speed", "0.3", "--x0", "0.1", "20"], "--x0"),
    (["--speed", "0.3", "--set", "alpha_f=5"], "--x0"),  # the system's own foil is the default start
    (["--speed", "0.3", "--x0", "0.1"], "--x0"),
    (["--speed", "0"], "--speed"),
    (["--speed", "60"], "--speed"),
    ([], "--speed"),
    (["--speed", "0.3", "--start", "0.2", "--end", "0.4"], "--speed"),
    (["--start", "0.3"], "--end"),
    (["--end", "0.3"], "--start"),
    (["--start", "0.4", "--end", "0.3"], "--end"),
    (["--start", "0.3", "--end", "0.4", "--step", "0"], "--step"),
    (["--start", "0.3", "--end", "0.4", "--step", "2"], "--step"),
    (["--speed", "0.3", "--objective", "W_B"], "--objective"),
    (["--speed", "0.3", "--method", "bfgs"], "--method"),
    (["--speed", "0.3", "--max-evals", "0"], "--max-evals"),
    (["--speed", "0.3", "--m", "8"], "--m"),
    (["--speed", "0.3", "--N", "1"], "--N"),
    (["--speed", "0.3", "--nx", "4"], "Nx"),
])
def test_optimize_bad_input_exits_2(argv, option, capsys, tmp_path, no_computation):
    out = tmp_path / "opt"
    code, _, err = _run(["optimize", *argv, "--out", str(out)], capsys)
    assert code == 2 and option in err, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not out.exists()  # nothing written either


def test_energy_tiny_run(tmp_path, capsys):
    out = tmp_path / "en"
    code, stdout, _ = _run(["energy", *GRID, "--start", "0.3", "--end", "0.34", "--dlam-max", "0.02", "--quiet",
                            "--out", str(out)], capsys)
    assert code in (0, 1)
    for name in ["branch.npz", "branch.json", "energy.json", "energy.png"]:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    data = json.loads((out / "energy.json").read_text())
    pts = data["points"]
    assert len(pts) >= 2
    works = ("W_fu", "W_B", "W_cf", "W_cb")
    assert all(set(p) == {"Omega_bar", "rpm", "stable", *works, *(f"{w}_J" for w in works)} for p in pts)
    unit_J = 1e5 * 19.05e-3 * 38.1e-3 * 38.1e-6  # p0 R L c of the reference system (README), J
    for p in pts:
        for w in works:
            assert p[f"{w}_J"] == pytest.approx(p[w] * unit_J, rel=1e-12)
    for p in pts:
        assert p["W_fu"] > 0 and p["W_cf"] > 0
        assert p["W_cb"] == pytest.approx(p["W_B"] - p["W_cf"], rel=1e-12, abs=1e-15)
    assert data["max_rel_identity_error"] < 1e-9
    assert isinstance(data["NS_Omega_bar"], list) and isinstance(data["W_cb_sign_changes"], list)
    with np.load(out / "branch.npz") as z:
        np.testing.assert_allclose(z["lam"], [p["Omega_bar"] for p in pts])
    printed = [ln for ln in stdout.splitlines() if "identity error" in ln]
    assert printed and float(printed[0].split("=")[-1]) < 1e-9
    assert "NS speeds" in stdout and "W_cb sign changes" in stdout

    # the saved branch, read back with --branch, gives the same works without a continuation
    again = tmp_path / "again"
    code, stdout, _ = _run(["energy", "--branch", str(out / "branch.npz"), "--out", str(again)], capsys)
    assert code == (0 if data["range"]["reached_end"] else 1)
    pts2 = json.loads((again / "energy.json").read_text())["points"]
    assert [p["Omega_bar"] for p in pts2] == [p["Omega_bar"] for p in pts]
    for a, b in zip(pts, pts2):
        for key in ("W_fu", "W_B", "W_cf", "W_cb"):
            assert b[key] == pytest.approx(a[key], rel=1e-12, abs=1e-15), key
    assert not (again / "branch.npz").exists()  # nothing recomputed, nothing rewritten
    # a system option with --branch is refused: the system comes from the file
    code, _, err = _run(["energy", "--branch", str(out / "branch.npz"), "--nx", "24", "--out", str(again)], capsys)
    assert code == 2 and "--nx" in err
    # so are the step options: the branch's points are the file's (review of session 15: they were ignored)
    code, _, err = _run(["energy", "--branch", str(out / "branch.npz"), "--chord-tol", "0.5", "--dlam-max", "0.3",
                         "--out", str(again)], capsys)
    assert code == 2 and "--chord-tol" in err and "--dlam-max" in err


def test_optimize_one_speed(tmp_path, capsys):
    out = tmp_path / "one"
    code, stdout, _ = _run(["optimize", *GRID, "--speed", "0.3", *FEW, "--out", str(out)], capsys)
    assert code == 0
    for name in ["optimum.json", "optimum.png"]:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    d = json.loads((out / "optimum.json").read_text())
    assert d["n_solves"] > 0 and d["n_gradients"] == 0 and d["reason"] == "max_evals"
    assert d["stable"] is True and d["max_mu"] < 1.0
    assert d["objective"] == "max_mu" and d["objective_value"] == d["max_mu"]
    lo_a, hi_a, lo_e, hi_e = 0.005, 2.0, 1e-4, 10.0
    assert lo_a <= d["alpha_f"] <= hi_a and lo_e <= d["eta"] <= hi_e
    rows = np.asarray(d["history"]["rows"])
    assert d["history"]["columns"] == ["alpha_f", "eta", "max_mu", "seconds"]
    assert 1 <= len(rows) <= d["n_solves"] and rows[:, 2].min() == d["objective_value"]
    assert np.all(np.diff(rows[:, 3]) >= 0) and rows[-1, 3] <= d["seconds"]
    assert d["x0"] == {"alpha_f": 0.1, "eta": 0.05}  # the reference system's own foil
    assert "optimum" in stdout and "cycle solves" in stdout


def test_optimize_schedule_two_speeds(tmp_path, capsys):
    out = tmp_path / "sched"
    code, stdout, _ = _run(["optimize", *GRID, "--start", "0.3", "--end", "0.32", "--step", "0.02",
                            "--x0", "0.2", "0.1", *FEW, "--out", str(out)], capsys)
    assert code in (0, 1)
    for name in ["schedule.json", "schedule.png"]:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    d = json.loads((out / "schedule.json").read_text())
    n = len(d["Omega_bar"])
    assert n == 2 if code == 0 else 1 <= n <= 2
    np.testing.assert_allclose(d["Omega_bar"][:n], [0.3, 0.32][:n])
    for key in ["alpha_f", "eta", "W_cb", "max_mu", "stable", "journal_max", "journal_min", "multipliers_re"]:
        assert len(d[key]) == n, key
    assert d["objective"] == "max_mu" and d["method"] == "pattern" and d["n_solves"] >= n
    assert d["x0"] == {"alpha_f": 0.2, "eta": 0.1}
    assert "schedule" in stdout and "stable up to" in stdout


def test_plot_schedule_marks_unstable_points(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from gfbjax.design.schedule import Schedule
    from gfbjax.plot.branch import plot_schedule
    from test_plot import schedule  # the plot tests' three-speed schedule (one unstable point)

    s = schedule()
    fig = plot_schedule([("a", s), ("empty", Schedule("W_cb", "pattern"))], path=tmp_path / "s.png")
    assert (tmp_path / "s.png").stat().st_size > 0
    assert len(fig.axes) == 6
    assert fig.axes[1].get_yscale() == "log" and fig.axes[2].get_yscale() == "log"
    labels = fig.axes[3].get_legend_handles_labels()[1]
    assert "unstable" in labels
    plt.close(fig)
