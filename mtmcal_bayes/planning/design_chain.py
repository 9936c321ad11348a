"""The design's exact check through the machine's kinematics, where the linear model's first order does not hold.

The design's model is the linear one (the rows of :meth:`.design.Planner.rows_for`, a kinematic model's first order
at zero deviations), and so is the posterior that ``sample --sampler exact`` gives a measured campaign.  The machine
itself is not linear: at deviations drawn from their priors (a new machine's, up to minutes of arc and tenths of a
millimetre) its kinematic model — the chain on a described machine, the plug-in's on the thesis machine
(:func:`~mtmcal_bayes.models.default_kinematic_model`; a kinematic ``--model`` itself) — reads the design's runs
differently from the rows.  Where that misfit is large, the check's simulated machines are measured through the
kinematic model (:func:`kinematic_means`) and still inferred with the exact linear posterior, so that the share of
machines meeting a target is the share the real kinematics give.

**When.**  The misfit of a drawn machine θ is the largest ``|f(θ) − A θ|`` over the design's new readings (mm);
its :data:`~.design_problem.PROMISE` quantile over the check's machines (drawn from the priors on a new machine,
from today's posterior otherwise) is compared with the smaller of

* the ball bar's accuracy: above it the first order is refused elsewhere too (``sample``'s and ``simulate``'s
  warning, :func:`~mtmcal_bayes.models.first_order_gap`);
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
from ..models import build_model, default_kinematic_model
from .design_problem import PROMISE

#: the check goes through the kinematics where the misfit exceeds this fraction of the smallest target, in reading
#: units (or the ball bar's accuracy, whichever is smaller)
MISFIT_FRACTION = 0.1


@dataclass(frozen=True)
class Kinematics:
    """How the check simulated its machines: ``through`` the kinematic ``model`` or not, the misfit (µm, the
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
        return (f"exact check: the simulated machines measured through the {self.model} model (the linear model "
                f"misses its readings by up to {self.misfit_um:.3g} µm on {PROMISE:.0%} of them, above "
                f"{self.threshold_um:.3g} µm), inferred with the linear model")


def threshold(planner, A_new: np.ndarray, T: np.ndarray, targets: np.ndarray | None) -> float:
    """The misfit (mm) above which the check goes through the kinematics: the ball bar's accuracy, or
    :data:`MISFIT_FRACTION` of the smallest finite target of ``targets`` (t,) (display units) in reading units over
    the new rows ``A_new`` (m_new, P) and the target weights ``T`` (t, P), whichever is smaller."""
    out = float(planner.campaign.ballbar.accuracy)
    if targets is None or not len(A_new):
        return out
    for i, tg in enumerate(np.asarray(targets, float)):
        if np.isfinite(tg):
            s = units.to_internal(float(tg), planner.target_units[i])
            reading = float(np.abs(A_new @ T[i]).max()) * s
            if reading > 0.0:
                out = min(out, MISFIT_FRACTION * reading)
    return out


def linear_kinematics(planner, A_new: np.ndarray, T: np.ndarray, targets: np.ndarray | None) -> Kinematics:
    """The record of a check made through the linear rows ``A_new`` (m_new, P) alone (a design with touch-probe or
    R-test runs: their readings through the kinematics are not simulated yet), with the threshold it would have been
    held against (``T`` (t, P) the targets' weights over the same columns)."""
    name = planner.model if planner.model != "linear" else default_kinematic_model(planner.campaign.machine)
    return Kinematics(name, False, float("nan"), units.from_internal(threshold(planner, A_new, T, targets), "um"))


def kinematic_means(planner, aug, theta: np.ndarray, A: np.ndarray, *, new: np.ndarray,
                    targets: np.ndarray | None = None, through: bool | None = None) -> tuple[np.ndarray, Kinematics]:
    """The new readings' means ``(n, m_new)`` mm of the machines ``theta`` (n, P) over the planner's space of the
    augmented campaign ``aug`` (:meth:`.design.Planner.space_for`): the rows ``A`` (m, P) where the misfit stays
    below :func:`threshold` of ``targets`` (t,), else the kinematic model's predictions (vectorised over the
    machines).  ``new`` (m,) marks the designed runs' readings; ``through`` forces the choice (None: by the
    misfit)."""
    space = planner.space_for(aug)
    linear = theta @ A[new].T
    name = planner.model if planner.model != "linear" else default_kinematic_model(planner.campaign.machine)
    if not new.any() or through is False:
        return linear, Kinematics(name, False, float("nan"), units.from_internal(threshold(planner, A[new], planner.target_matrix(
            space), targets), "um"))
    model = build_model(name, aug, space)
    with np.errstate(all="ignore"):  # an absurd draw overflows: its misfit is then infinite and the chain is used
        kinematic = np.asarray(model.predict(theta), float)[:, new]
    gap = np.abs(kinematic - linear).max(axis=1)
    misfit = float(np.quantile(np.where(np.isfinite(gap), gap, np.inf), PROMISE))
    limit = threshold(planner, A[new], planner.target_matrix(space), targets)
    use = misfit > limit if through is None else True
    return (kinematic if use else linear), Kinematics(name, bool(use), units.from_internal(misfit, "um"),
                                                      units.from_internal(limit, "um"))


__all__ = ["Kinematics", "MISFIT_FRACTION", "kinematic_means", "linear_kinematics", "threshold"]
