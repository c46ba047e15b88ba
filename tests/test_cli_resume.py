"""Fault test of the checkpoints: ``kill -9`` of ``gfbjax cycles`` and then ``--resume`` loses no point beyond the
one in progress, and the final branch equals an uninterrupted run's (issue: long runs that lose nothing)."""
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from gfbjax.cont import Branch

ARGS = ["cycles", "--nx", "16", "--nz", "2", "--N", "8", "--start", "0.3", "--end", "0.42", "--no-figures",
        "--quiet"]


def _gfbjax(args, env, **kw):
    return subprocess.Popen([sys.executable, "-m", "gfbjax", *args], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, **kw)


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    # one compilation cache for the three runs: the second and third load the kernels the first compiled
    return {**os.environ, "GFBJAX_CACHE_DIR": str(tmp_path_factory.mktemp("jax_cache"))}


@pytest.mark.slow
def test_kill_9_then_resume_equals_uninterrupted(tmp_path, env):
    whole = _gfbjax([*ARGS, "--out", str(tmp_path / "whole")], env)
    out_whole, _ = whole.communicate(timeout=900)
    assert whole.returncode == 0, out_whole
    ref = Branch.load(tmp_path / "whole" / "branch")
    assert len(ref) >= 6 and [s.type for s in ref.special] == ["NS"], out_whole

    run = tmp_path / "killed"
    victim = _gfbjax([*ARGS, "--out", str(run)], env)
    target = run / "checkpoint" / "step_00003.npz"
    deadline = time.monotonic() + 900
    while not target.exists() and victim.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert victim.poll() is None, "the run finished before it could be killed"
    os.kill(victim.pid, signal.SIGKILL)
    victim.communicate(timeout=60)
    assert victim.returncode == -signal.SIGKILL
    written = len(list((run / "checkpoint").glob("step_*.npz")))
    assert 4 <= written < len(ref)
    assert not (run / "branch.npz").exists()  # nothing was written at the end: the checkpoint is all there is

    resumed = _gfbjax(["cycles", "--resume", str(run), "--quiet"], env)
    out, _ = resumed.communicate(timeout=900)
    assert resumed.returncode == 0, out
    assert "resuming" in out
    # its time line counts only the points it computed, after the rows the killed run had written
    resumed_after = re.search(r"resumed after (\d+) rows; first point", out)
    assert resumed_after and written <= int(resumed_after.group(1)) < len(ref), out
    got = Branch.load(run / "branch")
    assert got.outcome is ref.outcome and len(got) == len(ref)
    for key in ("lam", "period", "l2", "xmax", "xmin", "trivial_error", "tangent_lam"):
        np.testing.assert_allclose(getattr(got, key), getattr(ref, key), rtol=1e-8, atol=1e-10, err_msg=key)
    np.testing.assert_allclose(np.abs(got.multipliers), np.abs(ref.multipliers), rtol=1e-8, atol=1e-10)
    assert [(s.type, s.located) for s in got.special] == [(s.type, s.located) for s in ref.special]
    np.testing.assert_allclose([s.lam for s in got.special], [s.lam for s in ref.special], rtol=1e-8)


def test_resume_refuses_other_options(tmp_path, env):
    from gfbjax.cli import main

    (tmp_path / "checkpoint").mkdir()
    (tmp_path / "cycles_args.json").write_text('{"N": 8, "nx": 16}')
    assert main(["cycles", "--resume", str(tmp_path), "--N", "12"]) == 2
    assert main(["cycles", "--resume", str(tmp_path), "--no-checkpoint"]) == 2
    assert main(["cycles", "--resume", str(tmp_path / "nothing")]) == 2


def test_bad_input_leaves_a_resumable_checkpoint_alone(tmp_path):
    """Every option is checked before an old checkpoint is cleared (a fresh user's report: a bad --h-rub-um after
    an interrupted run deleted it)."""
    from gfbjax.cli import main

    ck = tmp_path / "checkpoint"
    ck.mkdir()
    (ck / "step_00000.npz").write_bytes(b"kept")
    assert main(["cycles", "--nx", "16", "--nz", "2", "--out", str(tmp_path), "--h-rub-um", "-5"]) == 2
    assert (ck / "step_00000.npz").read_bytes() == b"kept"


