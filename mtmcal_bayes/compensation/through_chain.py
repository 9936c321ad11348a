"""``compensate`` on a described machine (SPEC §19): X/Y/Z rewritten through the machine's chain.

The program's words are the axes' positions (:mod:`.chain_inverse`); the rotary axes, whatever their letters,
stay as programmed.  Per block, Newton through :class:`~mtmcal_bayes.models.chain.Chain` finds the X, Y, Z at
which the deviated chain puts the tool point on the nominal chain's (:func:`.chain_inverse.invert`).

The values: the posterior mean of each deviation the campaign determines, one by one or in a combination; a
deviation it does not determine (:func:`~mtmcal_bayes.inference.identifiability.campaign_identifiability`) is
left at zero, its prior mean — its posterior is its prior, not a measurement — and its prior spread stays in the
residual band; one the machine's model does not estimate (not among its selected deviations) is held at zero and
is in neither.  The result states each of them and why.  The residual per block: the tool point of the
compensated program through the chain of each posterior draw, against the programmed point.
"""

from __future__ import annotations

import numpy as np

from .. import units
from ..errors import InputError, ParameterError
from ..inference.identifiability import campaign_identifiability
from ..inference.log_posterior import LogPosterior
from ..io.gcode import Program, rewrite
from ..io.netcdf import read_posterior, read_posterior_attrs
from ..machines.deviations import generated, redundant
from ..models.chain import Chain
from .chain_inverse import invert, tool_axis_tilt, work_tool_point
from .options import N_DRAWS, OFF_TOOL_MM
from .result import CompensationResult

#: why a deviation is not compensated with a measured value, by its class
LEFT_AT_ZERO = "not determined by this campaign (its posterior is its prior): left at zero, its prior mean; its " \
               "prior spread is in the residual band"
HELD_AT_ZERO = "not estimated by the machine's model ({why}): held at zero, not in the residual band"
IN_COMBINATION = "determined only in combination ({names}): compensated with its posterior mean, whose split " \
                 "within the combination is the prior's"


def program_commands(campaign, program: Program) -> dict[str, np.ndarray]:
    """``{letter: (k,)}`` commands (mm, rad) of the program's motion blocks, each block checked against the
    described travels (an :class:`InputError` naming the program's line)."""
    desc = campaign.machine.description
    pos = program.positions()
    q = {}
    for i, letter in enumerate(program.axes):
        ax = desc.axes[letter]
        unit = "deg" if ax.rotary else "mm"
        q[letter] = units.to_internal(pos[:, i], unit) if ax.rotary else pos[:, i]
        if ax.travel is None:
            continue
        lo, hi = ax.travel
        bad = np.flatnonzero((q[letter] < lo - 1e-12) | (q[letter] > hi + 1e-12))
        if bad.size:
            block = program.motion[int(bad[0])]
            shown = [units.from_internal(v, unit) if ax.rotary else v for v in (lo, hi)]
            sym = units.SYMBOL[unit]
            raise InputError(program.source, f"line {block.number}", f"{letter}{pos[bad[0], i]:g} is beyond the "
                             f"{letter} travel [{shown[0]:g}, {shown[1]:g}] {sym} of {desc.name} "
                             f"({desc.configuration})")
    return q


def tool_length(campaign, setup: str | None) -> tuple[float, str]:
    """The programmed tool length (mm) of a ball-bar set-up (default the campaign's first) and its id."""
    setups = campaign.ballbar.setups
    if not setups:
        raise ParameterError("setup", f"{campaign.source} has no ball-bar set-up to take the tool length from")
    if setup is not None and setup not in setups:
        raise ParameterError("setup", f"no setup {setup!r} in the campaign (have {', '.join(setups)})")
    sid = setup or next(iter(setups))
    return float(setups[sid].R_B), sid


def deviation_draws(campaign, posterior, *, n: int = N_DRAWS) -> tuple[dict[str, np.ndarray], object, str]:
    """``({name: (n,)} internal units, log posterior, where from)``: the deviation draws of ``posterior`` (a
    :class:`~mtmcal_bayes.posterior.sample.PosteriorResult`, an InferenceData or a NetCDF file of ``sample -o``),
    thinned evenly to at most ``n``, and the (linear) log posterior whose identifiability they are read with."""
    lp = getattr(posterior, "log_posterior", None)
    idata = getattr(posterior, "idata", posterior)
    if hasattr(idata, "posterior"):
        post, where = idata.posterior, "the given posterior"
        data = lp.data if lp is not None else str(idata.posterior.attrs.get("data", "ballbar"))
    else:
        post, where = read_posterior(posterior), str(posterior)
        data = str(read_posterior_attrs(posterior).get("data", "ballbar"))
    if lp is None or lp.model_name != "linear":
        lp = LogPosterior(campaign, "linear", data=data)
    devs = [p for p in lp.space.parameters if p.group == "deviation"]
    if not any(p.name in post for p in devs):
        raise InputError(where, None, "holds no draws of this machine's deviations (is it a posterior of this "
                         "campaign from mtmcal-bayes sample?)")
    total = int(np.asarray(post[next(p.name for p in devs if p.name in post)]).size)
    idx = np.linspace(0, total - 1, min(n, total)).astype(int)
    draws = {p.name: units.to_internal(np.ravel(np.asarray(post[p.name]))[idx], p.unit) for p in devs if p.name in post}
    return draws, lp, f"posterior draws from {where}"


