"""The thesis machine's parts of the engine's compensation (:mod:`mtmcal_bayes.compensation.compensate`).

* :mod:`.kinematics` — the tool point of its models (``htm-thesis`` or ``htm-literal``) in their model frame, which
  the engine's Newton inverts and whose tool axis gives the tilts;
* :mod:`.printed_method` — thesis Eqs 3.4–3.13 as printed (``method="thesis"``);
* :mod:`.values` — the ball-bar values of Table 4.5 (``values="ballbar"``) and its default posterior;
* :mod:`.compensate` — these as the plug-in hands them to the engine (a set-up's and a mount's lever arms, the NC
  frame);
* :func:`~.verify.resimulate` — the campaign's patterns re-run with compensated commands.
"""
