"""The thesis machine's parts of the engine's compensation (:mod:`mtmcal_bayes.compensation.compensate`).

* :func:`kinematics` — its published models' tool point in their model frame (:class:`.kinematics.
  ModelFrameKinematics`), which the engine's Newton inverts: ``htm-thesis`` (default) or ``htm-literal``, at the
  lever arms of a set-up and a mount, the program's X/Y/Z in its NC frame (:func:`~..htm.nc_origin`);
* :func:`printed_method` — Eqs 3.4–3.13 as printed (``method="thesis"``, :mod:`.printed_method`);
* :func:`ballbar` — the deterministic ball-bar values (``values="ballbar"``, Table 4.5, :mod:`.values`);
* :func:`.values.default_posterior` — its default posterior: the closed form of the linear model at σ_model 2 µm,
  ball-bar data, 1000 draws.
"""

from __future__ import annotations

import numpy as np

from ....errors import ParameterError
from ....parameters import DEVIATIONS
from ..htm import PIVOTS, Geometry, nc_origin
from .kinematics import ModelFrameKinematics
from .printed_method import compensate_thesis
from .values import ballbar_values


def geometry_for(campaign, setup_id: str | None, mount_id: str | None) -> Geometry:
    """Lever arms of a campaign setup and mount (default: the primary setup, the first mount)."""
    bb = campaign.ballbar
    if setup_id is not None and setup_id not in bb.setups:
        raise ParameterError("setup", f"no setup {setup_id!r} in the campaign (have {', '.join(bb.setups)})")
    if mount_id is not None and mount_id not in bb.mounts:
        raise ParameterError("mount", f"no mount {mount_id!r} in the campaign (have {', '.join(bb.mounts)})")
    s = bb.setups[setup_id] if setup_id else campaign.primary_setup()
    m = bb.mounts[mount_id] if mount_id else next(iter(bb.mounts.values()))
    return Geometry(s.R_B, s.Z_T, s.X_T, m.Z_C, m.R_C)


#: the thesis machine's chain is Eq 2.10 as printed (``htm-literal``; tests/test_ballbar_model.py holds them equal)
CHAIN_IS = {"chain": "htm-literal"}


def kinematics(campaign, *, model: str | None, point: str, setup: str | None,
               mount: str | None) -> ModelFrameKinematics:
    """The tool point of its model ``model`` (default ``htm-thesis``; ``chain``, the machine's chain, is
    ``htm-literal``) at the lever arms of ``setup`` and ``mount`` (default the primary set-up, the first mount), the
    program in its NC frame."""
    model = "htm-thesis" if model is None else CHAIN_IS.get(model, model)
    if model not in PIVOTS:
        raise ParameterError("model", f"{model}: compensation needs a kinematic model of the thesis machine; use "
                             f"{' or '.join(PIVOTS)} (default htm-thesis) or chain (htm-literal)")
    geo = geometry_for(campaign, setup, mount)
    origin = nc_origin(geo)
    info = {"geometry_mm": {"R_B": geo.R_B, "Z_T": geo.Z_T, "X_T": geo.X_T, "Z_C": geo.Z_C},
            "nc_origin_mm": origin.tolist()}
    return ModelFrameKinematics(geo, model, point=point, origin=origin, info=info)


def printed_method(kin: ModelFrameKinematics, values: dict[str, float], program, q) -> np.ndarray:
    """X, Y, Z ``(k, 3)`` mm by Eqs 3.4–3.13 as printed (which correct twice: :mod:`.printed_method`), in the NC
    frame, with the deviations ``values`` ``{thesis name: value}`` (mm, rad; the others zero)."""
    pos = program.positions()
    bc = pos[:, [program.axes.index("B"), program.axes.index("C")]]
    d = {name: values.get(name, 0.0) for name in DEVIATIONS}
    return compensate_thesis(d, pos[:, :3], bc)[0]


def ballbar(campaign) -> dict[str, float]:
    """The deterministic ball-bar values ``{name: value}`` (thesis Table 4.5 on the thesis campaign), mm and rad."""
    return dict(zip(DEVIATIONS, ballbar_values(campaign)))
