"""Synthetic ball-bar data: predicted eccentricities for a known truth, with realistic scatter.

A truth (``[truth]`` of a campaign, or a TRUTH.toml with the same tables at top
level) gives the parameter vector; a forward model predicts every component of
every run.  With noise, each component gets, like a real measurement, an
instrument error shared by the run's repeats (sd = the ball bar's accuracy)
and a repeat scatter per repeat, rounded to the instrument resolution.  This is
the data-generating process the likelihood assumes (SPEC §5).
"""

from __future__ import annotations

import copy

import numpy as np

from .. import units
from ..campaign import Campaign, Run, Truth
from ..errors import InputError
from ..machines import selected
from ..machines.patterns import components
from ..machines.plugins import provided
from ..machines.space import described_space
from ..models import default_kinematic_model, first_order_gap, make_model
from ..models.probe import DEFAULT_REPEATABILITY, repeatability_required
from ..observations import TYPICAL_REPEAT_SD_UM, Observations, with_run_values
from ..parameters import ParameterSpace, nuisance_name

#: repeat scatter of a described machine's probe readings where the campaign states no repeatability, mm
DEFAULT_PROBE_SD = DEFAULT_REPEATABILITY
#: resolution of the ball-bar readings (thesis Table 4.1)
RESOLUTION_UM = 0.1


def truth_vector(space: ParameterSpace, truth: Truth, source: str = "<truth>") -> np.ndarray:
    """Parameter vector ``(p,)`` (internal units) of a truth; missing values are zero."""
    values = dict(truth.deviations)
    for group in (truth.setups, truth.mounts, truth.probe, truth.rtest):
        for owner, kv in group.items():
            values.update({nuisance_name(k, owner): v for k, v in kv.items()})
    missing = [k for k in values if k not in space.names]
    if missing:
        raise InputError(source, missing[0], "not a parameter of this campaign")
    return space.vector(values)


def simulation_space(campaign: Campaign, truth: Truth, data: str) -> ParameterSpace | None:
    """The space a truth is simulated in: the machine's selected deviations and any other the truth gives (every
    generated one may be simulated); None (the model's default) where the machine's plug-in builds the models of its
    own campaign format (the thesis': all 13)."""
    if provided(campaign.machine, "make_model") is not None:
        return None
    chosen = [d.name for d in selected(campaign.machine.description)]
    return described_space(campaign, chosen + [d for d in truth.deviations if d not in chosen], data=data)


def truth_from_vector(space: ParameterSpace, theta: np.ndarray) -> Truth:
    """The :class:`Truth` of a parameter vector; ``theta`` may be longer than the space (extra columns ignored)."""
    t = Truth()
    for i, p in enumerate(space.parameters):
        if p.group == "deviation":
            t.deviations[p.name] = float(theta[i])
        else:
            table = getattr(t, p.group) if p.group in ("probe", "rtest") else getattr(t, p.group + "s")
            table.setdefault(p.owner, {})[p.base] = float(theta[i])
    return t


def planned_as_runs(campaign: Campaign) -> Campaign:
    """``campaign`` itself when it plans no run, else a copy whose planned runs are runs, appended after the measured
    ones in measuring order, each with every component of its pattern and ``repeats`` placeholder repeats (zeros,
    to be replaced by simulated values); the copy plans nothing.

    A planned run with a bar length of its own is an error: the forward models take the campaign's one
    ``[ballbar] length_mm`` for every run."""
    bb = campaign.ballbar
    if not bb.planned:
        return campaign
    for k, run in enumerate(bb.planned, start=1):
        if run.length is not None:
            raise InputError(campaign.source, "ballbar.runs", f"planned run {k} ({run.label}) asks for a bar of "
                             f"{run.length:g} mm, and the models simulate every run with the campaign's bar length "
                             f"L_B = {bb.length:g} mm: simulate it from a campaign whose [ballbar] length_mm is "
                             f"{run.length:g}")
    out = copy.deepcopy(campaign)
    comps = provided(campaign.machine, "pattern_components") or (lambda p: components(campaign.machine.description, p))
    out.ballbar.runs += [Run(p.pattern, p.setup, p.mount, {c: np.zeros(p.repeats) for c in comps(p.pattern)},
                             convention=p.convention, arc_deg=p.arc_deg, hold_deg=p.hold_deg)
                         for p in out.ballbar.planned]
    out.ballbar.planned = []
    return out


