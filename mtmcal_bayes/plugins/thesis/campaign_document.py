"""The thesis' own parts of a campaign written (the inverse of :mod:`.campaign_keys`): its
touch probe's ``[probe.b_axis]`` and ``[probe.c_axis]`` (Tables 5.1/5.2).  The engine writes the rest of the document
alike for every machine (:mod:`mtmcal_bayes.io.campaign_writer`), its keys of ``[ballbar]`` with the plug-in's
(:class:`.campaign_keys.BallbarKeys`)."""

from __future__ import annotations

from collections.abc import Callable

from ...campaign import Probe
from .probe_runs import B_RUN, C_RUN, record, run_of


def probe_document(p: Probe, path_of: Callable[[str], str]) -> dict:
    """``[probe.b_axis]`` (styli at indexed B angles) and ``[probe.c_axis]`` (a sphere at indexed C angles), each with
    its centres or its DPRNT files (``path_of``: a file's name as seen from the saved campaign): the plug-in's record
    of its keys, each run's readings.  A section is written for the runs the probe has (its readings are required
    keys): a probe whose runs were taken away (a new machine's, its styli kept to design with) writes neither, and
    its styli are the engine's ``[probe.styli]``."""
    d: dict = {}
    own = record(p)

    def readings(run) -> dict:  # DPRNT files relative to the saved file, else the centres
        return {"dprnt": [path_of(f) for f in run.dprnt]} if run.dprnt else {"centres_mm": run.centres}

    measured = {(r.id, r.stylus) for r in p.runs}
    kept = [s for s in own.b_axis.styli.values() if (B_RUN, s.id) in measured] if own.b_axis is not None else []
    if kept:
        b = own.b_axis
        styli = {}
        for s in kept:
            sd = {"R_B_mm": s.R_B}
            if s.ball_radius:
                sd["ball_radius_mm"] = s.ball_radius
            if s.nominal is not None:
                sd["nominal_mm"] = s.nominal
            styli[s.id] = {**sd, **readings(run_of(p, B_RUN, s.id))}
        d["b_axis"] = {"X_T_mm": b.X_T, **({"Z_C_mm": b.Z_C} if b.Z_C is not None else {}),
                       "angles_deg": b.angles_deg, "styli": styli}
    if own.c_axis is not None and any(rid == C_RUN for rid, _ in measured):
        x = own.c_axis
        cd = {"R_C_mm": x.R_C, "Z_C_mm": x.Z_C, "axis_xy_mm": x.axis_xy, "angles_deg": x.angles_deg}
        if x.stylus and x.stylus not in {s.id for s in kept}:  # its stylus' B-axis run taken away: its length
            cd["R_B_mm"] = p.styli[x.stylus]
            if p.ball_radii.get(x.stylus):
                cd["ball_radius_mm"] = p.ball_radii[x.stylus]
        elif x.stylus:
            cd["stylus"] = x.stylus
        if x.R_B is not None:
            cd["R_B_mm"] = x.R_B
        if x.ball_radius:
            cd["ball_radius_mm"] = x.ball_radius
        if x.datum != "machine":
            cd["datum"] = x.datum
        d["c_axis"] = {**cd, **readings(run_of(p, C_RUN))}
    return d
