"""The thesis machine's compensation of NC programs (its ``compensate`` contribution).

* :func:`~.compensate.compensate` — rewrite X/Y/Z so the tool point reaches the programmed point: exact Newton
  inversion of its kinematic model (``htm-thesis`` or ``htm-literal``, :mod:`.kinematics`) or thesis Eqs
  3.4–3.13 as printed (:mod:`.printed_method`), with the posterior or the ball-bar values of Table 4.5
  (:mod:`.values`); the residual error from posterior draws, the tool tilts X/Y/Z cannot correct.
* :func:`~.verify.resimulate` — the campaign's patterns re-run with compensated commands.
"""
