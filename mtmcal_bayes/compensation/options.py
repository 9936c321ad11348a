"""The options a machine's compensation is asked with, and the constants of every compensation's result."""

#: how X/Y/Z are found, every name a built-in machine offers: exact inversion of its kinematics (the engine's), or
#: thesis Eqs 3.4–3.13 as printed (the thesis plug-in's); a machine offers the engine's and its plug-ins' own
METHODS = ("exact", "thesis")
#: where the deviations a program is compensated with come from, likewise: the posterior (the engine's), or the
#: deterministic ball-bar values (the thesis plug-in's)
VALUES = ("posterior", "ballbar")
#: which point of the tool is put on the programmed point: the tool centre, or the spindle nose
POINTS = ("tcp", "nose")
#: distance along the tool from the compensated point at which the tilt's position error is stated, mm
OFF_TOOL_MM = 100.0
#: posterior draws for the residual error of a compensated program
N_DRAWS = 1000
#: σ_model, µm, of the closed-form posterior a compensation uses when it is given none
SIGMA_MODEL_UM = 2.0