def test_damaged_checkpoint_is_a_one_line_error(tmp_path, capsys):
    from gfbjax.cli import main

    (tmp_path / "checkpoint").mkdir()
    (tmp_path / "checkpoint" / "journal.json").write_text("{not json")
    (tmp_path / "cycles_args.json").write_text('{"nx": 16, "nz": 2, "N": 8, "start": 0.3, "end": 0.32}')
    assert main(["cycles", "--resume", str(tmp_path), "--quiet", "--no-figures"]) == 2
    err = capsys.readouterr().err
    assert "journal.json unreadable" in err and "Traceback" not in err


def test_resume_refuses_another_out(tmp_path):
    from gfbjax.cli import main

    (tmp_path / "checkpoint").mkdir()
    (tmp_path / "cycles_args.json").write_text('{"N": 8, "nx": 16}')
    assert main(["cycles", "--resume", str(tmp_path), "--out", str(tmp_path / "elsewhere")]) == 2


def test_contact_summary_counts_the_located_contact():
    """A branch that ended at the located contact: its last point is the contact (h_min = h_rub to rounding),
    counted and named as such; a flagging branch counts the points at or below h_rub."""
    import numpy as np
    from types import SimpleNamespace

    from gfbjax.cli.commands._contact import contact_summary

    class Branch(SimpleNamespace):  # the attributes contact_summary reads
        def __len__(self):
            return len(self.lam)

    spec = SimpleNamespace(c=38.1e-6)
    stop = Branch(monitor=np.array([0.3, 0.1, 1e-9]), lam=np.array([0.2, 0.22, 0.233]),
                           monitor_info={"minimum": 0.0, "stop": True}, outcome="contact")
    d = contact_summary(stop, spec)
    assert d["points_in_contact"] == 1 and d["first_contact_Omega_bar"] == 0.233
    assert d["first_contact_is"] == "the located crossing"
    flag = Branch(monitor=np.array([0.3, 0.1, -0.05, -0.1]), lam=np.array([0.2, 0.22, 0.24, 0.26]),
                           monitor_info={"minimum": 0.0, "stop": False}, outcome="reached_end")
    d = contact_summary(flag, spec)
    assert d["points_in_contact"] == 2 and d["first_contact_Omega_bar"] == 0.24 and d["on_contact"] == "flag"


def test_special_points_in_contact_or_unresolved_are_flagged():
    """With --on-contact flag a branch goes on past contact: a special point there is listed as FLAGGED (film
    contact), and so is one on a point whose trivial multiplier or mesh error is above its tolerance."""
    import numpy as np
    from types import SimpleNamespace

    from gfbjax.cli.commands.cycles import _row_flags, format_table

    class Branch(SimpleNamespace):
        def __len__(self):
            return len(self.lam)

    br = Branch(lam=np.array([0.2, 0.22, 0.24, 0.26]), monitor=np.array([0.3, 0.1, -0.05, -0.1]),
                monitor_info={"minimum": 0.0, "stop": False}, accuracy_tol=1e-3,
                trivial_error=np.array([1e-9, 1e-2, 1e-9, 1e-9]), mesh_tol=1e-4,
                mesh_error=np.array([1e-6, 1e-6, 1e-6, 1e-3]), stiff_modulus=np.array([0.95, 0.1, 0.1, 0.1]),
                stiff_tol=0.9, multiplier_error=np.array([0.0, 0.0, 0.0, 2e-3]), multiplier_tol=1e-3)
    assert _row_flags(br, 0) == ["spurious multipliers"]
    assert _row_flags(br, 1) == ["trivial error"]
    assert _row_flags(br, 2) == ["film contact"]
    assert _row_flags(br, 3) == ["film contact", "mesh error", "multipliers unresolved"]
    row = {"type": "NS", "Omega_bar": 0.24, "rpm": 9000.0, "multiplier_moduli": [1.0, 1.0], "located": True,
           "localisation": "located", "flags": _row_flags(br, 2)}
    assert "FLAGGED: film contact" in format_table([row])


