"""The thesis' campaign keys (thesis Tables 4.2–4.4, 5.1/5.2): what its format has that the engine's has not.

In ``[ballbar]`` (read by the engine's reader, :mod:`mtmcal_bayes.io.ballbar_section`, like every machine's): its
tool set-ups by their lever arms (``R_B_mm``, ``Z_T_mm``, ``X_T_mm``), its W-ball mounts by ``Z_C_mm`` and
``R_C_mm``, its ``cr_geometry`` (:class:`BallbarKeys`); its 12 patterns, their components and Table 2.2's rule on
mounts are the plug-in's ``patterns``, ``pattern_components`` and ``mount_conflict``.  The touch probe's
``[probe.b_axis]`` (styli at indexed B angles) and ``[probe.c_axis]`` (a sphere at indexed C angles), their centres or
DPRNT files, are read here into the engine's probe runs (:mod:`.probe_runs`), beside whatever ``[[probe.runs]]`` the
campaign has too.  The engine asks the machine for these (its ``ballbar_keys``, ``probe_keys`` and
``read_probe_keys``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...campaign import Ballbar, Mount, Probe, Setup
from ...io.ballbar_section import equal_setups
from ...io.probe_readings import probe_readings
from ...io.toml_reader import TomlReader
from ...patterns import CR_GEOMETRIES
from .probe_runs import C_RUN, BAxisKeys, CAxisKeys, Readings, StylusKeys, add_thesis_runs, b_mount_height
from .translation import complete


class BallbarKeys:
    """The thesis' keys of ``[ballbar]`` in the engine's reader (thesis Tables 4.2–4.4): its tool set-ups by their
    lever arms ``R_B_mm``, ``Z_T_mm``, ``X_T_mm``, its W-ball mounts by ``Z_C_mm`` and ``R_C_mm`` (the W ball of a
    run where Tables 2.2/2.3 place it, :meth:`~mtmcal_bayes.campaign.Mount.centre`), its ``cr_geometry``; its runs'
    arcs and bar sides are its patterns' (:func:`.translation.complete`), not a run's own.  The ``write*`` members
    write the same keys back in the engine's writer (:mod:`mtmcal_bayes.io.ballbar_writer`)."""

    keys = ("cr_geometry",)
    setup_keys = ("R_B_mm", "Z_T_mm", "X_T_mm")
    mount_keys = ("Z_C_mm", "R_C_mm")
    run_geometry = False

    @staticmethod
    def read(r: TomlReader, t: dict, path: str) -> dict:
        cr_geometry = r.string(t, "cr_geometry", path, default=CR_GEOMETRIES[0])
        if cr_geometry not in CR_GEOMETRIES:
            r.fail(f"{path}.cr_geometry", f"unknown CR geometry {cr_geometry!r} (expected {' or '.join(CR_GEOMETRIES)})")
        return {"cr_geometry": cr_geometry}

    @staticmethod
    def setup(r: TomlReader, sid: str, path: str, s: dict) -> Setup:
        return Setup(sid, r.number(s, "R_B_mm", path, positive=True), r.number(s, "Z_T_mm", path),
                     r.number(s, "X_T_mm", path))

    @staticmethod
    def check_setups(r: TomlReader, setups: dict[str, Setup], path: str) -> None:
        """Z_T + R_B is constant between tool lengths (the B centre's height above the tool ball)."""
        if pair := equal_setups(setups, "Z_T"):
            a, b = pair
            r.fail(f"{path}.setups.{b.id}.Z_T_mm", f"equal to {path}.setups.{a.id}.Z_T_mm ({a.Z_T:g} mm) although R_B "
                   "differs: Z_T + R_B must stay constant between tool lengths")

    @staticmethod
    def mount(r: TomlReader, mid: str, path: str, m: dict) -> Mount:
        return Mount(mid, r.number(m, "Z_C_mm", path, nonnegative=True), r.number(m, "R_C_mm", path, nonnegative=True))

    @staticmethod
    def complete(ballbar: Ballbar, desc) -> None:
        complete(ballbar, desc)

    @staticmethod
    def write(ballbar: Ballbar) -> dict:
        """``cr_geometry`` where it is not the default (``"RC-LB"``, Table 2.3)."""
        return {"cr_geometry": ballbar.cr_geometry} if ballbar.cr_geometry != CR_GEOMETRIES[0] else {}

    @staticmethod
    def write_setup(s: Setup) -> dict:
        return {"R_B_mm": s.R_B, "Z_T_mm": s.Z_T, "X_T_mm": s.X_T}

    @staticmethod
    def write_mount(m: Mount) -> dict:
        return {"Z_C_mm": m.Z_C, "R_C_mm": m.R_C}