def predict_truth(campaign: Campaign, truth: Truth, model: str = "htm-thesis", *,
                  source: str = "<truth>") -> tuple[Observations, np.ndarray]:
    """Noise-free eccentricities ``(m,)`` (mm) of every observed component under ``model``; planned runs are
    predicted too (every component), their observations after the measured runs' (:func:`planned_as_runs`:
    the observation keys index the runs of that campaign).

    A truth so large that an eccentricity is not finite or not below the bar
    length (no ball-bar could measure it) is an error naming ``source``.
    """
    fm, _, pred = ballbar_prediction(campaign, truth, model, source=source)
    return fm.observations, pred


def ballbar_prediction(campaign: Campaign, truth: Truth, model: str = "htm-thesis", *,
                       source: str = "<truth>") -> tuple:
    """:func:`predict_truth` with what it was computed from: ``(forward model of the campaign with its planned runs
    as runs, truth vector (p,) in its space, eccentricities (m,) mm)``."""
    campaign = planned_as_runs(campaign)
    if not campaign.ballbar.runs:
        raise InputError(campaign.source, "ballbar.runs", "nothing to simulate: the campaign has no runs, measured or "
                         "planned; add [[ballbar.runs]] (planned = true, repeats = N for runs not yet measured)")
    fm = make_model(model, campaign, simulation_space(campaign, truth, "ballbar"))
    theta = truth_vector(fm.space, truth.ballbar_part(), source)
    with np.errstate(all="ignore"):  # an absurd truth overflows; the check below names it
        pred = fm.predict(theta)
        bad = ~(np.abs(pred) < campaign.ballbar.length)
    if bad.any():
        k = fm.observations.keys[int(np.argmax(bad))]
        raise InputError(source, None, f"this truth gives {k.component} of {k.pattern} = "
                         f"{units.from_internal(pred[bad][0], 'um'):.4g} µm under {model}, not below the bar length "
                         f"L_B = {campaign.ballbar.length:g} mm: the deviations are too large to be measured")
    return fm, theta, pred


def first_order_warnings(fm, theta: np.ndarray) -> list[str]:
    """The warning of a ``linear`` model ``fm`` (:func:`ballbar_prediction`) asked for a truth ``theta`` too large for
    it: where the machine's kinematic model predicts eccentricities further from it than the ball bar's accuracy
    (:func:`~mtmcal_bayes.models.first_order_gap`); none for another model."""
    if fm.name != "linear":
        return []
    campaign = fm.campaign
    gap = first_order_gap(campaign, theta, fm.space)
    if gap <= campaign.ballbar.accuracy:
        return []
    return [f"the linear model is first order and this truth is too large for it: "
            f"{default_kinematic_model(campaign.machine)} predicts eccentricities up to "
            f"{units.from_internal(gap, 'um'):.1f} µm away (instrument accuracy "
            f"{units.from_internal(campaign.ballbar.accuracy, 'um'):g} µm)"]


def noisy_repeats(mean: np.ndarray, n_repeats: np.ndarray, accuracy: float, rng: np.random.Generator, *,
                  repeat_sd: float = units.to_internal(TYPICAL_REPEAT_SD_UM, "um"),
                  resolution: float = units.to_internal(RESOLUTION_UM, "um")) -> list[np.ndarray]:
    """Repeats around ``mean`` (m,), mm: shared instrument error N(0, accuracy) + N(0, repeat_sd) each, rounded."""
    out = []
    for mu, r in zip(mean, n_repeats):
        vals = mu + rng.normal(0.0, accuracy) + rng.normal(0.0, repeat_sd, size=int(r))
        out.append(np.round(vals / resolution) * resolution)
    return out


