"""Do the instruments agree, on which deviations do they not, and what could explain it: one check, fast.

:func:`check_instruments` runs the consistency check of every pair of the campaign's instruments (the ball bar,
the touch probe, the R-test: each against the other's posterior) on the exact
posteriors of the ``linear`` model (the kinematic models' first order; closed form on a grid, no
sampling: :mod:`.consistency`), the fused posterior's discrepancy scales (one per instrument), the
deviations each disagreeing reading group depends on (:func:`disputed_deviations`), and — on request, for each
pair that disagrees — the candidate explanations weighed by the marginal likelihood (:mod:`.conflict`).  ``compensate`` refuses
a disputed deviation (SPEC §17) on this check; ``mtmcal-bayes instruments`` prints it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import combinations

import numpy as np

from .. import units
from ..analysis import CampaignAnalysis, analysis_of
from ..errors import ParameterError
from ..inference.analytic import linearisation
from ..inference.log_posterior import LogPosterior
from ..parameters import DATA_INSTRUMENTS, SCALE_LABEL, data_instruments
from .conflict import ConflictAnalysis, explain_conflict
from .consistency import (GIVEN_LABEL, UNCHECKED, Consistency, column_basis, flat_terms, instrument_consistency,
                          pairwise, reading_groups, target_noise)

#: each instrument in words, by its data name
INSTRUMENT_NAME = {"ballbar": "ball bar", "probe": "touch probe", "rtest": "R-test"}


def _pair_label(a: str, b: str) -> str:
    return f"{INSTRUMENT_NAME[a]} / {INSTRUMENT_NAME[b]}"


def _roles(g, posteriors) -> tuple[LogPosterior, LogPosterior]:
    """``(target, source)`` of a group's row ``g``: the posterior whose readings it is, the one it was given."""
    source = next(p for p in posteriors if GIVEN_LABEL.get(p.data) == g["given"])
    target = next(p for p in posteriors if p is not source
                  and g["group"] in reading_groups(p.forward.observations.keys))
    return target, source


def disputed_deviations(consistency: Consistency, *posteriors: LogPosterior) -> dict[str, list[str]]:
    """``{deviation: [sentence per disagreeing group that depends on it]}``; ``posteriors``: the log posteriors of
    each instrument's data alone (the ball bar's and the probe's; the R-test's where the check has it; any model: a
    kinematic one is linearised).

    A group depends on a deviation when the deviation moves its readings in a way the group's flat nuisance terms
    (those the check profiles out: :func:`~.consistency.flat_terms`) cannot absorb: the deviation's column of the
    target's linear design, restricted to the group's readings, has a part outside the span of the flat columns.
    Every deviation the target's posterior has counts, whatever the machine calls it."""
    return _disputed(consistency, posteriors)[0]


def _disputed(consistency: Consistency, posteriors) -> tuple[dict[str, list[str]], dict[str, list[tuple]]]:
    """:func:`disputed_deviations`, and for each deviation the pairs of instruments (data names, in the order
    ball bar, probe, R-test) behind its sentences."""
    out: dict[str, list[str]] = {}
    pairs: dict[str, list[tuple]] = {}
    order = list(INSTRUMENT_NAME)
    for _, g in consistency.groups[consistency.groups["verdict"] == "disagree"].iterrows():
        target, source = _roles(g, posteriors)
        pair = tuple(sorted((target.data, source.data), key=order.index))
        rows = reading_groups(target.forward.observations.keys)[g["group"]]
        A = linearisation(target)[0][rows]  # the design of the linear model; a kinematic model's first order
        sd = target.priors.width[: target.p]
        own = [i for i, n in enumerate(target.space.names) if n not in source.space.names]
        B = column_basis(A[:, flat_terms(A, sd, own, target_noise(target)[rows])])
        sentence = (f"{g['group']} given the {g['given']}-only posterior: χ² = {g['chi2']:.1f} on {g['dof']} dof, "
                    f"p = {g['p_value']:.2g}")
        for j, p in enumerate(target.space.parameters):
            if p.group != "deviation":
                continue
            col = A[:, j] * sd[j]  # the deviation's effect at one prior sd, mm
            if B.size:
                col = col - B @ np.linalg.lstsq(B, col, rcond=None)[0]
            if np.abs(col).max() > units.to_internal(0.01, "um"):
                out.setdefault(p.name, []).append(sentence)
                pairs.setdefault(p.name, []).append(pair)
    return out, pairs