def classify_values(campaign, draws: dict[str, np.ndarray], lp) -> tuple[dict[str, float], list[dict]]:
    """The values compensated with ``{name: value}`` (internal units) and the deviations not compensated with a
    measured value, each ``{"name", "status", "why"}`` (``left at zero``, ``held at zero``, ``in combination``)."""
    desc = campaign.machine.description
    ident = campaign_identifiability(lp)
    combos: dict[str, list[str]] = {}
    for c in ident.combinations:
        for name in c.weights:
            combos.setdefault(name, []).append(c.name)
    values, notes = {}, []
    reasons = redundant(desc)
    for d in generated(desc):
        if d.name not in draws:
            notes.append({"name": d.name, "status": "held at zero",
                          "why": HELD_AT_ZERO.format(why=reasons.get(d.name, "not selected in the description"))})
        elif d.name in ident.undetermined:
            notes.append({"name": d.name, "status": "left at zero", "why": LEFT_AT_ZERO})
        else:
            values[d.name] = float(np.mean(draws[d.name]))
            if d.name not in ident.determined:
                notes.append({"name": d.name, "status": "in combination",
                              "why": IN_COMBINATION.format(names="; ".join(combos.get(d.name, [])))})
    return values, notes


def tilts(chain: Chain, length: float, q: dict, values: dict[str, float]) -> list[dict]:
    """Tool-axis tilt left by each deviation used (largest over the blocks), all together, and its position error
    :data:`OFF_TOOL_MM` along the tool; one call for every deviation (one per row)."""
    names = [n for n, v in values.items() if v != 0.0]
    rows = len(names) + 1
    dev = {n: np.zeros(rows) for n in names}
    for i, n in enumerate(names):
        dev[n][i] = values[n]
        dev[n][-1] = values[n]  # the last row: all together
    tilt = tool_axis_tilt(chain, length, q, dev, n=rows).max(axis=1) if names else np.zeros(1)
    off = f"error_at_{OFF_TOOL_MM:g}mm_off_the_tool_point_um"
    out = [{"name": n, "tool_tilt_arcsec": units.from_internal(float(t), "arcsec"),
            off: units.from_internal(float(t) * OFF_TOOL_MM, "um")}
           for n, t in zip(names + ["all together"], tilt)]
    return sorted([r for r in out if r["tool_tilt_arcsec"] > 0.01 or r["name"] == "all together"],
                  key=lambda r: -r["tool_tilt_arcsec"])


def compensate_described(campaign, program: Program, posterior, *, setup: str | None = None,
                         point: str = "tcp", label: str | None = None) -> CompensationResult:
    """Compensate ``program`` (read with the description's rotary letters) for the deviations of ``posterior``
    (see the module docstring and :func:`deviation_draws`); ``point``: the tool centre (``"tcp"``, the set-up's
    tool length) or the spindle ``"nose"`` (length 0); ``setup``: the ball-bar set-up whose tool length is used;
    ``label``: where the posterior comes from, as the result states it (default: "the given posterior").

    Besides the residual band, ``info["residual_determined_um"]``: the band with the deviations left at zero held at
    zero in every draw too — what the data vouch for; the rest of the band is those deviations' prior spread."""
    desc = campaign.machine.description
    chain = Chain(desc, generated(desc))
    length, sid = tool_length(campaign, setup)
    length = length if point == "tcp" else 0.0
    q = program_commands(campaign, program)
    draws, lp, source = deviation_draws(campaign, posterior)
    values, notes = classify_values(campaign, draws, lp)
    xyz = np.stack([q[a] for a in "XYZ"], axis=-1)
    xyz_c, miss = invert(chain, length, q, values)
    nominal = work_tool_point(chain, length, q, {})[0]
    before = work_tool_point(chain, length, q, {n: np.array([v]) for n, v in values.items()})[0] - nominal
    n = len(next(iter(draws.values())))
    q_c = {**q, **{a: xyz_c[:, i] for i, a in enumerate("XYZ")}}
    resid = units.from_internal(np.linalg.norm(work_tool_point(chain, length, q_c, draws, n=n) - nominal, axis=-1),
                                "um")  # (n, k)
    left = [d["name"] for d in notes if d["status"] == "left at zero"]
    seen = {nm: v for nm, v in draws.items() if nm not in left}
    resid_seen = units.from_internal(np.linalg.norm(work_tool_point(chain, length, q_c, seen, n=n) - nominal, axis=-1),
                                     "um") if left else resid
    quantity = {p.name: p for p in lp.space.parameters}
    if label is not None:
        source = f"{label}, {n} draws"
    info = {"method": "exact", "model": "chain", "point": point, "values": "posterior", "uncertainty_from": source,
            "machine": {"name": desc.name, "configuration": desc.configuration, "rotary_axes": list(program.axes[3:])},
            "tool_length_mm": length, "setup": sid, "newton_miss_um": units.from_internal(miss, "um"),
            "deviations": {nm: {"value": units.from_internal(v, quantity[nm].unit), "unit": quantity[nm].unit}
                           for nm, v in values.items() if v != 0.0},
            "not_measured": notes,
            "residual_determined_um": {"mean_max": float(resid_seen.mean(axis=0).max()),
                                       "p95_max": float(np.quantile(resid_seen, 0.95, axis=0).max()),
                                       "per_block_p95": np.quantile(resid_seen, 0.95, axis=0).tolist()}}
    warnings = [f"left at zero, not determined by this campaign (their posterior is their prior): {', '.join(left)}"
                ] if left else []
    return CompensationResult(rewrite(program, xyz_c), program.source, xyz, xyz_c, resid.mean(axis=0),
                              np.quantile(resid, 0.95, axis=0),
                              units.from_internal(np.linalg.norm(before, axis=-1), "um"),
                              tilts(chain, length, q, values), info, warnings=warnings)