def synthetic_campaign(campaign: Campaign, truth: Truth, model: str = "htm-thesis", *, noise: bool = False,
                       seed: int | None = None, repeats: int | None = None, sigma_model: float = 0.0) -> Campaign:
    """A copy of ``campaign`` whose runs carry simulated data and whose ``[truth]`` is ``truth``.

    Noise-free: one repeat per component equal to the prediction.  With
    ``noise``: as many repeats as the original run (or ``repeats``), scattered
    as described in the module docstring.  Planned runs are filled: measured runs after the others, in measuring
    order, with every component of their pattern and their planned number of repeats (one without ``noise``),
    so the copy plans nothing.  ``sigma_model`` (mm, with ``noise``): a model discrepancy, one N(0, σ²) offset per
    observed eccentricity shared by its repeats (what the model leaves out).  Touch-probe and R-test readings are
    simulated too (:func:`simulated_probe`, :func:`simulated_rtest`) when the campaign has them; published results
    are dropped (they belong to the real measurement).
    """
    campaign = planned_as_runs(campaign)
    rng = np.random.default_rng(seed) if noise else None
    if not campaign.ballbar.runs and (campaign.has_probe_readings() or campaign.has_rtest_readings()):
        out = copy.deepcopy(campaign)  # a campaign of the probe or the R-test alone
        out.probe = simulated_probe(campaign, truth, model, noise=noise, rng=rng, repeats=repeats)
        out.rtest = simulated_rtest(campaign, truth, model, noise=noise, rng=rng, repeats=repeats)
        out.truth = copy.deepcopy(truth)
        return out
    obs, pred = predict_truth(campaign, truth, model)
    if noise:
        n = np.full(len(obs), repeats) if repeats else obs.n
        if sigma_model > 0:  # drawn only then: a history without discrepancy keeps its random stream
            pred = pred + rng.normal(0.0, sigma_model, len(pred))
        values = noisy_repeats(pred, n, campaign.ballbar.accuracy, rng)
    else:
        values = [np.array([v]) for v in pred]
    out = with_run_values(campaign, obs.keys, values)
    out.probe = simulated_probe(campaign, truth, model, noise=noise, rng=rng if noise else None, repeats=repeats)
    out.rtest = simulated_rtest(campaign, truth, model, noise=noise, rng=rng if noise else None, repeats=repeats)
    out.truth = copy.deepcopy(truth)
    return out


def simulated_rtest(campaign: Campaign, truth: Truth, model: str = "chain", *, noise: bool = False,
                    rng: np.random.Generator | None = None, repeats: int | None = None):
    """The campaign's ``[rtest]`` with its runs' displacements simulated for ``truth`` (SPEC §22), in the order of
    :attr:`~mtmcal_bayes.campaign.RTest.runs`: the R-test model's (``linear``: its first order; any other name: the
    chain).  Noise-free: one repeat equal to the prediction.  With ``noise``: as many repeats as measured (or
    ``repeats``), each scattered by the sensors' repeatability (:data:`DEFAULT_PROBE_SD` where none is stated).
    None without an ``[rtest]``."""
    if not campaign.has_rtest_readings():
        return copy.deepcopy(campaign.rtest)
    readings = rtest_readings(campaign, truth, model)
    sd = campaign.rtest.repeatability if campaign.rtest.repeatability is not None else DEFAULT_PROBE_SD
    out = copy.deepcopy(campaign.rtest)
    for run, d in _repeats(readings, out.runs, [run.displacements.shape[0] for run in out.runs], noise=noise,
                           repeats=repeats, sd=sd, rng=rng):
        run.displacements = d
    return out


def _repeats(readings: np.ndarray, runs, measured: list[int], *, noise: bool, repeats: int | None, sd: float, rng):
    """Per run (in order, ``runs[i].positions`` of the ``(k, 3)`` ``readings`` each): ``(run, (r, a, 3))`` the
    readings repeated ``measured[i]`` times (``repeats`` where given) each scattered by ``sd`` with ``noise``, else
    once as they are."""
    start = 0
    for run, k in zip(runs, measured):
        a = run.positions
        r = (repeats or k) if noise else 1
        d = np.broadcast_to(readings[start:start + a], (r, a, 3)).copy()
        if noise:
            d += rng.normal(0.0, sd, size=d.shape)
        yield run, d
        start += a


