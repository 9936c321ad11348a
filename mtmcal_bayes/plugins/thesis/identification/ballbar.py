"""Ball-bar identification as the thesis does it: Eqs 4.10–4.18 on the means of the repeats.

:func:`identify_ballbar` recomputes the eight quantities of Table 4.5;
:func:`thesis_checks` states what the deterministic method leaves out (SPEC §9
items 1–2): the redundant ``ex_CR'`` and the dx_BT = 0 assumption of Eq 4.2.
"""

from __future__ import annotations

import numpy as np

from .... import units
from ....campaign import Campaign
from ....parameters import IDENTIFIABLE
from .result import Identified


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

    return {k: out[k] for k in IDENTIFIABLE}


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
