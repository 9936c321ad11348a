"""Verification by simulation: the campaign's ball-bar patterns re-run with compensated commands."""

from __future__ import annotations

import numpy as np
import pandas as pd

from .... import units
from ..htm import nc_origin
from ....parameters import DEVIATIONS, ParameterSpace
from ..kinematic import HTMModel
from ....compensation.inverse import invert
from .kinematics import ModelFrameKinematics
from .printed_method import compensate_thesis


def resimulate(campaign, theta13: np.ndarray, *, model: str = "htm-thesis", method: str = "exact",
               point: str = "tcp") -> pd.DataFrame:
    """Eccentricities (µm) of every observation before and after compensation, deviations ``theta13`` (13,).

    Each run is compensated for its own tool length (the T ball is the tool point);
    nuisance offsets are zero, so what remains is the machine's.
    """
    space = ParameterSpace.for_campaign(campaign)
    theta = np.zeros((1, len(space)))
    for i, name in enumerate(DEVIATIONS):
        theta[0, space.index(name)] = theta13[i]
    htm = HTMModel(campaign, model, space)
    before = htm.predict(theta)[0]
    d = dict(zip(DEVIATIONS, theta13))
    for i, run in enumerate(htm.runs):
        q, geometry = run.q, htm.kernel.geometry(run.setup, run.mount)
        xyz, bc = np.c_[q["X"], q["Y"], q["Z"]], np.degrees(np.c_[q["B"], q["C"]])
        if method == "exact":  # the engine's Newton through the model, its commands in the model frame
            kin = ModelFrameKinematics(geometry, model, point=point, origin=np.zeros(3))
            xyz_c, _ = invert(kin, q, d)
        else:
            origin = nc_origin(geometry)
            xyz_c = compensate_thesis(d, xyz - origin, bc)[0] + origin
        htm.replace_commands(i, dict(q, X=xyz_c[:, 0], Y=xyz_c[:, 1], Z=xyz_c[:, 2]))
    after = htm.predict(theta)[0]
    return pd.DataFrame({"observation": htm.observations.labels, "before_um": units.from_internal(before, "um"),
                         "after_um": units.from_internal(after, "um")}).set_index("observation")
