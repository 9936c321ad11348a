"""``mtmcal-bayes compensate``: rewrite a program's X, Y, Z so the tool reaches the programmed points.

The deviations are the posterior mean (default) or the deterministic ball-bar
values (``values="ballbar"``, thesis Table 4.5 for the thesis campaign).  The
uncertainty of the result comes from posterior draws: for each draw the tool
point of the compensated program is computed again; per block the residual
error's mean and 95 % quantile of its length are reported.  What X/Y/Z cannot
correct — the tilt of the tool axis — is reported per deviation by name, with
the position error it leaves 100 mm along the tool from the compensated point.
"""

from __future__ import annotations

import numpy as np

from .... import units
from ....errors import ParameterError
from ....inference.analytic import prior_sensitivity
from ....inference.identifiability import DETERMINED, IN_COMBINATION, campaign_identifiability
from ....inference.log_posterior import LogPosterior
from ....compensation.reading_choice import deviation_marks
from ....compensation.options import METHODS, OFF_TOOL_MM, POINTS, SIGMA_MODEL_UM, VALUES
from ....compensation.result import CompensationResult
from ....io.gcode import Program, rewrite
from ....models import KINEMATIC_MODELS, check_model
from ..htm import Geometry, nc_origin
from ....parameters import DEVIATIONS
from .kinematics import compensate_exact, tool_axis_tilt, tool_point
from .printed_method import compensate_thesis
from .values import ballbar_values, posterior_draws


def geometry_for(campaign, setup_id: str | None, mount_id: str | None) -> Geometry:
    """Lever arms of a campaign setup and mount (default: the primary setup, the first mount)."""
    bb = campaign.ballbar
    if setup_id is not None and setup_id not in bb.setups:
        raise ParameterError("setup", f"no setup {setup_id!r} in the campaign (have {', '.join(bb.setups)})")
    if mount_id is not None and mount_id not in bb.mounts:
        raise ParameterError("mount", f"no mount {mount_id!r} in the campaign (have {', '.join(bb.mounts)})")
    s = bb.setups[setup_id] if setup_id else campaign.primary_setup()
    m = bb.mounts[mount_id] if mount_id else next(iter(bb.mounts.values()))
    return Geometry(s.R_B, s.Z_T, s.X_T, m.Z_C, m.R_C)


def not_compensable(theta: np.ndarray, geo: Geometry, xyz_model: np.ndarray, bc: np.ndarray, *, model: str) -> list[dict]:
    """Tool-axis tilt left by each deviation (largest over the blocks) and its effect off the tool length."""
    out = []
    for i, name in enumerate(DEVIATIONS):
        if theta[i] == 0.0:
            continue
        single = np.zeros((1, len(DEVIATIONS)))
        single[0, i] = theta[i]
        tilt = float(tool_axis_tilt(single, geo, xyz_model, bc, model=model).max())
        if units.from_internal(tilt, "arcsec") > 0.01:
            out.append({"name": name, "tool_tilt_arcsec": units.from_internal(tilt, "arcsec"),
                        f"error_at_{OFF_TOOL_MM:g}mm_off_the_tool_point_um": units.from_internal(tilt * OFF_TOOL_MM, "um")})
    total = float(tool_axis_tilt(theta[None], geo, xyz_model, bc, model=model).max())
    out.append({"name": "all together", "tool_tilt_arcsec": units.from_internal(total, "arcsec"),
                f"error_at_{OFF_TOOL_MM:g}mm_off_the_tool_point_um": units.from_internal(total * OFF_TOOL_MM, "um")})
    return sorted(out, key=lambda r: -r["tool_tilt_arcsec"])


