"""Where a conflict between the instruments comes from: candidate explanations weighed by the data (SPEC §17).

When two instruments disagree (:mod:`.consistency`: the ball bar and the touch probe, or either of them and the
R-test), the question is which of the plausible causes the data support.  Each candidate is a changed campaign or
model; each is weighed by

* the **marginal likelihood** of the pair's fused linear model, ``log p(y | candidate)``: both instruments'
  data, every parameter and both discrepancy scales integrated out exactly (normal priors, the scales on
  a grid: :meth:`~mtmcal_bayes.inference.marginal.MarginalPosterior.log_evidence`).  Differences are log
  Bayes factors: 2.3 is 10 : 1, 4.6 is 100 : 1 (Jeffreys: above 2.3 strong, above 4.6 decisive);
* the posterior of the two discrepancy scales (a candidate that explains the conflict needs no large σ);
* the consistency check of each instrument against the other's posterior (:func:`instrument_consistency`).

Candidates, each where it applies to the pair and the campaign's machine:

* **Readings of the B patterns** (:mod:`mtmcal_bayes.conventions`), where the campaign has B-pattern runs whose
  reading the observations honour: the eight orientations in which a ball-bar program can draw the B = 0° and
  B = 90° ends of its arcs (the thesis' reading among them), each with the BY (and BA) bar on either side of the W
  ball.  The BX bar's side is fixed by the thesis' NC program (Fig 4.30(a): the T ball at X = −390 mm, 100 mm from
  the C axis in +X).  A campaign whose runs are read in the machine frame, whatever their convention, has none.
* **Stylus length along its axis** known to 0.3 mm instead of its prior (the touch probe's programmed length is
  the tool eye's with the controller's pivot length, which the ball bar's dial-gauge tool length does not share;
  pre-travel and stylus-ball radius act along the same axis): any machine with a touch probe.
* **The R-test's set-up** (docs/rtest.md), where the pair has the R-test: its readings in the other frame
  ("tool" for "machine" and back; only on a machine where the two differ), its readings' sign reversed (nest
  − sphere exported for sphere − nest), its runs zeroed at their first position where they say "absolute", its
  nests not calibrated where they say so, the sphere placed anew for every run where runs share a placement.
* **A difference between the sessions**, per rotary axis of the machine: that axis' orientation deviations (its
  two tilts and its zero; on the thesis machine the B axis' α_XB, β_XB, γ_XB and the C axis' α_CZ, β_CZ) differ in
  the second instrument's session (the probe's, the R-test's) from the first's — by a thermal drift (prior sd 5″
  each), or, beside the ball bar, by what clamping the axis at indexed positions (the probe, the static R-test)
  changes against continuous motion (the ball bar) (prior sd 20″ each).

Each candidate shows the fused posterior of the quantities :func:`shown_quantities` picks: the thesis' seven
(:data:`SHOWN`) where the machine has them, else every deviation it estimates.

The analysis is for the ``linear`` model (the kinematic models' first order: their nonlinearity is below
0.1 µm at thesis magnitudes) with normal priors.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .. import units
from ..conventions import geometry_string, parse_geometry, run_frame, run_matrix
from ..errors import ParameterError
from ..analysis import CampaignAnalysis
from ..inference.log_posterior import LogPosterior
from ..inference.marginal import MarginalPosterior
from ..io.machine_reader import description_of
from ..machines.deviations import generated
from ..observations import Observations
from ..parameters import DATA_INSTRUMENTS, DERIVED, DISCREPANCY_SCALES, quantity_unit
from ..patterns import B_PATTERNS
from .consistency import instrument_consistency

#: grid cells per scale for the evidence (log evidence within 0.01 of a 160-cell grid on the thesis campaign)
CELLS = 24
#: the stylus length's prior sd in the "stylus length" candidate, mm
STYLUS_LENGTH_SD = 0.3
#: each instrument in words, by its data name
INSTRUMENT_WORDS = {"ballbar": "ball bar", "probe": "touch probe", "rtest": "R-test"}
#: the pair of instruments whose conflict is weighed unless another is named
BALLBAR_PROBE = ("ballbar", "probe")
#: each instrument's possessive in the sessions' sentences, by its data name
OWNER = {"ballbar": "ball bar's", "probe": "probe's", "rtest": "R-test's"}
#: a rotary axis' angles' difference between the sessions: (label, prior sd in ″, what it supposes, with {axis},
#: {angles} and {second} (the second instrument's possessive) to fill, whether it needs the ball bar as the first)
SESSIONS = (("session drift 5″", 5.0, "a thermal drift of the {axis}-axis angles {angles} between the two sessions "
             "(sd 5″ each)", False),
            ("sessions differ 20″", 20.0, "the {axis}-axis angles {angles} differ between the {second} clamped indexed "
             "positions and the ball bar's continuous motion (sd 20″ each)", True))
#: the eight orientations of a B-pattern plot: where B = 0° and B = 90° are drawn (first: the thesis' reading)
ORIENTATIONS = ("B0=+Z,B90=+X", "B0=+Z,B90=-X", "B0=-Z,B90=+X", "B0=-Z,B90=-X",
                "B0=+X,B90=+Z", "B0=-X,B90=+Z", "B0=+X,B90=-Z", "B0=-X,B90=-Z")
#: the patterns whose bar runs along Y (their side of the W ball is not fixed by the thesis)
Y_BARS = ("BY", "BA")
#: quantities shown for every candidate, where the machine has them (the thesis machine's)
SHOWN = ("alpha_XB", "gamma_XB", "alpha_XB+gamma_XB", "beta_XB", "alpha_BT", "dy_CZ", "dz_BT")


def shown_quantities(post: LogPosterior) -> tuple[str, ...]:
    """The quantities each candidate shows: :data:`SHOWN` where ``post`` has every deviation they are made of, else
    the deviations ``post`` estimates, in its order."""
    names = set(post.space.names)
    parts = lambda q: q.split("+") if "+" in q else list(DERIVED.get(q, {q: 1.0}))  # noqa: E731
    if all(k in names for q in SHOWN for k in parts(q)):
        return SHOWN
    return tuple(p.name for p in post.space.parameters if p.group == "deviation")


def session_axes(campaign, post: LogPosterior) -> dict[str, list[str]]:
    """``{rotary axis letter: its orientation deviations post estimates}`` (the two tilts and the zero of each rotary
    axis of the campaign's machine, in the posterior's order; axes with none are left out)."""
    desc = description_of(campaign.machine)
    by_axis = {ax.letter: {d.name for d in generated(desc) if d.body == ax.letter and d.role == "orientation"}
               for ax in desc.rotary_axes}
    out = {k: [n for n in post.space.names if n in v] for k, v in by_axis.items()}
    return dict(sorted(((k, v) for k, v in out.items() if v), key=lambda kv: post.space.index(kv[1][0])))


def _weights(name: str, names: list[str]) -> np.ndarray:
    row = np.zeros(len(names))
    if name == "alpha_XB+gamma_XB":
        row[names.index("alpha_XB")] = row[names.index("gamma_XB")] = 1.0
        return row
    for k, w in DERIVED.get(name, {name: 1.0}).items():
        if k in names:
            row[names.index(k)] = w
    return row


def _unit(name: str) -> str:
    return "arcsec" if name == "alpha_XB+gamma_XB" else quantity_unit(name)


@dataclass
class Candidate:
    """One explanation: its id, what it supposes, its log evidence, scale means (µm), shown quantities (display
    units: mean and sd), and where it changes the campaign (``campaign``: a copy to analyse further)."""

    name: str
    kind: str
    supposes: str
    log_evidence: float
    scales: dict[str, float]
    quantities: dict[str, tuple[float, float]]
    campaign: object = field(repr=False, default=None)
    consistency: pd.DataFrame | None = None


def reread(campaign, orientation: str, y_reversed: bool):
    """A copy of ``campaign`` whose B runs read their offsets with the plot ``orientation`` (a B-plane geometry
    string), the BY/BA bar reversed when ``y_reversed``; None when the campaign has no B run."""
    out = copy.deepcopy(campaign)
    any_b = False
    for run in out.ballbar.runs:
        if run.pattern in B_PATTERNS:
            any_b = True
            frame = run_frame(run, out.ballbar)
            D = parse_geometry(orientation, frame)
            run.convention = geometry_string(-D if y_reversed and run.pattern in Y_BARS else D, frame)
    return out if any_b else None


def _reads_alike(a, b) -> bool:
    """Whether two campaigns' ball-bar observations are the same (a campaign whose observations do not follow its
    runs' conventions reads every reading alike)."""
    oa, ob = Observations.from_campaign(a), Observations.from_campaign(b)
    return oa.keys == ob.keys and bool(np.array_equal(oa.mean, ob.mean))


