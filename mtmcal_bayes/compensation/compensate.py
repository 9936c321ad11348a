"""``compensate`` on any machine: one path from the program's commands to the compensated program (SPEC §20).

1. the program's commands, each block within the description's travels (:func:`program_commands`);
2. the posterior's deviation draws (:func:`.values.deviation_draws`);
3. the values compensated with (:func:`.values.classify_values`): the posterior mean of each deviation the model
   estimates — under the posterior the value that leaves the smallest expected squared error — except one whose
   posterior is its prior (the campaign's Jacobian, nuisance terms included, leaves it undetermined:
   :func:`~mtmcal_bayes.inference.identifiability.campaign_identifiability`, and no nuisance prior informs it), which
   is left at zero, its prior mean, its spread staying in the residual band; one the machine's model does not
   estimate is held at zero and is in neither.  Each value the data do not determine one by one is named, with the
   nuisance priors it rests on (the separate diagnostic :func:`~mtmcal_bayes.inference.analytic.prior_sensitivity`).
   A plug-in may offer values of its own (the thesis' ball-bar values, Table 4.5);
4. Newton block by block through the machine's kinematics (:func:`.inverse.invert`; the description's chain,
   :mod:`.chain_kinematics`, or a plug-in's), or a plug-in's method (the thesis' Eqs 3.4–3.13 as printed);
5. per block the residual band: the tool point of the compensated program through the kinematics of each draw,
   against the programmed point;
6. the tool-axis tilt each deviation used leaves (:func:`tilts`), the warnings, the result.

What a machine's plug-ins may contribute (:func:`~mtmcal_bayes.machines.plugins.provided`):
``compensation_kinematics(campaign, model=, point=, setup=, mount=)`` (default :func:`.chain_kinematics.
chain_kinematics`), ``compensation_methods`` ``{name: method(kin, values, program, q) -> xyz (k, 3)}``,
``compensation_values`` ``{name: values(campaign) -> {deviation: value}}``, and a default posterior
(``compensation_posterior``, asked for by ``api.compensate``).
"""

from __future__ import annotations

import numpy as np

from .. import units
from ..errors import InputError, ParameterError
from ..inference.analytic import prior_sensitivity
from ..inference.identifiability import campaign_identifiability
from ..io.gcode import LINEAR, Program, read_program, rewrite
from ..machines.plugins import provided
from ..machines.selection import selected
from .chain_kinematics import chain_kinematics
from .inverse import invert, tool_axis_tilt, with_xyz
from .options import OFF_TOOL_MM, POINTS
from .reading_choice import deviation_marks
from .result import CompensationResult
from .values import classify_values, deviation_draws, sigma_model_um, value_warnings

#: the engine's own method and values
EXACT, POSTERIOR = "exact", "posterior"


def _where(campaign) -> str:
    desc = campaign.machine.description
    return f"{desc.name} ({desc.configuration})"


#: what each option of ``compensate`` chooses, as its refusal names it
_WHAT = {"method": "a compensation method", "values": "a source of the values", "point": "a tool point"}


def check_options(campaign, *, method: str, values: str, point: str) -> None:
    """A :class:`ParameterError` naming the first option the machine does not offer: ``method`` (exact, or a
    plug-in's), ``values`` (posterior, or a plug-in's), ``point``."""
    for name, value, offered in (
            ("method", method, (EXACT, *provided(campaign.machine, "compensation_methods", {}))),
            ("values", values, (POSTERIOR, *provided(campaign.machine, "compensation_values", {}))),
            ("point", point, POINTS)):
        if value not in offered:
            raise ParameterError(name, f"{value!r}: {_WHAT[name]} {_where(campaign)} does not offer (it has "
                                 f"{' or '.join(offered)})")


def kinematics_of(campaign, *, model: str | None = None, point: str = "tcp", setup: str | None = None,
                  mount: str | None = None):
    """The kinematics a compensation on ``campaign``'s machine inverts: a plug-in's
    (``compensation_kinematics``) or the description's chain (:func:`.chain_kinematics.chain_kinematics`); a
    :class:`ParameterError` for a ``model``, ``setup`` or ``mount`` it does not take."""
    make = provided(campaign.machine, "compensation_kinematics", chain_kinematics)
    return make(campaign, model=model, point=point, setup=setup, mount=mount)


def read(campaign, path, *, integer_unit: str | None = None) -> Program:
    """The program at ``path``, its rotary axes by the description's letters (each one required), every block
    checked against the travels (:func:`program_commands`)."""
    rotary = tuple(a.letter for a in campaign.machine.description.rotary_axes)
    program = read_program(path, integer_unit=integer_unit, rotary=rotary, required=LINEAR + rotary)
    program_commands(campaign, program)
    return program


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


def tilts(kin, q: dict, values: dict[str, float]) -> list[dict]:
    """Tool-axis tilt left by each deviation used (largest over the blocks), all together, and its position error
    :data:`OFF_TOOL_MM` along the tool; one call for every deviation (one per row)."""
    names = [n for n, v in values.items() if v != 0.0]
    rows = len(names) + 1
    dev = {n: np.zeros(rows) for n in names}
    for i, n in enumerate(names):
        dev[n][i] = values[n]
        dev[n][-1] = values[n]  # the last row: all together
    tilt = tool_axis_tilt(kin, q, dev, n=rows).max(axis=1) if names else np.zeros(1)
    off = f"error_at_{OFF_TOOL_MM:g}mm_off_the_tool_point_um"
    out = [{"name": n, "tool_tilt_arcsec": units.from_internal(float(t), "arcsec"),
            off: units.from_internal(float(t) * OFF_TOOL_MM, "um")}
           for n, t in zip(names + ["all together"], tilt)]
    return sorted([r for r in out if r["tool_tilt_arcsec"] > 0.01 or r["name"] == "all together"],
                  key=lambda r: -r["tool_tilt_arcsec"])


