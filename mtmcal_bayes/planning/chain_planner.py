"""The closed-form planner on a described machine (SPEC §19): :class:`~.design.Planner`'s algebra over the rows
of the machine's chain linearised at zero deviations.

Everything the planner, the design search and the exact preposterior check compute — candidate rows, expected
sds, the σ_model information — rests on four things that depend on the machine: the parameter space, the rows of
a campaign, the target matrix and the candidate runs as campaign runs.  Here they are the described machine's:
its selected deviations (ISO 230-7 names) with the nuisance terms of every set-up and mount, the first order of
:class:`~mtmcal_bayes.models.chain_models.ChainBallbarModel` (complex-step Jacobian, exact to rounding; the `linear`
and `chain` models share it), each target one deviation, and :func:`.chain_candidates.run_of`.

Default targets: the selected deviations the campaign plus every feasible candidate determines one by one
(:func:`~mtmcal_bayes.inference.identifiability.identifiability` of their stacked rows, the T ball centred as in
``axes`` and the report): those no measurement of the catalogue separates are named in
:attr:`DescribedPlanner.not_targeted`, never given a planned sd.
"""

from __future__ import annotations

import copy

import numpy as np

from ..errors import ParameterError
from ..inference.identifiability import CENTRED, identifiability
from ..machines.deviations import quantities, selected
from ..models import DESCRIBED_MODELS, check_model
from ..models.chain_models import ChainBallbarModel, ChainProbeModel, FirstOrderModel
from ..observations import Observations
from ..parameters import ParameterSpace
from .candidates import Candidate
from .chain_candidates import run_of
from .chain_probe_candidates import DescribedProbeCandidate
from .design import Planner


def described_targets(targets, desc) -> list[str]:
    """``targets`` checked against the machine's selected deviations (ISO symbols or names); ParameterError names
    an unknown one."""
    chosen = selected(desc)
    by = {d.name: d.name for d in chosen} | {d.symbol: d.name for d in chosen}
    out = []
    for t in targets:
        if t not in by:
            raise ParameterError("targets", f"unknown quantity {t!r} for this machine (expected one of: "
                                 f"{', '.join(d.name for d in chosen)})")
        out.append(by[t])
    return list(dict.fromkeys(out))