def _same_reading(a, b) -> bool:
    """Whether two campaigns read every run alike."""
    return all(np.allclose(run_matrix(x, a.ballbar), run_matrix(y, b.ballbar)) for x, y in zip(a.ballbar.runs,
                                                                                           b.ballbar.runs))


def _marginal(post: LogPosterior, extra: np.ndarray | None = None, extra_var: np.ndarray | None = None,
              cells: int = CELLS) -> MarginalPosterior:
    priors = post.priors.priors[: post.p]
    bad = [q.name for q in priors if q.dist != "normal"]
    if bad:
        raise ParameterError("campaign", f"weighing explanations needs normal priors; {bad[0]} has another in [priors]")
    A = post.forward.design
    var0 = np.array([q.sd for q in priors]) ** 2
    mean0 = np.array([q.loc for q in priors])
    if extra is not None:
        A, var0, mean0 = np.hstack([A, extra]), np.concatenate([var0, extra_var]), np.concatenate([mean0, 0 * extra_var])
    return MarginalPosterior(A, post.likelihood.base_var, var0, [q.frozen() for q in post.priors.priors[post.p:]],
                             prior_mean=mean0, groups=post.scale_of, y=post.likelihood.y, cells=cells)


def pair_data(pair: tuple[str, str]) -> str:
    """The ``data`` value whose likelihood uses exactly the instruments of ``pair`` (``("ballbar", "probe")`` ->
    ``"both"``)."""
    return next(d for d, used in DATA_INSTRUMENTS.items() if used == tuple(pair))