def test_special_point_table_gives_the_estimated_error():
    """The table's "+-" column is SpecialPoint.lam_error (``Omega_bar_error`` in cycles.json); "?" where none was
    estimated."""
    from gfbjax.cli.commands.cycles import format_table

    rows = [{"type": "NS", "Omega_bar": 0.3768, "rpm": 13326.0, "multiplier_moduli": [1.0, 1.0], "located": True,
             "localisation": "located", "Omega_bar_error": 2.1e-5, "flags": []},
            {"type": "PD", "Omega_bar": 0.5, "rpm": 17700.0, "multiplier_moduli": [1.0], "located": False,
             "localisation": "not localised", "Omega_bar_error": None, "flags": ["not localised"]}]
    lines = format_table(rows).splitlines()
    assert "+-" in lines[1]
    assert "2.1e-05" in lines[2] and lines[3].split()[2] == "?"
    assert lines[2].rstrip().endswith("located") and "FLAGGED" not in lines[2]
    assert "FLAGGED: not localised" in lines[3]


def test_unlocated_special_points_are_flagged_in_the_table():
    """A special point that was not located carries how it was placed ("bracketed": a jump pinned down, no zero;
    "not localised": the first point past it) as a flag of its row, not only in the last column."""
    from gfbjax.cli.commands.cycles import format_table, special_summary
    from gfbjax.cont import SpecialPoint
    from gfbjax.params import SystemSpec

    from types import SimpleNamespace

    mu = np.array([1.0, -0.5 + 0.9j, -0.5 - 0.9j])
    class Rows(SimpleNamespace):
        def __len__(self):
            return len(self.lam)

    br = Rows(lam=np.array([0.2, 0.22, 0.24]), xmax=np.ones((3, 2)), xmin=-np.ones((3, 2)), monitor=None,
              monitor_info=None, accuracy_tol=None, mesh_error=None, mesh_tol=None, stiff_modulus=None,
              stiff_tol=None, multiplier_error=None, multiplier_tol=None, special=[
        SpecialPoint("NS", 0.21, 1, mu, located=True, residual=1e-10, lam_error=1e-6, angle=2.0),
        SpecialPoint("NS", 0.23, 2, mu, located=False, residual=0.3, lam_error=8e-11, angle=2.0),
        SpecialPoint("PD", 0.24, 2, mu, located=False)])
    rows = special_summary(br, SystemSpec())
    assert [r["localisation"] for r in rows] == ["located", "bracketed", "not localised"]
    assert [r["flags"] for r in rows] == [[], ["bracketed"], ["not localised"]]
    lines = format_table(rows).splitlines()[2:]
    assert "FLAGGED" not in lines[0] and "FLAGGED: bracketed" in lines[1] and "FLAGGED: not localised" in lines[2]


def test_accuracy_line_gives_each_cause_its_own_remedy():
    """Review case: the line always advised "--collocation radau", also on Radau runs and for multipliers that
    Radau points make worse; it said "1 points"; a branch too large for the resolution estimate (all NaN) gave
    NaN maxima with a warning."""
    from types import SimpleNamespace

    from gfbjax.cli.commands._contact import accuracy_line, accuracy_summary
    from gfbjax.cont import Branch as RealBranch

    class Rows(SimpleNamespace):
        def __len__(self):
            return len(self.lam)

        flagged = property(lambda self: RealBranch.flagged.fget(self))

    common = dict(lam=np.arange(3.0), trivial_error=np.full(3, 1e-9), accuracy_tol=1e-5, mesh_error=np.full(3, 1e-6),
                  mesh_tol=1e-4, stiff_tol=0.9, multiplier_tol=1e-3, monitor=None, monitor_info=None)
    gauss = Rows(**common, collocation="gauss", stiff_modulus=np.array([0.95, 0.2, 0.1]),
                 multiplier_error=np.array([0.5, 2e-3, 1e-6]))
    line = accuracy_line(accuracy_summary(gauss))
    assert "2 points flagged" in line and "spurious multipliers up to |mu| 0.950" in line
    assert "1 with spurious multipliers above stiff_tol = 0.9: refine --N or --collocation radau" in line
    assert "2 with multipliers not resolved to multiplier_tol = 0.001: refine --N" in line
    radau = Rows(**common, collocation="radau", stiff_modulus=np.zeros(3), multiplier_error=np.array([2e-3, 0, 0]))
    line = accuracy_line(accuracy_summary(radau))
    assert "1 point flagged" in line and "radau" not in line.split("flagged")[1] and "spurious" not in line
    big = Rows(**common, collocation="gauss", stiff_modulus=np.full(3, np.nan), multiplier_error=np.full(3, np.nan))
    acc = accuracy_summary(big)
    assert acc["max_multiplier_error"] is None and acc["max_stiff_modulus"] is None
    assert "flagged" not in accuracy_line(acc)


