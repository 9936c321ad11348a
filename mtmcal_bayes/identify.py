"""Deterministic identification as in the thesis, recomputed and compared with what it printed.

* :func:`identify_ballbar` — Eqs 4.10–4.18 from the mean of the repeats of BX,
  BY, CR, CA at the first tool setup and CR at a second tool length.
* :func:`identify_probe` — Eqs 5.1–5.19 from the averaged touch-probe sphere
  centres (Table 5.2) and the nominal positions given in the campaign.
* :func:`identify` — both, each value beside the ``[reported]`` one with a flag
  when they differ by more than the rounding of the printed value.

Known discrepancies of the thesis are listed by :func:`thesis_checks` and in
``docs/thesis-notes.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import units
from .campaign import Campaign, ReportedValue
from .parameters import QUANTITIES


@dataclass
class Identified:
    """One recomputed quantity.

    ``value`` is in internal units (mm, rad), ``None`` when the data do not
    allow it (``missing`` says why).  ``reported`` is the published value, if any.
    """

    name: str
    value: float | None
    equation: str
    missing: str | None = None
    reported: ReportedValue | None = None
    note: str | None = None

    @property
    def unit(self) -> str:
        return QUANTITIES[self.name].unit

    @property
    def display(self) -> float | None:
        """Value in the display unit (″ or µm)."""
        return None if self.value is None else units.from_internal(self.value, self.unit)

    @property
    def reported_display(self) -> float | None:
        return None if self.reported is None else units.from_internal(self.reported.value, self.reported.unit)

    @property
    def difference(self) -> float | None:
        """Recomputed minus reported, display unit."""
        if self.value is None or self.reported is None:
            return None
        return self.display - self.reported_display

    @property
    def reproduced(self) -> bool | None:
        """Whether the recomputed value rounds to the printed one (``None`` if nothing to compare)."""
        if self.difference is None:
            return None
        half_step = 0.5 * 10.0 ** (-self.reported.decimals)
        return abs(self.difference) <= half_step * (1 + 1e-9)

    def to_json(self) -> dict:
        d = {"value": self.display, "unit": self.unit, "equation": self.equation}
        if self.missing:
            d["missing"] = self.missing
        if self.reported is not None:
            d.update(reported=self.reported_display, difference=self.difference, reproduced=self.reproduced)
        if self.note:
            d["note"] = self.note
        return d


@dataclass
class IdentificationResult:
    """Recomputed ball-bar and probe values, thesis consistency checks and stated assumptions."""

    ballbar: dict[str, Identified]
    probe: dict[str, Identified]
    checks: list[str] = field(default_factory=list)
    assumptions: list[str] = field(default_factory=list)
    source: str = ""

    def to_json(self) -> dict:
        return {
            "campaign": self.source,
            "ballbar": {k: v.to_json() for k, v in self.ballbar.items()},
            "probe": {k: v.to_json() for k, v in self.probe.items()},
            "checks": self.checks,
            "assumptions": self.assumptions,
        }


# --------------------------------------------------------------------------- ball bar
def _pooled(campaign: Campaign, pattern: str, setup: str | None = None, mount: str | None = None):
    """Runs of ``pattern`` grouped by (setup, mount) in file order, repeats pooled per component."""
    groups: dict[tuple[str, str], dict[str, list]] = {}
    for run in campaign.runs_of(pattern):
        if (setup and run.setup != setup) or (mount and run.mount != mount):
            continue
        g = groups.setdefault((run.setup, run.mount), {})
        for comp, rep in run.repeats.items():
            g.setdefault(comp, []).extend(np.asarray(rep).tolist())
    return [(s, m, {c: float(np.mean(v)) for c, v in comps.items()}) for (s, m), comps in groups.items()]


def identify_ballbar(campaign: Campaign) -> dict[str, Identified]:
    """Thesis Eqs 4.10–4.18 on the means of the repeats.

    The first BX run fixes the primary tool setup; CR at that setup gives
    ``ex_CR``/``ey_CR`` and CR at another setup with a different Z_T gives
    ``ey'_CR``.  Eqs 4.17/4.18 are solved with each CR run's own lever arms
    (identical to the printed equations when Z_C and X_T agree, as in the thesis).
    Quantities whose runs are missing come back with ``value=None`` and a reason.
    """
    bb = campaign.ballbar
    out: dict[str, Identified] = {}

    def first(pattern, comp, setup=None):
        for s, m, means in _pooled(campaign, pattern, setup):
            if comp in means:
                return bb.setups[s], bb.mounts[m], means[comp]
        return None

    def put(name, eq, value, missing=None):
        value = None if value is None else float(value) + 0.0  # + 0.0: no "-0.00" from all-zero data
        out[name] = Identified(name, value, eq, missing)

    ca_y, ca_x = first("CA", "ey"), first("CA", "ex")
    for name, eq, obs, sign in (("alpha_CZ", "4.10", ca_y, -1.0), ("beta_CZ", "4.11", ca_x, 1.0)):
        if obs is None:
            put(name, eq, None, f"needs {'ey' if sign < 0 else 'ex'} of a CA run")
        elif obs[1].R_C == 0:
            put(name, eq, None, f"CA run at mount {obs[1].id} has R_C = 0, which carries no information")
        else:
            put(name, eq, sign * obs[2] / obs[1].R_C)

    by_z, by_x, bx_z = first("BY", "ez"), first("BY", "ex"), first("BX", "ez")
    put("alpha_XB", "4.12", by_z[2] / by_z[0].R_B if by_z else None, None if by_z else "needs ez of a BY run")
    put("beta_XB", "4.13", bx_z[2] / bx_z[0].R_B if bx_z else None, None if bx_z else "needs ez of a BX run")
    put("gamma_XB", "4.14", -by_x[2] / by_x[0].R_B if by_x else None, None if by_x else "needs ex of a BY run")

    primary = bx_z[0].id if bx_z else None
    cr_x = first("CR", "ex", primary) or first("CR", "ex")
    beta_cz, beta_xb = out["beta_CZ"].value, out["beta_XB"].value
    if cr_x is None or beta_cz is None or beta_xb is None:
        put("dx_CZ_minus_dx_BT", "4.15", None, "needs ex of a CR run with beta_XB and beta_CZ")
    else:
        setup, mount, ex = cr_x
        put("dx_CZ_minus_dx_BT", "4.15", -ex + mount.Z_C * beta_cz - setup.Z_T * beta_xb)

    cr_y = [(bb.setups[s], bb.mounts[m], means["ey"]) for s, m, means in _pooled(campaign, "CR") if "ey" in means]
    if primary is not None:
        cr_y.sort(key=lambda t: t[0].id != primary)  # the primary setup first, stable otherwise
    second = next((t for t in cr_y[1:] if t[0].Z_T != cr_y[0][0].Z_T), None) if cr_y else None
    alpha_cz, alpha_xb, gamma_xb = (out[k].value for k in ("alpha_CZ", "alpha_XB", "gamma_XB"))
    if second is None or None in (alpha_cz, alpha_xb, gamma_xb):
        why = ("needs ey of CR at a second tool length (R'_B)" if second is None
               else "needs alpha_CZ, alpha_XB and gamma_XB")
        put("alpha_BT", "4.17", None, why)
        put("dy_CZ", "4.18", None, why)
    else:
        # y_i = ey_i + Z_C·alpha_CZ + X_T·gamma_XB = −dy_CZ + Z_T,i·(alpha_XB + alpha_BT)
        (s1, m1, ey1), (s2, m2, ey2) = cr_y[0], second
        y1 = ey1 + m1.Z_C * alpha_cz + s1.X_T * gamma_xb
        y2 = ey2 + m2.Z_C * alpha_cz + s2.X_T * gamma_xb
        slope = (y2 - y1) / (s2.Z_T - s1.Z_T)
        put("alpha_BT", "4.17", slope - alpha_xb)
        put("dy_CZ", "4.18", s1.Z_T * slope - y1)

    order = ("alpha_CZ", "beta_CZ", "alpha_XB", "beta_XB", "gamma_XB", "alpha_BT", "dx_CZ_minus_dx_BT", "dy_CZ")
    return {k: out[k] for k in order}


# --------------------------------------------------------------------------- touch probe
def _rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _rot_y(b):
    c, s = np.cos(b), np.sin(b)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


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

    c = probe.c_axis
    if c is not None:
        ang = np.round(np.mod(c.angles_deg, 360.0), 6)
        idx = [int(np.flatnonzero(ang == a)[0]) if np.any(ang == a) else -1 for a in (0.0, 90.0, 180.0, 270.0)]
        if -1 in idx:
            assumptions.append("C-axis probe angles are not 0/90/180/270°: Eqs 5.1–5.7 not applied")
        else:
            P = c.centres.mean(axis=0)[idx]  # (4, 3) averaged centres P1..P4, mm
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

    b = probe.b_axis
    if b is not None and b.styli:
        styli = sorted(b.styli.values(), key=lambda s: s.R_B)
        short = styli[0]
        D = {s.id: s.centres.mean(axis=0) - s.nominal for s in styli}  # (2, 3): rows B=0°, 90°
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


# --------------------------------------------------------------------------- both
def thesis_checks(campaign: Campaign, ballbar: dict[str, Identified]) -> list[str]:
    """Consistency checks the deterministic method leaves out (SPEC §9 items 1–2)."""
    checks = []
    bb = campaign.ballbar
    crs = [(bb.setups[s], bb.mounts[m], means["ex"]) for s, m, means in _pooled(campaign, "CR") if "ex" in means]
    beta = ballbar.get("beta_XB")
    if len(crs) >= 2 and beta is not None and beta.value is not None:
        (s1, m1, e1), (s2, m2, e2) = crs[0], crs[1]
        if s1.Z_T != s2.Z_T and m1.Z_C == m2.Z_C:
            implied = -(e2 - e1) / (s2.Z_T - s1.Z_T)
            checks.append(
                f"redundant data: ex_CR({s2.id}) − ex_CR({s1.id}) = {units.from_internal(e2 - e1, 'um'):.2f} µm "
                f"implies beta_XB = {units.from_internal(implied, 'arcsec'):.1f}″ through Eq 4.5, against "
                f"{units.from_internal(beta.value, 'arcsec'):.2f}″ from BX (Eq 4.13); the deterministic method "
                "ignores ex_CR'")
    bx = [s for s, _, means in _pooled(campaign, "BX") if "ez" in means]
    if bx:
        R_B = bb.setups[bx[0]].R_B
        per10 = units.from_internal(units.to_internal(10.0, "um") / R_B, "arcsec")
        checks.append(f"Eq 4.13 assumes dx_BT = 0 (Eq 4.2), Table 2.6 does not: beta_XB is biased by dx_BT/R_B "
                      f"= {per10:.1f}″ per 10 µm of dx_BT at R_B = {R_B:g} mm")
    return checks


def identify(campaign: Campaign) -> IdentificationResult:
    """Ball-bar and touch-probe identification with published values and flags."""
    ballbar = identify_ballbar(campaign)
    for name, ident in ballbar.items():
        ident.reported = campaign.reported.get("ballbar", {}).get(name)
    probe, assumptions = identify_probe(campaign)
    assumptions = ["ball bar: means of the repeats; Eq 4.13 assumes dx_BT = 0 as the thesis does (Eq 4.2)"] + assumptions
    return IdentificationResult(ballbar, probe, thesis_checks(campaign, ballbar), assumptions, campaign.source)
