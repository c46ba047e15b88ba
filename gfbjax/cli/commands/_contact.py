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
    """Why points of a cycle branch are flagged, count by count (trivial multiplier, mesh error, film contact)."""
    def count(values: Any, tol: Any, above: bool = True) -> int:
        if values is None or tol is None:
            return 0
        v = np.asarray(values, float)
        return int(np.sum(v > tol) if above else np.sum(v <= tol))

    info = branch.monitor_info or {}
    return {"trivial_tol": branch.accuracy_tol, "mesh_tol": branch.mesh_tol,
            "max_trivial_error": float(np.nanmax(branch.trivial_error)) if len(branch) else None,
            "max_mesh_error": (float(np.nanmax(branch.mesh_error)) if branch.mesh_error is not None and len(branch)
                               else None),
            "flagged_points": int(np.sum(branch.flagged)),
            "above_trivial_tol": count(branch.trivial_error, branch.accuracy_tol),
            "above_mesh_tol": count(branch.mesh_error, branch.mesh_tol),
            "in_contact": count(branch.monitor, info.get("minimum"), above=False)}


def accuracy_line(acc: dict[str, Any]) -> str:
    line = f"  accuracy          max trivial error {acc['max_trivial_error']:.2e}"
    if acc["max_mesh_error"] is not None:
        line += f", max mesh error {acc['max_mesh_error']:.2e}"
    why = [f"{acc['above_trivial_tol']} above trivial_tol = {acc['trivial_tol']:g}" if acc["above_trivial_tol"] else "",
           f"{acc['above_mesh_tol']} above mesh_tol = {acc['mesh_tol']:g}" if acc["above_mesh_tol"] else "",
           f"{acc['in_contact']} in film contact" if acc["in_contact"] else ""]
    why = [w for w in why if w]
    if why:
        line += (f"; {acc['flagged_points']} points flagged ({', '.join(why)}): their stability labels are "
                 "unreliable (refine --N, or the model does not apply)")
    return line
