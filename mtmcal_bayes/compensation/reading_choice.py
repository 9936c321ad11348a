"""Which compensated deviations rest on the campaign's choice of reading (docs/compensation.md).

Where the reading of some ball-bar runs was chosen over another (``alternative_convention``,
docs/campaign-format.md), each deviation a program is compensated with is estimated under the alternative reading
too, from the posterior the compensation uses — the same model, data, dx_BT assumption and σ_model settings, exact
σ-marginal posteriors of both readings (:meth:`~mtmcal_bayes.analysis.CampaignAnalysis.reading_choice`).  A
deviation whose estimate moves by more than its posterior sd rests on the choice: ``compensate`` marks it and names
it in its summary.
"""

from __future__ import annotations

import math

from .. import units
from ..analysis import analysis_of
from ..inference import reading_choice
from ..io.netcdf import read_posterior_attrs


def _analysis(campaign, posterior):
    """The analysis of the posterior a compensation takes its draws from: a sampled result's own (or a plug-in's
    default draws', :class:`~.compensate.Draws`), or that an InferenceData or NetCDF file names in its attributes
    (model, data, dx_BT assumption, a fixed σ_model; a σ_model prior learnt elsewhere is not recorded there: the
    assumed one)."""
    lp = getattr(posterior, "log_posterior", None)
    if lp is not None:
        return analysis_of(lp.campaign, model=lp.model_name, data=lp.data, fix_dx_BT=lp.fix_dx_BT,
                           sigma_model=lp.fixed_sigma, sigma_prior=lp.sigma_prior)
    idata = getattr(posterior, "idata", posterior)
    attrs = dict(idata.posterior.attrs) if hasattr(idata, "posterior") else read_posterior_attrs(posterior)
    fixed = attrs.get("sigma_model_fixed_um")
    return analysis_of(campaign, model=str(attrs.get("model", "linear")), data=str(attrs.get("data", "ballbar")),
                       fix_dx_BT=bool(attrs.get("fix_dx_BT", 0)),
                       sigma_model=None if fixed is None else units.to_internal(float(fixed), "um"))


def deviation_marks(campaign, values: dict[str, float], unit: dict[str, str], *, posterior,
                    kind: str = "posterior") -> dict | None:
    """For each deviation of ``values`` (``{name: value}``, internal units; ``unit`` its display unit by name) used
    (non-zero): its value (display units), its estimate under the campaign's alternative reading, the shift in
    posterior sd and whether it rests on the choice; with the mark, the line saying what it means and the names
    resting on the choice.  None where the campaign records no choice, the posterior's data are the probe's alone,
    or the values are not the posterior's (``kind``: a plug-in's deterministic values, such as thesis Table 4.5,
    read the offsets as their procedure reads them whatever the campaign's reading: no choice enters)."""
    if kind != "posterior" or not campaign.ballbar.reading_choices():
        return None
    used = {n: v for n, v in values.items() if v != 0.0}
    table = _analysis(campaign, posterior).reading_choice(used)
    if table is None:
        return None
    deviations = {}
    for name, row in table.iterrows():
        deviations[name] = {"value": units.from_internal(used[name], unit[name]), "unit": unit[name],
                            "alternative": float(row[reading_choice.ALTERNATIVE]),
                            "shift_sd": float(row[reading_choice.SHIFT]) if math.isfinite(row[reading_choice.SHIFT])
                            else None, "rests_on_choice": bool(row[reading_choice.RESTS])}
    return {"mark": reading_choice.MARK, "note": reading_choice.note(campaign),
            "rests_on_choice": [n for n, d in deviations.items() if d["rests_on_choice"]], "deviations": deviations}
