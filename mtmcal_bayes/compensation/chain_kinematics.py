"""The tool point of a machine through its description's chain: the engine's kinematics of a compensation.

A program's words are the axes' positions (X, Y, Z mm; the rotary axes' by their letters, rad here), as the
description's commands are (:mod:`mtmcal_bayes.machines.chain`).  The tool point — the tool centre ``length`` mm
along the spindle from its ``point_mm`` — is taken down the tool side to the bed and back up the workpiece side
(:meth:`~mtmcal_bayes.machines.chain.Chain.work_frame`): where it sits on the workpiece, as its place at the home
pose.  With no deviations that is the programmed point.

Shapes: ``k`` blocks, ``n`` draws (or single-deviation rows); deviation values ``{name: (n,)}`` in mm and rad;
points ``(n, k, 3)`` mm.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..machines.chain import Chain
from ..machines.deviations import generated
from ..machines.patterns import tool_home


def work_tool_point(chain: Chain, length: float, q: dict[str, np.ndarray], dev: dict[str, np.ndarray], *,
                    n: int = 1) -> np.ndarray:
    """Tool point ``(n, k, 3)`` mm in the workpiece frame for commands ``q`` ``{letter: (k,) or (n, k)}`` (mm, rad)
    and deviation values ``dev`` ``{name: (n,)}`` (``{}``: the nominal machine), a tool ``length`` mm long."""
    k = max(np.shape(v)[-1] for v in q.values())
    t = np.broadcast_to(tool_home(chain.desc, length), (n, k, 3)).copy()
    return chain.work_frame(chain.tool_point(t, q, dev), q, dev)


class ChainKinematics:
    """The tool point ``length`` mm along the spindle through ``chain`` (see :mod:`.inverse` for the interface)."""

    model = "chain"

    def __init__(self, chain: Chain, length: float, info: dict | None = None):
        self.chain, self.length, self.info = chain, float(length), dict(info or {})

    def tool_point(self, q, dev, *, n: int = 1) -> np.ndarray:
        return work_tool_point(self.chain, self.length, q, dev, n=n)

    def tool_axis(self, q, dev, *, n: int = 1) -> np.ndarray:
        """The unit vector from the tool point to the point 1 mm further along the tool."""
        v = work_tool_point(self.chain, self.length + 1.0, q, dev, n=n) - self.tool_point(q, dev, n=n)
        return v / np.linalg.norm(v, axis=-1, keepdims=True)


def tool_length(campaign, setup: str | None) -> tuple[float, str]:
    """The programmed tool length (mm) of a ball-bar set-up (default the campaign's first) and its id."""
    setups = campaign.ballbar.setups
    if not setups:
        raise ParameterError("setup", f"{campaign.source} has no ball-bar set-up to take the tool length from")
    if setup is not None and setup not in setups:
        raise ParameterError("setup", f"no setup {setup!r} in the campaign (have {', '.join(setups)})")
    sid = setup or next(iter(setups))
    return float(setups[sid].R_B), sid


def chain_kinematics(campaign, *, model: str | None, point: str, setup: str | None,
                     mount: str | None) -> ChainKinematics:
    """The engine's kinematics of ``campaign``'s machine: its chain with every generated deviation, the tool as long
    as the ball-bar ``setup``'s (``point="nose"``: length 0, the spindle's ``point_mm``).  ``model`` must be the
    chain (or None) and ``mount`` None: the workpiece frame is the description's."""
    desc = campaign.machine.description
    where = f"{desc.name}, {desc.configuration}"
    if model not in (None, "chain"):
        raise ParameterError("model", f"{model}: {where} is compensated through its chain (chain, the default)")
    if mount is not None:
        raise ParameterError("mount", f"not used on {where}: its workpiece frame is the description's")
    length, sid = tool_length(campaign, setup)
    length = length if point == "tcp" else 0.0
    return ChainKinematics(Chain(desc, generated(desc)), length, {"tool_length_mm": length, "setup": sid})