def _drift_columns(post: LogPosterior, sd_arcsec: float, drifting: list[str],
                   instrument: str = "probe") -> tuple[np.ndarray, np.ndarray]:
    """Columns of a difference of the angles ``drifting`` in ``instrument``'s session: the angles' own columns on
    that instrument's rows, prior sd ``sd_arcsec`` each."""
    A = post.forward.design
    scale = DISCREPANCY_SCALES[instrument].name
    rows = np.array([post.scales[k] == scale for k in post.scale_of])
    cols = [post.space.index(n) for n in drifting]
    extra = np.where(rows[:, None], A[:, cols], 0.0)
    return extra, np.full(len(cols), units.to_internal(sd_arcsec, "arcsec") ** 2)


def weigh(campaign, name: str, kind: str, supposes: str, *, drift_arcsec: float | None = None,
          drifting: list[str] = (), post: LogPosterior | None = None, pair: tuple[str, str] = BALLBAR_PROBE
          ) -> Candidate:
    """Evidence, scales and shown quantities (:func:`shown_quantities`) of the fused linear posterior of ``campaign``
    (a candidate) on the data of ``pair``, with the second instrument's session's angles ``drifting`` differing by a
    difference of prior sd ``drift_arcsec`` when it is given.  ``post``: that fused linear log posterior when it is
    at hand."""
    post = post or LogPosterior(campaign, "linear", data=pair_data(pair))
    drift = drift_arcsec is not None
    extra, extra_var = _drift_columns(post, drift_arcsec, drifting, pair[1]) if drift else (None, None)
    mp = _marginal(post, extra, extra_var)
    y = post.likelihood.y
    names = list(post.space.names) + ([f"drift {n}" for n in drifting] if drift else [])
    shown = shown_quantities(post)
    T = np.array([_weights(q, names) for q in shown])
    mean, sd = mp.target_moments(y[None], T)
    sm, _ = mp.sigma_moments(y)
    quantities = {q: (units.from_internal(mean[0, i], _unit(q)), units.from_internal(sd[0, i], _unit(q)))
                  for i, q in enumerate(shown)}
    return Candidate(name, kind, supposes, mp.log_evidence(y),
                     {n: units.from_internal(sm[k], "um") for k, n in enumerate(post.scales)}, quantities, campaign)


