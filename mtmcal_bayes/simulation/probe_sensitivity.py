"""What the touch probe can tell: the sensitivity of every probe reading to every deviation and nuisance term,
and which quantities the probe readings alone identify (``docs/probe.md`` is written from these).

Sensitivity: the Jacobian of the ``htm-thesis`` probe model at zero (the ``linear`` probe model), in µm of
reading per ″ (angles) or per µm (lengths).  Identifiability: with every nuisance term left free (a flat
prior), a linear combination ``cᵀθ`` of the deviations is determined by the readings exactly when ``c`` lies
in the row space of the design; a quantity outside it is set by the priors, however many repeats are taken.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .. import units
from ..inference.log_posterior import SAMPLED_DEVIATIONS
from ..models import make_model
from ..parameters import DERIVED, ParameterSpace

#: combinations worth naming: where a deviation is not identified alone, is it in one of these?
COMBINATIONS = {
    **{name: w for name, w in DERIVED.items()},
    "alpha_XB + gamma_XB": {"alpha_XB": 1.0, "gamma_XB": 1.0},
    "alpha_XB + alpha_BT": {"alpha_XB": 1.0, "alpha_BT": 1.0},
}


def probe_design(campaign, deviations=SAMPLED_DEVIATIONS):
    """The linear probe model of ``campaign`` over ``deviations`` and the probe's nuisance terms."""
    space = ParameterSpace.for_campaign(campaign, deviations, data="probe")
    return make_model("linear", campaign, space, data="probe")


def probe_sensitivity_table(campaign, deviations=SAMPLED_DEVIATIONS) -> pd.DataFrame:
    """Rows: probe readings (``X@C90/short``: X at C = 90° with the short stylus); columns: deviations and
    nuisance terms; values: µm of reading per ″ or per µm.  Readings of DPRNT-fitted centres are along the
    principal axes of their fit covariance (``u1..u3``)."""
    model = probe_design(campaign, deviations)
    scale = model.space.display_scale()  # internal units per display unit
    values = units.from_internal(model.design * scale, "um")
    return pd.DataFrame(values, index=model.observations.labels, columns=model.space.names)


def probe_identifiability(campaign, deviations=SAMPLED_DEVIATIONS) -> pd.DataFrame:
    """Per deviation (and the combinations of :data:`COMBINATIONS`): whether the probe readings alone
    determine it with all nuisance terms free, and the share of it outside the design's row space
    (0: determined; 1: no information)."""
    model = probe_design(campaign, deviations)
    A = model.design * model.space.display_scale()
    _, s, vt = np.linalg.svd(A, full_matrices=False)
    basis = vt[s > 1e-9 * s[0]]  # orthonormal basis of the row space
    names = model.space.names
    rows = {}
    targets = {d: {d: 1.0} for d in deviations if d in names}
    targets.update({k: w for k, w in COMBINATIONS.items() if all(d in names for d in w)})
    for label, w in targets.items():
        c = np.zeros(len(names))
        for d, v in w.items():
            c[names.index(d)] = v
        c /= np.linalg.norm(c)
        outside = float(np.linalg.norm(c - basis.T @ (basis @ c)))
        rows[label] = {"identified by the probe alone": outside < 1e-6, "share outside the row space": outside}
    return pd.DataFrame.from_dict(rows, orient="index")
