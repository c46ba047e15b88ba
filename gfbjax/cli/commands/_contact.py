"""Film contact options of the continuation commands: where the minimum film thickness h_min reaches the contact
thickness (``--h-rub-um``, micrometres), a branch ends there or goes on with the points flagged (``--on-contact``);
see :func:`gfbjax.analyses.cycles.film_monitor`."""
from __future__ import annotations

import argparse
import math
from typing import Any

import numpy as np

__all__ = ["add_contact_options", "contact_kwargs", "contact_line", "contact_summary", "accuracy_summary",
           "accuracy_line"]


def add_contact_options(parser: argparse.ArgumentParser) -> None:
    g = parser.add_argument_group("film contact")
    g.add_argument("--h-rub-um", dest="h_rub_um", type=float, default=0.0, metavar="UM",
                   help="film thickness at which the journal is taken to touch the foil, in micrometres (default 0: "
                        "the film closes)")
    g.add_argument("--on-contact", choices=("stop", "flag"), default="stop",
                   help="at contact: end the branch there (stop, default) or go on and flag the points (flag); the "
                        "model does not describe a closed film either way")


def contact_kwargs(args: argparse.Namespace, spec: Any) -> dict[str, Any]:
    """``h_rub`` (over c) and ``on_contact`` for the analyses; ParameterError for a bad --h-rub-um."""
    from ... import limits

    h_um = limits.Range("--h-rub-um", 0.0, spec.c * 1e6, hi_open=True,
                        what="micrometres, below the clearance").check(args.h_rub_um)
    return {"h_rub": h_um / (spec.c * 1e6), "on_contact": args.on_contact}


def contact_summary(branch: Any, spec: Any) -> dict[str, Any] | None:
    """The film figures of a branch for the JSON summary (None without a film monitor)."""
    if branch.monitor is None or not len(branch):
        return None
    h = np.asarray(branch.monitor, float)
    info = branch.monitor_info or {}
    low = h <= float(info.get("minimum", 0.0))
    if str(branch.outcome) == "contact":  # the located crossing is the last point (its h_min equals h_rub)
        low[-1] = True
    return {"h_min_over_c": float(np.min(h)), "h_min_um": float(np.min(h)) * spec.c * 1e6,
            "at_Omega_bar": float(branch.lam[int(np.argmin(h))]), "h_rub_over_c": info.get("minimum"),
            "on_contact": "stop" if info.get("stop", True) else "flag", "points_in_contact": int(np.sum(low)),
            "first_contact_Omega_bar": float(branch.lam[int(np.argmax(low))]) if low.any() else None,
            "first_contact_is": (None if not low.any() else "the located crossing" if str(branch.outcome) == "contact"
                                 else "the first point at or below h_rub (not located: --on-contact flag)")}


def contact_line(branch: Any, spec: Any) -> str:
    d = contact_summary(branch, spec)
    line = (f"  film              min h_min = {d['h_min_over_c']:.4f} c ({d['h_min_um']:.2f} um) at Omega_bar "
            f"{d['at_Omega_bar']:.4f}")
    if str(branch.outcome) == "contact":
        line += f"; the branch ends at the located contact, Omega_bar {d['first_contact_Omega_bar']:.4f}"
    elif d["points_in_contact"]:
        line += (f"; CONTACT from Omega_bar {d['first_contact_Omega_bar']:.4f} ({d['points_in_contact']} points "
                 "flagged: outside the model's validity; special points there are not physical)")
    return line if math.isfinite(d["h_min_over_c"]) else "  film              h_min not available"


def accuracy_summary(branch: Any) -> dict[str, Any]:
    """Why points of a cycle branch are flagged, count by count (trivial multiplier, mesh error, spurious
    multipliers of unresolved fast modes, multipliers of modes the mesh does not resolve, film contact)."""
    def count(values: Any, tol: Any, above: bool = True) -> int:
        if values is None or tol is None:
            return 0
        v = np.asarray(values, float)
        return int(np.sum(v > tol) if above else np.sum(v <= tol))

    def largest(values: Any) -> float | None:
        # None where nothing was estimated (an older file, an empty branch, or every value NaN: too large a
        # problem for the resolution estimate)
        v = None if values is None else np.asarray(values, float)
        return None if v is None or not np.any(np.isfinite(v)) else float(np.nanmax(v))

    info = branch.monitor_info or {}
    return {"trivial_tol": branch.accuracy_tol, "mesh_tol": branch.mesh_tol,
            "max_trivial_error": largest(branch.trivial_error),
            "max_mesh_error": largest(branch.mesh_error),
            "collocation": branch.collocation, "stiff_tol": branch.stiff_tol,
            "max_stiff_modulus": largest(branch.stiff_modulus),
            "multiplier_tol": branch.multiplier_tol,
            "max_multiplier_error": largest(branch.multiplier_error),
            "flagged_points": int(np.sum(branch.flagged)),
            "above_trivial_tol": count(branch.trivial_error, branch.accuracy_tol),
            "above_mesh_tol": count(branch.mesh_error, branch.mesh_tol),
            "above_stiff_tol": count(branch.stiff_modulus, branch.stiff_tol),
            "above_multiplier_tol": count(branch.multiplier_error, branch.multiplier_tol),
            "in_contact": count(branch.monitor, info.get("minimum"), above=False)}


def accuracy_line(acc: dict[str, Any]) -> str:
    line = "  accuracy          max trivial error " + ("-" if acc["max_trivial_error"] is None
                                                       else f"{acc['max_trivial_error']:.2e}")
    if acc["max_mesh_error"] is not None:
        line += f", max mesh error {acc['max_mesh_error']:.2e}"
    if acc.get("max_stiff_modulus") is not None and acc["max_stiff_modulus"] >= 1e-3:
        # the multipliers the mesh gives the fast modes (exactly ~0): a band of artefacts up to this modulus
        line += f", fast modes' spurious multipliers up to |mu| {acc['max_stiff_modulus']:.3f}"
    if acc.get("max_multiplier_error") is not None:
        line += f", max multiplier error {acc['max_multiplier_error']:.1e}"
    if acc.get("collocation"):
        line += f" ({acc['collocation']} points)"
    # each cause with its own remedy
    why = [(acc["above_trivial_tol"], f"above trivial_tol = {acc['trivial_tol']:g}", "refine --N"),
           (acc["above_mesh_tol"], f"above mesh_tol = {acc['mesh_tol']:g}", "refine --N"),
           # refining reduces h*lam and so the band, and it also resolves slow modes; radau points remove the band
           # at any N but damp a mode that oscillates within an interval, so they come second
           (acc.get("above_stiff_tol", 0), f"with spurious multipliers above stiff_tol = {acc.get('stiff_tol')}",
            "refine --N" if acc.get("collocation") == "radau" else "refine --N or --collocation radau"),
           (acc.get("above_multiplier_tol", 0),
            f"with multipliers not resolved to multiplier_tol = {acc.get('multiplier_tol')}", "refine --N"),
           (acc["in_contact"], "in film contact", "the model does not apply there")]
    why = [(n, text, fix) for n, text, fix in why if n]
    if why:
        count = acc["flagged_points"]
        causes = ", ".join(f"{n} {text}: {fix}" for n, text, fix in why)
        line += (f"; {count} point{'s' if count != 1 else ''} flagged ({causes}); their multipliers or stability "
                 "labels are unreliable")
    return line