def rtest_readings(campaign: Campaign, truth: Truth, model: str = "chain") -> np.ndarray:
    """Noise-free R-test readings ``(k, 3)``, mm, of every position for ``truth`` under the R-test model of
    ``model``, in the order of :attr:`~mtmcal_bayes.campaign.RTest.runs`."""
    fm = make_model(model, campaign, simulation_space(campaign, truth, "rtest"), data="rtest")
    return fm.predict(truth_vector(fm.space, truth.rtest_part())).reshape(-1, 3)


def simulated_probe(campaign: Campaign, truth: Truth, model: str = "htm-thesis", *, noise: bool = False,
                    rng: np.random.Generator | None = None, repeats: int | None = None):
    """The campaign's ``[probe]`` with its runs' readings simulated for ``truth``: ``None`` without a ``[probe]`` or
    where a gap of the campaign keeps the probe model from running (:meth:`~mtmcal_bayes.campaign.Campaign.probe_gap`);
    the probe as measured where it has no readings or no repeatability its model can take (:func:`probe_noise`).

    The readings are the probe model's (:func:`probe_readings`), handed to the runs in order
    (:attr:`~mtmcal_bayes.campaign.Probe.runs`).  Noise-free: one repeat equal to the prediction.  With
    ``noise``: as many repeats as measured (or ``repeats``), each scattered by the probe's repeatability.  DPRNT file
    names and fit covariances are dropped: the readings are centres now.
    """
    sd = probe_noise(campaign)
    if sd is None:  # no readings, or none its model can take: the probe as it is
        return copy.deepcopy(campaign.probe)
    if campaign.probe_gap() is not None:  # readings the probe model cannot simulate: none (Simulation.save says so)
        return None
    readings = probe_readings(campaign, truth, model)
    out = copy.deepcopy(campaign.probe)
    for run, centres in _repeats(readings, out.runs, [run.centres.shape[0] for run in out.runs], noise=noise,
                                 repeats=repeats, sd=sd, rng=rng):
        run.replace_centres(centres)
    return out


def probe_noise(campaign: Campaign) -> float | None:
    """The sd, mm, of a simulated probe reading's repeat scatter: the probe's repeatability; where it states none,
    :data:`DEFAULT_PROBE_SD`, unless the machine's probe model takes only a stated one (the thesis': its readings are
    then not simulated); None without probe readings."""
    if not campaign.has_probe_readings():
        return None
    if campaign.probe.repeatability is not None:
        return campaign.probe.repeatability
    return None if repeatability_required(campaign.machine) else DEFAULT_PROBE_SD


def probe_readings(campaign: Campaign, truth: Truth, model: str = "htm-thesis") -> np.ndarray | None:
    """Noise-free readings ``(k, 3)``, mm, of every probed position for ``truth`` under the probe model of ``model``
    (``linear``: its first order), in the campaign's reading frame and in the order of
    :attr:`~mtmcal_bayes.campaign.Probe.runs`; None where the campaign has none to simulate (no readings, a
    gap, no repeatability its model can take: :func:`probe_noise`)."""
    if probe_noise(campaign) is None or campaign.probe_gap() is not None:
        return None
    fm = make_model(model, campaign, simulation_space(campaign, truth, "probe"), data="probe")
    return fm.centres(truth_vector(fm.space, truth.probe_part()))


def probe_records(campaign: Campaign, readings: np.ndarray) -> list[dict]:
    """JSON records of ``readings`` (k, 3), mm (:func:`probe_readings`), one per probed position: run, stylus,
    position (from 1), each rotary axis' angle (``<letter>_deg``) and ``X_mm``, ``Y_mm``, ``Z_mm``."""
    out, start = [], 0
    for run in campaign.probe.runs:
        out += [{"run": run.id, "stylus": run.stylus, "position": i + 1,
                 **{f"{a}_deg": float(v[i]) for a, v in run.angles_deg.items()},
                 **{f"{x}_mm": float(readings[start + i, j]) for j, x in enumerate("XYZ")}}
                for i in range(run.positions)]
        start += run.positions
    return out


def eccentricity_records(obs: Observations, values: np.ndarray) -> list[dict]:
    """JSON records ``{"pattern", "setup", "mount", "component", "value_um"}`` of ``values`` (m,), mm."""
    return [{"pattern": k.pattern, "setup": k.setup, "mount": k.mount, "component": k.component,
             "value_um": units.from_internal(v, "um")} for k, v in zip(obs.keys, values)]
