"""``probe-fit``: the sphere through the probed points of a DPRNT file, on any machine.

* :func:`probe_fit` — least-squares sphere fit of DPRNT probe output (thesis Fig 5.13's format).

The thesis' deterministic identification (Eqs 4.10–4.18, 5.1–5.19) is the thesis plug-in's
(``mtmcal_bayes.plugins.thesis.identification``): the engine asks a machine for it (its ``identify``).
"""

from __future__ import annotations

from .probe_fit import ProbeFit, probe_fit

__all__ = ["ProbeFit", "probe_fit"]