def test_fresh_run_refuses_to_delete_an_unfinished_checkpoint(tmp_path, capsys):
    """Re-running the command without --resume into the folder of a killed run must not delete its points (a
    new user's report: the same command line again cleared OUT/checkpoint/); --fresh does, and a finished run's
    checkpoint (end.json) is cleared as before."""
    from gfbjax.cli.commands._checkpoints import checkpoint_folder
    from gfbjax.cli.commands.cycles import register
    from gfbjax.params import ParameterError
    import argparse

    ck = tmp_path / "checkpoint"
    ck.mkdir()
    (ck / "step_00000.npz").write_bytes(b"kept")
    parser = register(argparse.ArgumentParser().add_subparsers())
    args = parser.parse_args(["--out", str(tmp_path)])
    with pytest.raises(ParameterError, match=r"unfinished 'gfbjax cycles' run \(1 accepted step.*--resume"):
        checkpoint_folder(args, tmp_path, "cycles")
    assert (ck / "step_00000.npz").read_bytes() == b"kept"
    (ck / "end.json").write_text('{"outcome": "reached_end", "message": ""}')
    checkpoint_folder(args, tmp_path, "cycles")  # finished: cleared for the new run
    assert not (ck / "step_00000.npz").exists()
    ck.mkdir()
    (ck / "step_00000.npz").write_bytes(b"again")  # unfinished again
    checkpoint_folder(parser.parse_args(["--out", str(tmp_path), "--fresh"]), tmp_path, "cycles")
    assert not (ck / "step_00000.npz").exists()


def test_fresh_and_resume_exclude_each_other(tmp_path):
    from gfbjax.cli import main

    (tmp_path / "checkpoint").mkdir()
    (tmp_path / "cycles_args.json").write_text('{"N": 8, "nx": 16}')
    assert main(["cycles", "--resume", str(tmp_path), "--fresh"]) == 2


def test_the_refusal_names_the_command_that_owns_the_folder(tmp_path):
    """An unfinished 'gfbjax cycles' folder met by 'gfbjax energy': the advice is to resume it with cycles (a new
    user's report: it said 'gfbjax energy --resume', which then failed), and energy's --resume points there too."""
    from gfbjax.cli.commands._checkpoints import checkpoint_folder, resume_args
    from gfbjax.cli.commands.energy import register
    from gfbjax.params import ParameterError
    import argparse

    (tmp_path / "checkpoint").mkdir()
    (tmp_path / "checkpoint" / "step_00000.npz").write_bytes(b"kept")
    (tmp_path / "cycles_args.json").write_text('{"N": 8}')
    parser = register(argparse.ArgumentParser().add_subparsers())
    with pytest.raises(ParameterError, match=r"unfinished 'gfbjax cycles' run .*gfbjax cycles --resume"):
        checkpoint_folder(parser.parse_args(["--out", str(tmp_path)]), tmp_path, "energy")
    with pytest.raises(ParameterError, match=r"no energy_args.json there\); it holds a 'gfbjax cycles' run"):
        resume_args(parser.parse_args(["--resume", str(tmp_path)]), "energy")
    assert (tmp_path / "checkpoint" / "step_00000.npz").read_bytes() == b"kept"
