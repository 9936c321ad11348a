"""The ``linear`` forward model: the thesis relations with nuisance terms (SPEC §3.1).

Thesis Eqs 4.1–4.9 and Table 2.6, first order, with the lever arms of each
run's tool setup (R_B, Z_T, X_T) and W-ball mount (Z_C, R_C)::

    ex_BX = dz_BT + zT − dRB
    ez_BX = dx_BT + R_B·beta_XB + xT          (Table 2.6; Eq 4.2 drops dx_BT)
    ex_BY = −R_B·gamma_XB
    ez_BY = +R_B·alpha_XB
    ex_CR = dx_BT − dx_CZ − Z_T·beta_XB + Z_C·beta_CZ + xT
    ey_CR = −dy_CZ + Z_T·(alpha_XB + alpha_BT) − Z_C·alpha_CZ − X_T·gamma_XB + yT
    ex_CA = +R_C·beta_CZ
    ey_CA = −R_C·alpha_CZ

Being linear, the model is a design matrix ``A`` of shape ``(m, p)``: the
prediction of a batch ``theta`` of shape ``(n, p)`` is ``theta @ A.T``.

The thesis gives no relation for the other patterns (BZ, BR, BT, BA, CT, CX,
CY, CZ); their rows are the Jacobian of the ``htm-thesis`` kinematic model at
zero, whose first-order response equals the relations above.  Like the thesis
relations, the model leaves out the squareness of the linear axes (gamma_XY,
alpha_YZ, beta_YZ; thesis Sec 2.5.3): their columns are zero.  The kinematic
models do respond to them.
"""

from __future__ import annotations

import copy

import numpy as np

from ...observations import Observations
from ...parameters import ParameterSpace, nuisance_name


def linear_coefficients(pattern: str, component: str, setup, mount) -> dict[str, float] | None:
    """Coefficients of one eccentricity component, ``{parameter name: d e / d parameter}``.

    Lengths in mm, angles in rad, so angular coefficients are lever arms in mm.
    ``setup`` and ``mount`` are :class:`~mtmcal_bayes.campaign.Setup` /
    :class:`~mtmcal_bayes.campaign.Mount`; nuisance names carry their ids.
    ``None`` for a pattern the thesis gives no relation for.
    """
    xT, yT, zT, dRB = (nuisance_name(b, setup.id) for b in ("xT", "yT", "zT", "dRB"))
    R_B, Z_T, X_T = setup.R_B, setup.Z_T, setup.X_T
    Z_C, R_C = mount.Z_C, mount.R_C
    table = {
        ("BX", "ex"): {"dz_BT": 1.0, zT: 1.0, dRB: -1.0},
        ("BX", "ez"): {"dx_BT": 1.0, "beta_XB": R_B, xT: 1.0},
        ("BY", "ex"): {"gamma_XB": -R_B},
        ("BY", "ez"): {"alpha_XB": R_B},
        ("CR", "ex"): {"dx_BT": 1.0, "dx_CZ": -1.0, "beta_XB": -Z_T, "beta_CZ": Z_C, xT: 1.0},
        ("CR", "ey"): {"dy_CZ": -1.0, "alpha_XB": Z_T, "alpha_BT": Z_T, "alpha_CZ": -Z_C,
                       "gamma_XB": -X_T, yT: 1.0},
        ("CA", "ex"): {"beta_CZ": R_C},
        ("CA", "ey"): {"alpha_CZ": -R_C},
    }
    return table.get((pattern, component))


#: deviations the thesis relations leave out (columns of zeros in the linear model)
LEFT_OUT = ("gamma_XY", "alpha_YZ", "beta_YZ")


def _kinematic_rows(campaign, space: ParameterSpace, runs: set[int]) -> dict[tuple[int, str], np.ndarray]:
    """Rows ``(p,)`` of the runs ``runs`` (indices into the campaign's ball-bar runs) by ``(run, component)``: the
    htm-thesis model linearised at zero, for the patterns the thesis gives no relation for.  Only those runs are
    simulated, with the run that places each of their mounts' W ball (:func:`~mtmcal_bayes.models.ballbar.placing_runs`):
    the rows are then those of the whole campaign's Jacobian."""
    from ...models.ballbar import placing_runs
    from ...models.jacobian import jacobian
    from .kinematic import HTMModel

    first = placing_runs(campaign.ballbar)
    chosen = sorted(set(runs) | {first[campaign.ballbar.runs[r].mount] for r in runs})
    some = copy.copy(campaign)
    some.ballbar = copy.copy(campaign.ballbar)
    some.ballbar.runs = [campaign.ballbar.runs[r] for r in chosen]
    model = HTMModel(some, "htm-thesis", space)
    J = jacobian(model)
    return {(chosen[k.run], k.component): J[j] for j, k in enumerate(model.observations.keys)}


class LinearModel:
    """Thesis relations as a linear map for the runs of a campaign.

    Parameters
    ----------
    campaign : Campaign
    space : ParameterSpace, optional
        Defaults to all deviations plus the nuisance terms of every setup and mount.
    """

    name = "linear"

    def __init__(self, campaign, space: ParameterSpace | None = None, *, observations: Observations | None = None):
        self.campaign = campaign
        self.space = space or ParameterSpace.for_campaign(campaign)
        self.observations = observations or Observations.from_campaign(campaign)
        bb = campaign.ballbar
        self._names = set(self.space.names)
        A = np.zeros((len(self.observations), len(self.space)))
        kinematic = []  # observations of patterns the thesis gives no relation for
        for i, key in enumerate(self.observations.keys):
            coeffs = linear_coefficients(key.pattern, key.component, bb.setups[key.setup], bb.mounts[key.mount])
            if coeffs is None:
                kinematic.append(i)
            else:
                for name, c in coeffs.items():
                    if name in self._names:  # parameters outside the space are held at zero
                        A[i, self.space.index(name)] = c
        if kinematic:
            rows = _kinematic_rows(campaign, self.space, {self.observations.keys[i].run for i in kinematic})
            for i in kinematic:
                key = self.observations.keys[i]
                A[i] = rows[key.run, key.component]
        for name in LEFT_OUT:
            if name in self.space.names:
                A[:, self.space.index(name)] = 0.0
        self.design = A  # (m, p), mm per internal parameter unit

    def predict(self, theta: np.ndarray) -> np.ndarray:
        """Predicted eccentricities, mm.

        ``theta`` of shape ``(n, p)`` (internal units) gives ``(n, m)``;
        a single vector ``(p,)`` gives ``(m,)``.
        """
        return np.asarray(theta, dtype=float) @ self.design.T

    __call__ = predict