def read_probe_keys(r: TomlReader, t: dict, probe: Probe, *, ballbar: Ballbar | None = None,
                    base_dir: Path | None = None) -> None:
    """``[probe.b_axis]`` and ``[probe.c_axis]`` of ``[probe]`` ``t`` (thesis Tables 5.1–5.2), read into ``probe``'s
    runs and styli (:func:`.probe_runs.add_thesis_runs`); ``ballbar`` the campaign's: its B patterns' mount's height
    is the B-axis sphere's where the sections give none."""
    P = "probe"
    readings: dict[str, Readings] = {}
    bax = cax = None
    b = r.table(t, "b_axis", P, required=False)
    if b is not None:
        path = f"{P}.b_axis"
        r.check_keys(b, {"X_T_mm", "Z_C_mm", "angles_deg", "styli"}, path)
        angles = r.array(b, "angles_deg", path, (None,))
        if len(np.unique(angles)) < 2:
            r.fail(f"{path}.angles_deg", f"needs at least two different B angles (only differences between indexed "
                   f"positions inform the deviations), got [{', '.join(f'{a:g}' for a in angles)}]")
        bax = BAxisKeys(r.number(b, "X_T_mm", path), angles, Z_C=r.number(b, "Z_C_mm", path, required=False))
        for sid, sp, st in r.subtables(b, "styli", path, what="stylus",
                                       allowed={"R_B_mm", "nominal_mm", "centres_mm", "dprnt", "ball_radius_mm"}):
            centres, cov, files = probe_readings(r, st, sp, len(angles), base_dir=base_dir, position="angle")
            bax.styli[sid] = StylusKeys(sid, r.number(st, "R_B_mm", sp, positive=True),
                                        r.array(st, "nominal_mm", sp, (len(angles), 3), required=False),
                                        ball_radius=r.number(st, "ball_radius_mm", sp, required=False,
                                                             nonnegative=True, default=0.0))
            readings[sid] = Readings(centres, cov, files)
        for i, (sa, a) in enumerate(bax.styli.items()):
            for sb, bb in list(bax.styli.items())[i + 1:]:
                if a.R_B == bb.R_B:
                    r.fail(f"{path}.styli.{sb}.R_B_mm", f"equal to styli.{sa}.R_B_mm ({a.R_B:g} mm): "
                           "a second stylus length equal to the first carries no information")
    c = r.table(t, "c_axis", P, required=False)
    if c is not None:
        path = f"{P}.c_axis"
        r.check_keys(c, {"R_C_mm", "Z_C_mm", "axis_xy_mm", "angles_deg", "centres_mm", "dprnt", "stylus", "R_B_mm",
                         "ball_radius_mm", "datum"}, path)
        angles = r.array(c, "angles_deg", path, (None,))
        if len(np.unique(np.mod(angles, 360.0))) < 3:
            r.fail(f"{path}.angles_deg", f"needs at least three different C angles (a circle through the sphere "
                   f"centres), got [{', '.join(f'{a:g}' for a in angles)}]")
        centres, cov, files = probe_readings(r, c, path, len(angles), base_dir=base_dir, position="angle")
        stylus = r.string(c, "stylus", path, default="") or None
        R_B = r.number(c, "R_B_mm", path, required=False, positive=True)
        if stylus is not None:
            if bax is None or stylus not in bax.styli:
                have = ", ".join(bax.styli) if bax else "none"
                r.fail(f"{path}.stylus", f"no stylus {stylus!r} in [probe.b_axis.styli] (have: {have})")
            if R_B is not None:
                r.fail(f"{path}.R_B_mm", "give either stylus (a stylus of [probe.b_axis.styli]) or R_B_mm, not both")
        datum = r.string(c, "datum", path, default="machine")
        if datum not in ("machine", "first"):
            r.fail(f"{path}.datum", f"unknown datum {datum!r} (expected \"machine\": the readings are machine "
                   "coordinates with the C axis at axis_xy_mm, or \"first\": the reading frame was zeroed on the sphere)")
        cax = CAxisKeys(
            r.number(c, "R_C_mm", path, positive=True), r.number(c, "Z_C_mm", path, nonnegative=True),
            r.array(c, "axis_xy_mm", path, (2,)), angles, stylus=stylus, R_B=R_B,
            ball_radius=r.number(c, "ball_radius_mm", path, required=False, nonnegative=True, default=0.0),
            datum=datum)
        readings[C_RUN] = Readings(centres, cov, files)
    add_thesis_runs(probe, c_axis=cax, b_axis=bax, readings=readings,
                    mount_Z=b_mount_height(ballbar) if ballbar is not None else np.nan)
