"""Touch-probe identification as the thesis does it: Eqs 5.1–5.19 on the averaged sphere centres."""

from __future__ import annotations

import numpy as np

from ....campaign import Campaign
from ..probe_runs import B_RUN, C_RUN, record, run_of
from .result import Identified


def _rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _rot_y(b):
    c, s = np.cos(b), np.sin(b)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def missing_probe(campaign: Campaign) -> list[str]:
    """Sentences naming the probe sections a campaign with a ``[probe]`` lacks, and the values Eqs 5.1–5.19 then do
    not give (the report's list of what a campaign lacks)."""
    if campaign.probe is None:
        return []
    own, out = record(campaign.probe), []
    if own.c_axis is None:
        out.append("No C-axis touch-probe data: alpha_CZ, beta_CZ, dx_CZ and dy_CZ have no probe value.")
    if own.b_axis is None or not own.b_axis.styli:
        out.append("No B-axis touch-probe data: alpha_XB, beta_XB, gamma_XB, dx_BT and dz_BT have no probe value.")
    return out


def identify_probe(campaign: Campaign) -> tuple[dict[str, Identified], list[str]]:
    """Thesis Eqs 5.1–5.19 on the averaged sphere centres; returns values and assumptions.

    C axis: the normal of the plane through the four centres (Eq 5.1) gives
    beta_CZ = X_N/Z_N and alpha_CZ = Y_N/Z_N (Eqs 5.5/5.6, signs as printed);
    dx_CZ, dy_CZ from Eq 5.7 with the trajectory centre taken as the mean of the
    four centres relative to the nominal ``axis_xy_mm``.  B axis: errors
    Δ = measured − nominal at B = 0°/90°, Eqs 5.12, 5.13 (two styli), 5.15,
    5.17, 5.19 (shorter stylus).
    """
    out: dict[str, Identified] = {}
    assumptions: list[str] = []
    probe = campaign.probe
    if probe is None:
        return out, ["the campaign has no touch-probe data"]

    own = record(probe)
    c = own.c_axis
    if c is not None:
        ang = np.round(np.mod(c.angles_deg, 360.0), 6)
        idx = [int(np.flatnonzero(ang == a)[0]) if np.any(ang == a) else -1 for a in (0.0, 90.0, 180.0, 270.0)]
        if -1 in idx:
            assumptions.append("C-axis probe angles are not 0/90/180/270°: Eqs 5.1–5.7 not applied")
        else:
            P = run_of(probe, C_RUN).centres.mean(axis=0)[idx]  # (4, 3) averaged centres P1..P4, mm
            N = np.cross(P[2] - P[0], P[3] - P[1])  # Eq 5.1
            beta, alpha = N[0] / N[2], N[1] / N[2]  # Eqs 5.5, 5.6
            out["beta_CZ"] = Identified("beta_CZ", beta, "5.5")
            out["alpha_CZ"] = Identified("alpha_CZ", alpha, "5.6",
                                         note="sign as printed; opposite to the Chapter 2 convention")
            centre = P.mean(axis=0)
            d = _rot_x(-alpha) @ _rot_y(-beta) @ np.array([centre[0] - c.axis_xy[0], centre[1] - c.axis_xy[1], c.Z_C])
            how = "depends on how ΔX_center, ΔY_center are formed (see assumptions)"
            out["dx_CZ"] = Identified("dx_CZ", d[0], "5.7", note=how)
            out["dy_CZ"] = Identified("dy_CZ", d[1], "5.7", note=how)
            assumptions.append(
                "Eq 5.7: trajectory centre = mean of the four averaged sphere centres, its error taken "
                f"relative to the nominal C-axis centreline axis_xy_mm = ({c.axis_xy[0]:g}, {c.axis_xy[1]:g}) mm "
                "(the thesis does not say how it formed ΔX_center, ΔY_center)")

    b = own.b_axis
    if b is not None and b.styli and (list(b.angles_deg) != [0.0, 90.0]
                                      or any(s.nominal is None for s in b.styli.values())):
        assumptions.append("B-axis probe: Eqs 5.8–5.19 need B = 0° and 90° and every stylus's nominal_mm: not applied")
    elif b is not None and b.styli:
        styli = sorted(b.styli.values(), key=lambda s: s.R_B)
        short = styli[0]
        D = {s.id: run_of(probe, B_RUN, s.id).centres.mean(axis=0) - s.nominal for s in styli}  # (2, 3): rows B=0°, 90°
        d = D[short.id]
        dX1, dY1, dZ1 = d[0]
        dX2, dY2, dZ2 = d[1]
        assumed = "depends on the assumed nominal positions"
        if len(styli) >= 2:
            long = styli[1]
            dl = D[long.id]
            k, kp = dX1 - dZ2, dl[0, 0] - dl[1, 2]  # Eqs 5.10, 5.11
            same_nominal = bool(np.array_equal(short.nominal, long.nominal))
            out["beta_XB"] = Identified(
                "beta_XB", (kp - k) / (2 * (long.R_B - short.R_B)), "5.12",
                note=("independent of the assumed nominal positions (both styli share them)" if same_nominal
                      else "depends on the assumed nominal positions"))
            out["dx_BT"] = Identified("dx_BT", (long.R_B * k - short.R_B * kp) / (2 * (long.R_B - short.R_B)), "5.13",
                                      note=assumed)
        out["dz_BT"] = Identified("dz_BT", (dZ1 + dX2) / 2, "5.15", note=assumed)
        out["gamma_XB"] = Identified("gamma_XB", (dX2 - dX1) / b.X_T, "5.17", note=assumed)
        out["alpha_XB"] = Identified("alpha_XB", (dY1 - dY2) / short.R_B, "5.19", note=assumed)
        for s in styli:
            nom = "; ".join(f"B={a:g}°: ({', '.join(f'{v:g}' for v in row)})" for a, row in zip(b.angles_deg, s.nominal))
            assumptions.append(f"B-axis errors are measured minus the nominal positions of the campaign, stylus "
                               f"{s.id} (R_B = {s.R_B:g} mm): {nom} mm; the thesis does not give them")
        assumptions.append(f"Eqs 5.15, 5.17, 5.19 use the shorter stylus ({short.id})")

    reported = campaign.reported.get("probe", {})
    for name, ident in out.items():
        ident.reported = reported.get(name)
    for name, rv in reported.items():
        if name not in out:
            out[name] = Identified(name, None, "", "not computable from the campaign's probe data", rv)
    return out, assumptions