@dataclass
class InstrumentCheck:
    """The check of :func:`check_instruments`.

    ``consistency``: both directions of every pair, per reading group; ``scales``: each discrepancy scale's fused
    posterior mean and sd, µm; ``disputed``: the deviations the instruments disagree on, with the verdicts behind
    each; ``conflicts``: per disagreeing pair of instruments (data names), the candidate explanations of its conflict
    (empty when none is explained); ``disputed_pairs``: per disputed deviation the pairs of instruments (data names)
    behind its verdicts."""

    source: str
    consistency: Consistency
    scales: dict[str, tuple[float, float]]
    disputed: dict[str, list[str]]
    conflicts: dict[tuple[str, str], ConflictAnalysis] = field(default_factory=dict)
    disputed_pairs: dict[str, list[tuple]] = field(default_factory=dict)

    @property
    def agree(self) -> bool:
        """Whether no reading group disagrees (the one verdict every sentence of the check follows)."""
        return not self.consistency.disagreeing

    def refusal(self, used) -> str | None:
        """The sentence refusing to compensate with the disputed deviations among ``used`` (None when none is)."""
        hit = [d for d in used if d in self.disputed]
        if not hit:
            return None
        why = self.disputed[hit[0]][0]
        a, b = self.disputed_pairs.get(hit[0], [("ballbar", "probe")])[0]
        return (f"the {INSTRUMENT_NAME[a]} and the {INSTRUMENT_NAME[b]} of {self.source} disagree on {', '.join(hit)} ({why}): "
                "compensating with a deviation the instruments dispute can double the error it should remove; "
                "find out which is right (mtmcal-bayes instruments, docs/probe.md), or accept the disagreement")

    def to_json(self) -> dict:
        return {"campaign": self.source, "agree": self.agree,
                "scales_um": {n: {"mean": m, "sd": s} for n, (m, s) in self.scales.items()},
                "disputed": self.disputed, "consistency": self.consistency.to_json(),
                "explanations": self._explanations_json()}

    def _explanations_json(self) -> dict | None:
        """The explanations' JSON: None when none was weighed; with two instruments the one analysis, with three
        ``{pair: analysis}`` (as the consistency names pairs only then)."""
        if not self.conflicts:
            return None
        if "pair" not in self.consistency.groups:
            return next(iter(self.conflicts.values())).to_json()
        return {_pair_label(*pair): c.to_json() for pair, c in self.conflicts.items()}

    def to_text(self) -> str:
        lines = [f"Campaign: {self.source}", "", self.consistency.to_text(), "",
                 "Fused posterior (linear, exact), each instrument's discrepancy scale: "
                 + ", ".join(f"{SCALE_LABEL[n]} {m:.2f} ± {s:.2f} µm" for n, (m, s) in self.scales.items())]
        if self.disputed:
            lines += ["", "Disputed deviations (compensate refuses them unless the disagreement is accepted):"]
            lines += [f"  {d}: {v[0]}" for d, v in self.disputed.items()]
        elif not self.agree:
            lines += ["", f"The instruments disagree ({', '.join(self.consistency.disagreeing)}), but on no deviation: "
                      "no deviation moves those readings beyond what their flat nuisance terms absorb, so the "
                      "disagreement rests on the readings themselves or their narrower nuisance terms; compensate "
                      "does not refuse, but find the cause (docs/probe.md)."]
        else:
            lines += ["", "The instruments agree on every deviation they both measure."]
        unchecked = list(dict.fromkeys(self.consistency.groups.loc[self.consistency.groups["verdict"] == UNCHECKED,
                                                                   "group"]))
        if unchecked:
            lines.append(f"Not checked: {', '.join(unchecked)} (their broad nuisance terms leave their readings no "
                         "free direction; narrower priors on them would).")
        for conflict in self.conflicts.values():
            lines += ["", conflict.to_text()]
        return "\n".join(lines)