def worst_block_p95(resid: np.ndarray) -> float:
    """The simultaneous 95 % band of a program, µm: per draw the largest residual over its blocks, the 95 % quantile
    of those maxima — the error no block of the program exceeds with 95 % probability (≥ every block's own 95 %
    quantile).  ``resid`` ``(n draws, k blocks)`` µm."""
    return float(np.quantile(resid.max(axis=1), 0.95))


def compensate(campaign, program: Program, posterior, *, method: str = EXACT, model: str | None = None,
               values: str = POSTERIOR, point: str = "tcp", setup: str | None = None,
               mount: str | None = None, label: str | None = None) -> CompensationResult:
    """Compensate ``program`` (read by :func:`read`) for the deviations of ``posterior`` (see the module docstring
    and :func:`deviation_draws`).  ``method``: ``"exact"`` (Newton through the kinematics) or a plug-in's;
    ``model``: the kinematics' model (default the machine's); ``values``: the posterior mean or a plug-in's;
    ``point``: the tool centre (``"tcp"``) or the spindle ``"nose"``; ``setup``/``mount``: the campaign's tool and
    workpiece placement, where the kinematics takes them; ``label``: what the posterior is, as the result states it
    (default: the posterior given, or a :class:`.values.Draws`' own).

    The residual band is stated per block (``residual_p95_um``) and for the whole program at once
    (``residual_program_p95_um``, :func:`worst_block_p95`).  Besides, ``info["residual_determined_um"]``: the band with the deviations left at zero held at
    zero in every draw too — what the data vouch for; the rest of the band is those deviations' prior spread."""
    machine = campaign.machine
    check_options(campaign, method=method, values=values, point=point)
    kin = kinematics_of(campaign, model=model, point=point, setup=setup, mount=mount)
    q = program_commands(campaign, program)
    draws, lp, source = deviation_draws(campaign, posterior, label=label)
    ident = campaign_identifiability(lp)
    through = prior_sensitivity(lp, units.to_internal(sigma_model_um(posterior), "um")).through
    used, notes = classify_values(campaign, draws, ident, through)
    unit = {p.name: p.unit for p in lp.space.parameters}
    left = [d["name"] for d in notes if d["status"] == "left at zero"]
    if values != POSTERIOR:  # a plug-in's values (the thesis' ball-bar values): each as its procedure gives it
        used = provided(machine, "compensation_values")[values](campaign)
    desc = machine.description
    rank = {name: i for i, name in enumerate(desc.deviations or [d.name for d in selected(desc)])}
    used = dict(sorted(used.items(), key=lambda item: rank.get(item[0], len(rank))))  # the description's order
    warnings = []
    if values == POSTERIOR:
        if left:
            warnings.append("left at zero, not determined by this campaign (their posterior is their prior): "
                            + ", ".join(left))
        warnings += value_warnings(ident, through, used, unit)
    xyz = np.stack([q[a] for a in LINEAR], axis=-1)
    if method == EXACT:
        xyz_c, miss = invert(kin, q, used)
    else:
        xyz_c, miss = provided(machine, "compensation_methods")[method](kin, used, program, q), float("nan")
    nominal = kin.tool_point(q, {})[0]
    before = kin.tool_point(q, {n: np.array([v]) for n, v in used.items()})[0] - nominal
    n = len(next(iter(draws.values())))
    q_c = with_xyz(q, xyz_c)
    resid = units.from_internal(np.linalg.norm(kin.tool_point(q_c, draws, n=n) - nominal, axis=-1), "um")  # (n, k)
    seen = {nm: v for nm, v in draws.items() if nm not in left}
    resid_seen = units.from_internal(np.linalg.norm(kin.tool_point(q_c, seen, n=n) - nominal, axis=-1),
                                     "um") if left else resid
    info = {"method": method, "model": kin.model, "point": point, "values": values,
            "uncertainty_from": source,
            "machine": {"name": desc.name, "configuration": desc.configuration, "rotary_axes": list(program.axes[3:])},
            **kin.info, "newton_miss_um": units.from_internal(miss, "um"),
            "deviations": {nm: {"value": units.from_internal(v, unit[nm]), "unit": unit[nm]}
                           for nm, v in used.items() if v != 0.0}}
    if values == POSTERIOR:
        info["not_measured"] = notes
        info["residual_determined_um"] = {"mean_max": float(resid_seen.mean(axis=0).max()),
                                          "p95_max": float(np.quantile(resid_seen, 0.95, axis=0).max()),
                                          "program_p95": worst_block_p95(resid_seen),
                                          "per_block_p95": np.quantile(resid_seen, 0.95, axis=0).tolist()}
    return CompensationResult(rewrite(program, xyz_c), program.source, xyz, xyz_c, resid.mean(axis=0),
                              np.quantile(resid, 0.95, axis=0),
                              units.from_internal(np.linalg.norm(before, axis=-1), "um"), tilts(kin, q, used), info,
                              warnings=warnings,
                              reading_choice=deviation_marks(campaign, used, unit, posterior=posterior, kind=values),
                              residual_program_p95_um=worst_block_p95(resid))