@dataclass
class ConflictAnalysis:
    """Every candidate explanation, best first (``candidates``); ``given`` is the campaign as it is; ``pair`` the two
    instruments (data names) whose conflict they explain."""

    given: Candidate
    candidates: list[Candidate]
    pair: tuple[str, str] = BALLBAR_PROBE

    @property
    def shown(self) -> tuple[str, ...]:
        """The quantities every candidate shows (:func:`shown_quantities`)."""
        return tuple(self.given.quantities)

    def table(self) -> pd.DataFrame:
        """One row per candidate: log Bayes factor against the campaign as given, scales, shown quantities."""
        rows = []
        for c in [self.given] + [c for c in self.candidates if c is not self.given]:
            row = {"candidate": c.name, "kind": c.kind, "supposes": c.supposes,
                   "log_bayes_factor": c.log_evidence - self.given.log_evidence}
            row.update({f"{n}_um": v for n, v in c.scales.items()})
            row.update({f"{q}": m for q, (m, _) in c.quantities.items()})
            rows.append(row)
        return pd.DataFrame(rows).sort_values("log_bayes_factor", ascending=False, kind="stable").reset_index(drop=True)

    def to_json(self) -> dict:
        return {"given": self.given.name, "candidates": [
            {"name": c.name, "kind": c.kind, "supposes": c.supposes,
             "log_bayes_factor": c.log_evidence - self.given.log_evidence, "scales_um": c.scales,
             "quantities": {q: {"mean": m, "sd": s, "unit": _unit(q)} for q, (m, s) in c.quantities.items()},
             "consistency": None if c.consistency is None else c.consistency.to_dict(orient="records")}
            for c in self.candidates]}

    def to_text(self, top: int = 8) -> str:
        t = self.table().head(top)
        who = ("the instruments'" if self.pair == BALLBAR_PROBE else
               f"the {INSTRUMENT_WORDS[self.pair[0]]}'s and the {INSTRUMENT_WORDS[self.pair[1]]}'s")
        lines = [f"Where {who} conflict could come from (fused linear model; log Bayes factor against the "
                 "campaign as given; σ posterior means; ″ and µm):"]
        scale_cols = [c for c in t.columns if c.endswith("_um")]
        head = (f"  {'candidate':50s} {'log BF':>7s} " + " ".join(f"{_scale_head(c):>8s}"
                                                                   for c in scale_cols)
                + " " + " ".join(f"{q.replace('alpha_XB+gamma_XB', 'α+γ XB'):>9s}" for q in self.shown))
        lines.append(head)
        for _, r in t.iterrows():
            lines.append(f"  {r['candidate'][:50]:50s} {r['log_bayes_factor']:7.1f} "
                         + " ".join(f"{r[c]:8.2f}" for c in scale_cols) + " "
                         + " ".join(f"{r[q]:9.2f}" for q in self.shown))
        return "\n".join(lines)


def _scale_head(column: str) -> str:
    """A scale's column head in the text: ``sigma_model_probe_um`` -> ``σ_probe``."""
    return column[:-3].replace("sigma_model", "σ")


def _consistency(c: Candidate, pair: tuple[str, str]) -> pd.DataFrame:
    cons = instrument_consistency(LogPosterior(c.campaign, "linear", data=pair[0]),
                                  LogPosterior(c.campaign, "linear", data=pair[1]))
    return cons.groups


def _rtest_copy(campaign, change) -> object:
    """A copy of ``campaign`` whose R-test runs (and nests) ``change(rtest)`` has changed in place."""
    out = copy.deepcopy(campaign)
    change(out.rtest)
    return out


def _rtest_candidates(campaign, data: str, given: LogPosterior) -> list[tuple[object, str, str, LogPosterior | None]]:
    """The R-test's set-up explanations of ``campaign`` (module docstring; ``given``: its fused linear log posterior
    on ``data``): ``(changed campaign, name, what it supposes, its fused linear log posterior or None)``, each only
    where it changes the campaign's model."""
    rt = campaign.rtest
    out = []

    def flip_frames(r):
        for run in r.runs:
            run.frame = "machine" if run.frame == "tool" else "tool"

    def negate(r):
        for run in r.runs:
            run.displacements = -run.displacements

    def free_zeros(r):
        for run in r.runs:
            run.zero = "first"

    def uncalibrate(r):
        for nest in r.nests.values():
            nest.calibrated = False

    def own_placements(r):
        for k, run in enumerate(r.runs):
            run.placement = f"run {k + 1}"

    given = given.forward.design
    frames = _rtest_copy(campaign, flip_frames)
    post = LogPosterior(frames, "linear", data=data)
    if post.forward.design.shape != given.shape or not np.allclose(post.forward.design, given, rtol=0, atol=1e-12):
        out.append((frames, "R-test in the other frame", "the R-test's readings are in the other frame (\"tool\" for "
                    "\"machine\" and back: whether the device turned them back with the nominal rotation)", post))
    out.append((_rtest_copy(campaign, negate), "R-test readings' sign reversed", "the R-test's readings are nest − "
                "sphere, not sphere − nest (the device's sign convention)", None))
    if any(run.zero == "absolute" for run in rt.runs):
        out.append((_rtest_copy(campaign, free_zeros), "R-test zeroed at the first position", "the R-test's "
                    "\"absolute\" runs were zeroed at their first position (the nest not set on a master)", None))
    if any(nest.calibrated for nest in rt.nests.values()):
        out.append((_rtest_copy(campaign, uncalibrate), "R-test nest not calibrated", "the nests said to be "
                    "calibrated are not: their length and centring are free with their priors", None))
    shared = [run.placement or tuple(run.sphere) for run in rt.runs]
    if len(set(shared)) < len(shared):
        out.append((_rtest_copy(campaign, own_placements), "sphere placed anew per run", "the sphere moved between "
                    "the R-test's runs: each run has its own placement", None))
    return out