class DescribedPlanner(Planner):
    """:class:`~.design.Planner` on a described machine's campaign (module docstring; same attributes)."""

    def __init__(self, campaign, candidates: list, targets=None, *, sigma_model: float | None = None,
                 model: str = "linear", data: str = "ballbar", sigma_prior=None):
        check_model(model, DESCRIBED_MODELS)
        self.desc = campaign.machine.description
        self.table = quantities(self.desc)
        self.deviations = [d.name for d in selected(self.desc)]
        self._rows_cache: list | None = None
        self.not_targeted: list[str] = []
        super().__init__(campaign, candidates, targets, sigma_model=sigma_model, model=model, data=data,
                         sigma_prior=sigma_prior)

    def _make_space(self, data: str) -> ParameterSpace:
        """The machine's selected deviations, every set-up's and mount's terms (the candidates' too), the probe's own
        terms with probe data and each probe candidate's."""
        probe = (self._probe_terms() if data != "ballbar" else []) + \
            [t for c in self.candidates if isinstance(c, DescribedProbeCandidate) for t in c.terms(self.campaign)]
        return ParameterSpace(list(self._setups), list(self._mounts), self.deviations, probe, table=self.table)

    def _probe_now(self, campaign) -> tuple[np.ndarray, np.ndarray]:
        """The campaign's probe rows (the chain's first order) and their noise without sigma_model_probe, mm²."""
        model = FirstOrderModel(ChainProbeModel(campaign, self.space))
        return model.design, model.observations.noise_variance()

    def _targets_of(self, targets) -> list[str]:
        """``targets`` checked; by default the deviations the campaign and every candidate determine one by one."""
        return self._checked(targets) if targets else self._determinable()

    def _probe_terms(self):
        from ..machines.probe_terms import probe_terms

        return probe_terms(self.desc, self.campaign.probe)

    def _checked(self, targets) -> list[str]:
        return described_targets(targets, self.desc)

    def _unit(self, target: str) -> str:
        return self.table[target].unit

    # ------------------------------------------------------------------ what depends on the machine
    def target_matrix(self, space: ParameterSpace) -> np.ndarray:
        """``T`` (t, P) over ``space``: each target one deviation."""
        T = np.zeros((len(self.targets), len(space)))
        for i, t in enumerate(self.targets):
            T[i, space.index(t)] = 1.0
        return T

    def space_for(self, campaign) -> ParameterSpace:
        """The ball-bar parameter space of ``campaign`` (this machine's; the planner's deviations)."""
        bb = campaign.ballbar
        return ParameterSpace(list(bb.setups), list(bb.mounts), self.deviations, table=self.table)

    def rows_for(self, campaign, space: ParameterSpace) -> np.ndarray:
        """Rows ``(m, P)`` of ``campaign``'s ball-bar runs over ``space``: the chain's first order (both models),
        differentiated in the columns the runs touch only (the deviations, their set-ups' and mounts' terms; the
        other columns are zero)."""
        bb = campaign.ballbar
        if not bb.runs:
            return np.zeros((0, len(space)))
        used = ParameterSpace(list(dict.fromkeys(r.setup for r in bb.runs)),
                              list(dict.fromkeys(r.mount for r in bb.runs)), self.deviations, table=self.table)
        own = FirstOrderModel(ChainBallbarModel(campaign, used)).design
        out = np.zeros((len(own), len(space)))
        out[:, [space.index(n) for n in used.names]] = own
        return out

    def as_run(self, candidate: Candidate):
        return run_of(candidate, self.desc)

    def _design(self, campaign) -> np.ndarray:
        return self.rows_for(campaign, self.space)

    # ------------------------------------------------------------------ rows
    def candidate_rows(self, candidates: list[Candidate] | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
        """For each candidate, its rows ``(k, P)`` and precision weights ``(k,)`` (1/mm²); the planner's own
        candidates' rows made once."""
        if candidates is None or candidates is self.candidates:
            if self._rows_cache is None:
                self._rows_cache = self._rows(self.candidates)
            return self._rows_cache
        return self._rows(candidates)

    def _rows(self, candidates: list) -> list[tuple[np.ndarray, np.ndarray]]:
        """The thesis planner's rows of ball-bar candidates, a probe candidate's from its own run."""
        probe = [i for i, c in enumerate(candidates) if isinstance(c, DescribedProbeCandidate)]
        rest = [i for i in range(len(candidates)) if i not in set(probe)]
        out: list = [None] * len(candidates)
        for i, r in zip(rest, super().candidate_rows([candidates[i] for i in rest]) if rest else []):
            out[i] = r
        for i in probe:
            A, base = candidates[i].rows(self.campaign, self.space, self.deviations, self.table)
            out[i] = (A, 1.0 / (base + self.sigma_probe**2))
        return out

    def _new_run_rows(self, candidates: list[Candidate], length: float):
        """Rows of each new run (bar ``length``), each from a campaign of that run alone — after the campaign's first
        run at its mount, which placed the W ball there (the placement's set-up enters the rows)."""
        first_at: dict[str, object] = {}
        for run in self.campaign.ballbar.runs:
            first_at.setdefault(run.mount, run)
        out = []
        for c in candidates:
            aug = copy.copy(self.campaign)
            bb = copy.copy(self.campaign.ballbar)
            bb.length = length
            bb.setups, bb.mounts = self._setups, self._mounts
            bb.runs = ([first_at[c.mount.id]] if c.mount.id in first_at else []) + [self.as_run(c)]
            aug.ballbar = bb
            design = self.rows_for(aug, self.space)
            keys = Observations.from_campaign(aug).keys
            rows = [i for i, k in enumerate(keys) if k.run == len(bb.runs) - 1]
            out.append((design[rows], np.full(len(rows), 1.0 / self.noise_var(c.repeats))))
        return out

    def _determinable(self) -> list[str]:
        """The selected deviations the campaign and every candidate together determine one by one (the rest in
        :attr:`not_targeted`)."""
        rows = [A for A, _ in self.candidate_rows()] if self.candidates else []
        J = np.vstack([self.A] + rows) if rows or len(self.A) else np.zeros((0, len(self.space)))
        if not len(J):
            self.not_targeted = list(self.deviations)
            return []
        known = [b for b in CENTRED if any(p.base == b for p in self.space.parameters)]
        ident = identifiability(J, self.space, known=known)
        determined = [d for d in self.deviations if d in set(ident.determined)]
        self.not_targeted = [d for d in self.deviations if d not in set(determined)]
        return determined





__all__ = ["DescribedPlanner", "described_targets"]
