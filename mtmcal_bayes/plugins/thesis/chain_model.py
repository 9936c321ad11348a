"""The ``chain`` model on the thesis campaign format: thesis patterns and set-ups through the described chain.

The runs, angle grids, dummy-sphere placements and eccentricity extraction are those of
:class:`~.kinematic.HTMModel` (thesis Tables 2.2/2.3); only the kinematics differ: the tool ball and the W
ball go through :class:`~.chain.Chain` of the campaign's machine description (the built-in
``integrex-i200``: the thesis' ``htm-literal``, which the tests hold to 1e-9 mm).
"""

from __future__ import annotations

import numpy as np

from ...io.machine_reader import description_of
from ...machines.deviations import generated
from ...parameters import MOUNT_NUISANCE
from ...models.chain import Chain
from .htm import HTM_LITERAL, _column
from .kinematic import HTMModel


class ThesisChainModel(HTMModel):
    """Ball-bar model ``chain`` of a thesis-format campaign: ``(n, p)`` -> ``(n, m)`` eccentricities, mm."""

    def __init__(self, campaign, space=None, *, description=None, **kw):
        super().__init__(campaign, HTM_LITERAL, space, **kw)
        self.name = "chain"
        desc = description if description is not None else description_of(campaign.machine)
        self.chain = Chain(desc, generated(desc))

    def _dL(self, theta: np.ndarray) -> np.ndarray:
        pts = self._point_table()
        ext = np.concatenate([theta, np.zeros((len(theta), 1))], axis=1)  # column -1 holds zero
        dev = {d: ext[:, c] for d, c in pts.deviation_cols.items() if c >= 0}
        nui = {b: _column(ext[:, c]) for b, c in pts.setup_cols.items()}  # (n, k)
        t_off = np.stack([nui["xT"], nui["yT"], nui["zT"]], axis=-1) * (~pts.dummy)[None, :, None]
        w_off = np.stack([ext[:, pts.mount_cols[b]] for b in MOUNT_NUISANCE], axis=-1)  # (n, k, 3)
        q = {"X": pts.cmd.X, "Y": pts.cmd.Y, "Z": pts.cmd.Z, "B": pts.cmd.B, "C": pts.cmd.C}
        length = pts.geometry.R_B + nui["dRB"]
        return (self.chain.ballbar_lengths(length, t_off, q, placement=pts.placement, w_off=w_off, dev=dev)
                - self.campaign.ballbar.length)