def check_instruments(campaign, *, explain: bool = True) -> InstrumentCheck:
    """The consistency of every pair of the instruments of ``campaign`` (each against the other's posterior) on the
    exact linear posteriors, the fused scales, the disputed deviations and (``explain``) the candidate explanations
    of each disagreeing pair's conflict.  ``campaign`` may be a
    :class:`~mtmcal_bayes.analysis.CampaignAnalysis`, whose cache then serves the linear posteriors."""
    analysis = campaign
    campaign = analysis.campaign if isinstance(analysis, CampaignAnalysis) else analysis
    have = data_instruments("all", campaign)
    if len(have) < 2:
        raise ParameterError("campaign", f"{campaign.source} needs ball-bar runs and touch-probe readings to compare "
                             "the instruments" if "rtest" not in have else f"{campaign.source} needs ball-bar runs or "
                             "touch-probe readings beside its R-test runs to compare the instruments")
    fused_data = next((d for d, used in DATA_INSTRUMENTS.items() if used == have), "all")
    linear = analysis_of(analysis, model="linear", data=fused_data)
    alone = {i: linear.variant(data=i) for i in have}
    checks = {(a, b): instrument_consistency(alone[a], alone[b]) for a, b in combinations(have, 2)}
    cons = pairwise({_pair_label(a, b): c for (a, b), c in checks.items()})
    fused = linear.variant(data=fused_data)
    marginal = fused.marginal
    fused = fused.log_posterior
    posteriors = [alone[i].log_posterior for i in have]
    mean, sd = marginal.sigma_moments(fused.likelihood.y)
    scales = {n: (units.from_internal(mean[k], "um"), units.from_internal(sd[k], "um")) for k, n in
              enumerate(fused.scales)}
    conflicts = {pair: explain_conflict(linear, pair=pair) for pair, check in checks.items()
                 if explain and check.disagreeing}
    disputed, pairs = _disputed(cons, posteriors)
    return InstrumentCheck(campaign.source, cons, scales, disputed, conflicts, pairs)


def blame(scales: dict[str, tuple[float, float]], priors: dict) -> str:
    """Which instrument the fused posterior's discrepancy scales blame for a conflict, and why, in words.

    ``scales``: ``{name: (mean, sd)}`` µm of the fused posterior; ``priors``: ``{name: Prior}``.  A scale whose
    posterior mean is beyond its prior's 95 % quantile is inflated: the model cannot fit that instrument's data
    together with the other's."""
    high = {n: units.from_internal(float(priors[n].frozen().ppf(0.95)), "um") for n in scales}
    inflated = [n for n, (m, _) in scales.items() if m > high[n]]
    shown = ", ".join(f"{SCALE_LABEL[n]} {m:.2f} ± {s:.2f} µm" for n, (m, s) in scales.items())
    if not inflated:
        return (f"Each instrument has its own discrepancy scale ({shown}); neither is beyond its prior's 95 % "
                "quantile: the fused posterior combines data the model fits together.")
    if len(inflated) == len(scales):
        return (f"Each instrument has its own discrepancy scale ({shown}); both are beyond their priors' 95 % "
                "quantiles: the model fits neither instrument's data well, and no instrument is singled out.")
    n = inflated[0]
    other = next(k for k in scales if k != n)
    return (f"Each instrument has its own discrepancy scale ({shown}). The fused posterior blames the "
            f"{'ball bar' if n == 'sigma_model' else 'touch probe'}: its {SCALE_LABEL[n]} is beyond the prior's 95 % "
            f"quantile ({high[n]:.1f} µm), so its data weigh less, while the "
            f"{'touch probe' if n == 'sigma_model' else 'ball bar'}'s readings fit at {SCALE_LABEL[other]}. That "
            "singles out the instrument whose conflicting data are fewer, not necessarily the one that is wrong: "
            "find the cause before trusting the fused intervals (the explanations below, docs/probe.md).")
