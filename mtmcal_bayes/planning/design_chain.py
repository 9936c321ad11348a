"""The design's exact check through the machine's kinematics, where the linear model's first order does not hold.

The design's model is the linear one (the rows of :meth:`.design.Planner.rows_for`, a kinematic model's first order
at zero deviations; a probe or R-test run's :meth:`~.probe_catalogue.ProbeCandidate.rows`, the first order of its
probe or R-test model through the chain), and so is the posterior that ``sample --sampler exact`` gives a measured
campaign.  The machine itself is not linear: at deviations drawn from their priors (a new machine's, up to minutes of
arc and tenths of a millimetre) its kinematic models — the ball bar's: the chain on a described machine, the
plug-in's on the thesis machine (:func:`~mtmcal_bayes.models.default_kinematic_model`; a kinematic ``--model``
itself); the probe's and the R-test's: the chain, with every nuisance term (stylus, sphere, nest, zero) — read the
design's runs differently from the rows.  Where that misfit is large, the check's simulated machines are measured
through the kinematic models (:func:`kinematic_means`, every instrument's readings) and still inferred with the exact
linear posterior, so that the share of machines meeting a target is the share the real kinematics give.

**When.**  The misfit of a drawn machine θ is the largest ``|f(θ) − A θ|`` over the design's new readings (mm: ball
bar, probe and R-test alike); its :data:`~.design_problem.PROMISE` quantile over the check's machines (drawn from the
priors on a new machine, from today's posterior otherwise) is compared with the smaller of

* the smallest accuracy of the instruments that read the new runs (:func:`accuracy`: the ball bar's, the probe's and
  the R-test's repeatability): above the ball bar's the first order is refused elsewhere too (``sample``'s and
  ``simulate``'s warning, :func:`~mtmcal_bayes.models.first_order_gap`);
* :data:`MISFIT_FRACTION` of the smallest target in reading units: the largest change of a new reading when the
  targeted quantity moves by its target sd (``max |A T_tᵀ| s_t``).  A misfit of that fraction of a target can move
  its estimate, and σ_model's posterior that sets its sd, by about as much — the room the search leaves a kept
  promise (:data:`~.design_make.LOOSEN_ABOVE`).

The quantile, not the mean: the promise is about 90 % of machines, and the worst tenth decides it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import units
from ..models import CHAIN, build_model, default_kinematic_model
from ..models.probe import DEFAULT_REPEATABILITY
from .design_problem import PROMISE

#: the check goes through the kinematics where the misfit exceeds this fraction of the smallest target, in reading
#: units (or the instruments' smallest accuracy, whichever is smaller)
MISFIT_FRACTION = 0.1


@dataclass(frozen=True)
class Kinematics:
    """How the check simulated its machines: ``through`` the kinematic ``model`` (the models of the instruments that
    read the new runs, ``"htm-thesis and chain"`` where they differ) or not, the misfit (µm, the
    :data:`~.design_problem.PROMISE` quantile over the machines of the largest misfit over the new readings; NaN
    where not computed: no designed run, or the linear rows forced) and the ``threshold`` (µm) it was held
    against."""

    model: str
    through: bool
    misfit_um: float
    threshold_um: float

    def document(self) -> dict:
        """The ``check_kinematics`` of ``design --json``."""
        misfit = round(self.misfit_um, 4) if np.isfinite(self.misfit_um) else None
        return {"model": self.model, "through": self.through, "misfit_um": misfit,
                "threshold_um": round(self.threshold_um, 4)}

    def line(self) -> str:
        """The line of the text output (empty where the check used the linear model)."""
        if not self.through:
            return ""
        models = "models" if " and " in self.model else "model"
        return (f"exact check: the simulated machines measured through the {self.model} {models} (the linear model "
                f"misses its readings by up to {self.misfit_um:.3g} µm on {PROMISE:.0%} of them, above "
                f"{self.threshold_um:.3g} µm), inferred with the linear model")


def accuracy(campaign, instrument: str) -> float:
    """The accuracy of one reading of ``instrument`` (mm): the ball bar's, the probe's repeatability, the R-test's
    (:data:`~mtmcal_bayes.models.probe.DEFAULT_REPEATABILITY` where it states none)."""
    if instrument == "probe":
        return float(campaign.probe.repeatability)
    if instrument == "rtest":
        sd = campaign.rtest.repeatability
        return float(sd if sd is not None else DEFAULT_REPEATABILITY)
    return float(campaign.ballbar.accuracy)


def threshold(planner, A_new: np.ndarray, T: np.ndarray, targets: np.ndarray | None, *,
              instruments=("ballbar",)) -> float:
    """The misfit (mm) above which the check goes through the kinematics: the smallest accuracy of the
    ``instruments`` that read the new rows (:func:`accuracy`), or :data:`MISFIT_FRACTION` of the smallest finite
    target of ``targets`` (t,) (display units) in reading units over the new rows ``A_new`` (m_new, P) and the target
    weights ``T`` (t, P), whichever is smaller."""
    out = min(accuracy(planner.campaign, i) for i in (instruments or ("ballbar",)))
    if targets is None or not len(A_new):
        return out
    for i, tg in enumerate(np.asarray(targets, float)):
        if np.isfinite(tg):
            s = units.to_internal(float(tg), planner.target_units[i])
            reading = float(np.abs(A_new @ T[i]).max()) * s
            if reading > 0.0:
                out = min(out, MISFIT_FRACTION * reading)
    return out


def _model_name(planner, instruments) -> str:
    """The kinematic models that read ``instruments``: the ball bar's the planner's kinematic model (its default
    where the planner's is the linear one), the probe's and the R-test's the chain (what their rows are the first
    order of)."""
    bar = planner.model if planner.model != "linear" else default_kinematic_model(planner.campaign.machine)
    names = [bar if i == "ballbar" else CHAIN for i in (instruments or ("ballbar",))]
    return " and ".join(dict.fromkeys(names))


def _kinematic(planner, aug, theta: np.ndarray, *, space, new_bar: np.ndarray, others) -> np.ndarray:
    """The kinematic models' readings ``(n, m_new)`` mm of the machines ``theta`` (n, P) over ``space``: the ball
    bar's new readings (``new_bar`` over ``aug``'s ball-bar observations) through its kinematic model, then each
    probe or R-test run of ``others`` through its own (:meth:`~.probe_catalogue.ProbeCandidate.model`)."""
    out = []
    if new_bar.any():
        bar_space = planner.space_for(aug)
        cols = [space.index(n) for n in bar_space.names]
        model = build_model(_model_name(planner, ["ballbar"]), aug, bar_space)
        out.append(np.asarray(model.predict(theta if cols == list(range(len(space))) else theta[:, cols]),
                              float)[:, new_bar])
    for c in others:
        model = c.model(planner.campaign, planner.deviations, planner.table)
        out.append(np.asarray(model.predict(theta[:, [space.index(n) for n in model.space.names]]), float))
    return np.hstack(out) if out else np.zeros((len(theta), 0))


def linear_kinematics(planner, A_new: np.ndarray, T: np.ndarray, targets: np.ndarray | None, *,
                      instruments=("ballbar",)) -> Kinematics:
    """The record of a check made through the linear rows ``A_new`` (m_new, P) alone (as forced), with the threshold
    it would have been held against (``T`` (t, P) the targets' weights over the same columns, ``instruments`` those
    that read the new rows)."""
    return Kinematics(_model_name(planner, instruments), False, float("nan"),
                      units.from_internal(threshold(planner, A_new, T, targets, instruments=instruments),
                                          "um"))


def kinematic_means(planner, aug, theta: np.ndarray, A: np.ndarray, *, new: np.ndarray, space=None, others=(),
                    instrument=None, targets: np.ndarray | None = None,
                    through: bool | None = None) -> tuple[np.ndarray, Kinematics]:
    """The new readings' means ``(n, m_new)`` mm of the machines ``theta`` (n, P) over ``space`` (default the
    planner's space of the augmented campaign ``aug``, :meth:`.design.Planner.space_for`): the rows ``A`` (m, P) where
    the misfit stays below :func:`threshold` of ``targets`` (t,), else the kinematic models' predictions (vectorised
    over the machines).  ``A`` holds ``aug``'s ball-bar rows, then those of the probe and R-test runs ``others`` (as
    measured: :attr:`.design_runs.DesignedRun.measured`) in order; ``instrument`` (m,) names each row's instrument
    (default: all the ball bar's); ``new`` (m,) marks the designed runs' readings; ``through`` forces the choice
    (None: by the misfit)."""
    space = space if space is not None else planner.space_for(aug)
    instrument = np.asarray(["ballbar"] * len(A) if instrument is None else instrument)
    used = list(dict.fromkeys(instrument[new]))
    T = planner.target_matrix(space)
    linear = theta @ A[new].T
    if not new.any() or through is False:
        return linear, linear_kinematics(planner, A[new], T, targets, instruments=used)
    bar = instrument == "ballbar"
    with np.errstate(all="ignore"):  # an absurd draw overflows: its misfit is then infinite and the chain is used
        kinematic = _kinematic(planner, aug, theta, space=space, new_bar=new[bar], others=others)
    gap = np.abs(kinematic - linear).max(axis=1)
    misfit = float(np.quantile(np.where(np.isfinite(gap), gap, np.inf), PROMISE))
    limit = threshold(planner, A[new], T, targets, instruments=used)
    use = misfit > limit if through is None else True
    return (kinematic if use else linear), Kinematics(_model_name(planner, used), bool(use),
                                                      units.from_internal(misfit, "um"),
                                                      units.from_internal(limit, "um"))


__all__ = ["Kinematics", "MISFIT_FRACTION", "accuracy", "kinematic_means", "linear_kinematics", "threshold"]