def explain_conflict(campaign, *, pair: tuple[str, str] = BALLBAR_PROBE, consistency_of: int = 3) -> ConflictAnalysis:
    """Weigh the candidate explanations of a conflict between the instruments ``pair`` (data names, in the order
    ball bar, probe, R-test) of ``campaign`` (module docstring); the consistency check is run for the campaign as
    given and the ``consistency_of`` best candidates (none when 0).  ``campaign`` may be a
    :class:`~mtmcal_bayes.analysis.CampaignAnalysis`, whose fused linear log posterior then serves the campaign as
    given."""
    pair = tuple(pair)
    data = pair_data(pair)
    given_post = None
    if isinstance(campaign, CampaignAnalysis):
        given_post = campaign.variant(model="linear", data=data, fix_dx_BT=False, sigma_model=None).log_posterior
        campaign = campaign.campaign
    have = {"ballbar": bool(campaign.ballbar.runs), "probe": campaign.has_probe_readings(),
            "rtest": campaign.has_rtest_readings()}
    missing = [i for i in pair if not have[i]]
    if missing:
        what = {"ballbar": "ball-bar runs", "probe": "touch-probe readings", "rtest": "R-test readings"}[missing[0]]
        raise ParameterError("campaign", f"{campaign.source} has no {what}: there is no second instrument to weigh")
    posts = {id(campaign): given_post or LogPosterior(campaign, "linear", data=data)}  # built once per campaign
    given = weigh(campaign, "as given", "campaign", "the campaign as it is", post=posts[id(campaign)], pair=pair)
    out = [given]
    sd_um = units.from_internal(STYLUS_LENGTH_SD, "um")
    if "probe" in pair and ("dRS" not in campaign.priors or campaign.priors["dRS"].get("sd", 0.0) < STYLUS_LENGTH_SD):
        stylus = copy.deepcopy(campaign)
        stylus.priors["dRS"] = {"dist": "normal", "mean": 0.0, "sd": STYLUS_LENGTH_SD}
        posts[id(stylus)] = LogPosterior(stylus, "linear", data=data)
        out.append(weigh(stylus, "stylus length ±0.3 mm", "probe",
                         f"the stylus length along its axis known to {sd_um:g} µm (tool eye + controller pivot)",
                         post=posts[id(stylus)], pair=pair))
    if "rtest" in pair:
        for changed, name, supposes, post in _rtest_candidates(campaign, data, posts[id(campaign)]):
            posts[id(changed)] = post or LogPosterior(changed, "linear", data=data)
            out.append(weigh(changed, name, "R-test", supposes, post=posts[id(changed)], pair=pair))
    best_own = max(out, key=lambda c: c.log_evidence)  # the best of the instruments' own explanations
    base = best_own.campaign
    extra = "" if best_own is given else f"; {best_own.name}"
    base_post = posts.get(id(base)) or LogPosterior(base, "linear", data=data)
    for axis, angles in session_axes(base, base_post).items():
        for label, sd, supposes, beside_ballbar in SESSIONS:
            if beside_ballbar and pair[0] != "ballbar":
                continue
            out.append(weigh(base, f"{label} ({axis} axis){extra}", "sessions",
                             supposes.format(axis=axis, angles=", ".join(angles), second=OWNER[pair[1]]) + extra,
                             drift_arcsec=sd, drifting=angles, post=base_post, pair=pair))
    for orientation in ORIENTATIONS if "ballbar" in pair else ():
        for reversed_y in (False, True):
            moved = reread(base, orientation, reversed_y)
            if moved is None or _reads_alike(moved, base) or _same_reading(moved, base):
                continue  # no B run, runs read in the machine frame whatever their convention, or its own reading
            label = orientation + (", BY bar at −Y" if reversed_y else "")
            out.append(weigh(moved, label + extra, "ball-bar reading",
                             f"the B arcs drawn {orientation.replace(',', ', ')}"
                             + (", the BY/BA bar on the −Y side of the W ball" if reversed_y else "") + extra,
                             pair=pair))
    out.sort(key=lambda c: -c.log_evidence)
    checked = [given] + [c for c in out if c is not given and c.kind != "sessions"][:consistency_of]
    for c in checked if consistency_of else []:
        c.consistency = _consistency(c, pair)  # (a session difference changes the model, not a campaign: not checked)
    return ConflictAnalysis(given, out, pair)