def compensate(campaign, program: Program, *, method: str = "exact", model: str = "htm-thesis",
               values: str = "posterior", posterior=None, point: str = "tcp", setup: str | None = None,
               mount: str | None = None, seed: int = 0) -> CompensationResult:
    """Compensate ``program`` for the deviations of ``campaign`` (see the module docstring).

    ``values``: the posterior mean (``"posterior"``) or the thesis' ball-bar values (``"ballbar"``);
    ``posterior``: posterior draws, as a NetCDF file, a result of :func:`mtmcal_bayes.sample` or an
    InferenceData (default: the closed form); ``point``: ``"tcp"``
    or the spindle ``"nose"``; ``setup``/``mount``: campaign ids of the tool and the C-axis pivot.
    """
    for name, value, allowed in (("method", method, METHODS), ("values", values, VALUES), ("point", point, POINTS)):
        if value not in allowed:
            raise ParameterError(name, f"{value!r} (expected {' or '.join(allowed)})")
    if model == "linear":
        raise ParameterError("model", "linear: compensation needs a kinematic chain; use htm-thesis (default) "
                             "or htm-literal")
    check_model(model, KINEMATIC_MODELS)
    geo = geometry_for(campaign, setup, mount)
    origin = nc_origin(geo)
    pos = program.positions()
    xyz, bc = pos[:, :3], pos[:, 3:]
    xyz_model = xyz + origin
    draws, source = posterior_draws(campaign, posterior, seed=seed)
    theta = ballbar_values(campaign) if values == "ballbar" else draws.mean(axis=0)
    if method == "exact":
        xyz_c_model, miss = compensate_exact(theta[None], geo, xyz_model, bc, model=model, point=point)
        xyz_c = xyz_c_model - origin
    else:
        xyz_c = compensate_thesis(dict(zip(DEVIATIONS, theta)), xyz, bc)[0]
        xyz_c_model, miss = xyz_c + origin, float("nan")
    nominal = tool_point(np.zeros((1, len(DEVIATIONS))), geo, xyz_model, bc, model=model)[0]
    before = units.from_internal(np.linalg.norm(tool_point(theta[None], geo, xyz_model, bc, model=model)[0] - nominal,
                                                axis=-1), "um")
    resid = units.from_internal(np.linalg.norm(tool_point(draws, geo, xyz_c_model, bc, model=model) - nominal, axis=-1),
                                "um")  # (n, k)
    info = {"method": method, "model": model, "point": point, "values": values,
            "uncertainty_from": source, "geometry_mm": {"R_B": geo.R_B, "Z_T": geo.Z_T, "X_T": geo.X_T, "Z_C": geo.Z_C},
            "nc_origin_mm": origin.tolist(), "newton_miss_um": units.from_internal(miss, "um"),
            "deviations": {n: {"value": units.from_internal(v, DEVIATIONS[n].unit), "unit": DEVIATIONS[n].unit}
                           for n, v in zip(DEVIATIONS, theta) if v != 0.0}}
    warnings = prior_only_values(campaign, theta, posterior) if values == "posterior" else []
    return CompensationResult(rewrite(program, xyz_c), program.source, xyz, xyz_c, resid.mean(axis=0),
                              np.quantile(resid, 0.95, axis=0), before,
                              not_compensable(theta, geo, xyz_model, bc, model=model), info, warnings=warnings,
                              reading_choice=deviation_marks(campaign, theta, posterior=posterior, values=values))


def prior_only_values(campaign, theta: np.ndarray, posterior=None) -> list[str]:
    """A warning for each deviation compensated with a value the data do not determine one by one (the campaign's
    Jacobian, :func:`~mtmcal_bayes.inference.identifiability.campaign_identifiability`, for the posterior's data),
    and, separately, for each whose value rests on nuisance priors (the closed-form diagnostic
    :func:`~mtmcal_bayes.inference.analytic.prior_sensitivity`, at the posterior median of sigma_model when the
    posterior has one)."""
    idata = getattr(posterior, "idata", posterior)
    has_draws = hasattr(idata, "posterior")
    sigma_um = (float(np.median(idata.posterior["sigma_model"])) if has_draws and "sigma_model" in idata.posterior
                else SIGMA_MODEL_UM)
    data = str(idata.posterior.attrs.get("data", "ballbar")) if has_draws else "ballbar"
    lp = LogPosterior(campaign, "linear", data=data)
    ident = campaign_identifiability(lp)
    sens = prior_sensitivity(lp, units.to_internal(sigma_um, "um"))
    out = []
    for i, name in enumerate(DEVIATIONS):
        if name not in sens.through or theta[i] == 0.0:
            continue
        shown = f"{name} = {units.from_internal(theta[i], DEVIATIONS[name].unit):.3g} {units.SYMBOL[DEVIATIONS[name].unit]}"
        verdict, combos = ident.of(name)
        if verdict == IN_COMBINATION:
            out.append(f"compensating with {shown}, which the data determine only in combination ({'; '.join(combos)}): "
                       "its own value follows the priors")
        elif verdict != DETERMINED:
            out.append(f"compensating with {shown}, which the data do not identify (the campaign's Jacobian leaves it "
                       "undetermined; its value follows the priors)")
        if sens.through[name]:
            out.append(f"compensating with {shown}, whose value rests on the nuisance prior"
                       f"{'s' if len(sens.through[name]) > 1 else ''} {' and '.join(sens.through[name])}: the "
                       "correction is as good as that set-up knowledge (docs/metrology.md)")
    return out
