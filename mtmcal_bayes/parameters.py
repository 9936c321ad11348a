"""Canonical names, units and meanings of the model parameters (SPEC §1).

Three groups of quantities appear everywhere in the package:

* the 13 geometric deviations of thesis Table 2.1 (:data:`DEVIATIONS`);
* the eight quantities the thesis ball-bar procedure identifies
  (:data:`IDENTIFIABLE`), seven of them deviations and one the combination
  ``dx_CZ_minus_dx_BT``: a derived quantity, a weighted sum of deviations
  defined once in :data:`DERIVED` (every consumer asks :func:`weights` or
  :func:`combine`);
* nuisance quantities of the instrument set-up: per tool setup of the
  spindle-side (T) ball its centre offset ``xT, yT, zT`` and the tool-length
  error ``dRB``; per mount of the workpiece-side (W) ball its offset
  ``xW, yW, zW``.

:class:`ParameterSpace` orders them into the parameter vector that forward
models take, shape ``(n, p)``, in internal units (mm, rad).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import units


@dataclass(frozen=True)
class Quantity:
    """A named quantity with its kind (``"angle"`` or ``"length"``) and meaning."""

    name: str
    kind: str
    meaning: str

    @property
    def unit(self) -> str:
        """Display unit: ``"arcsec"`` for angles, ``"um"`` for lengths."""
        return "arcsec" if self.kind == "angle" else "um"


_DEVIATION_TABLE = [
    ("dx_BT", "length", "X offset of the spindle axis from the B-axis origin"),
    ("dz_BT", "length", "Z offset of the spindle axis from the B-axis origin"),
    ("alpha_BT", "angle", "squareness of the B axis to the spindle axis, about X"),
    ("alpha_XB", "angle", "squareness of the B axis to the Z motion, about X"),
    ("beta_XB", "angle", "initial angular position (zero) error of the B axis"),
    ("gamma_XB", "angle", "squareness of the B axis to the X motion, about Z"),
    ("gamma_XY", "angle", "squareness of the X and Y motions"),
    ("alpha_YZ", "angle", "squareness of the Y and Z motions"),
    ("beta_YZ", "angle", "squareness of the Z and X motions"),
    ("dx_CZ", "length", "X offset of the C axis from the machine origin"),
    ("dy_CZ", "length", "Y offset of the C axis from the machine origin"),
    ("alpha_CZ", "angle", "parallelism of the C axis to Z, about X"),
    ("beta_CZ", "angle", "parallelism of the C axis to Z, about Y"),
]

#: the 13 geometric deviations of thesis Table 2.1, by canonical name
DEVIATIONS: dict[str, Quantity] = {n: Quantity(n, k, m) for n, k, m in _DEVIATION_TABLE}

#: the eight quantities identified by the thesis ball-bar procedure (Table 4.5 order)
IDENTIFIABLE: tuple[str, ...] = (
    "alpha_CZ", "beta_CZ", "alpha_XB", "beta_XB",
    "gamma_XB", "alpha_BT", "dx_CZ_minus_dx_BT", "dy_CZ",
)

#: derived quantities: name -> {deviation: weight}; the value is Σ weight · deviation (same kind for all)
DERIVED: dict[str, dict[str, float]] = {
    "dx_CZ_minus_dx_BT": {"dx_CZ": 1.0, "dx_BT": -1.0},
}

#: every named quantity: deviations plus the derived ones
QUANTITIES: dict[str, Quantity] = {
    **DEVIATIONS,
    "dx_CZ_minus_dx_BT": Quantity("dx_CZ_minus_dx_BT", "length", "dx_CZ − dx_BT, the C-axis X offset relative to the spindle"),
}

#: the model-discrepancy scale of the ball bar's eccentricities (SPEC §5), sampled beside the parameters
SIGMA_MODEL = Quantity("sigma_model", "length", "sd of what the model leaves out of the ball-bar eccentricities "
                       "(dynamics, thermal drift, pitch error)")
#: the touch probe's own discrepancy scale (SPEC §17): a conflict between the instruments widens the one that causes it
SIGMA_MODEL_PROBE = Quantity("sigma_model_probe", "length", "sd of what the model leaves out of the touch-probe "
                             "readings (thermal drift between indexed positions, stylus bending, pre-travel lobing)")
#: the R-test's own discrepancy scale (SPEC §22), like the probe's
SIGMA_MODEL_RTEST = Quantity("sigma_model_rtest", "length", "sd of what the model leaves out of the R-test "
                             "readings (thermal drift between positions, sensor non-linearity, the sphere's form)")
#: the discrepancy scale of each instrument's observations, by instrument
DISCREPANCY_SCALES: dict[str, Quantity] = {"ballbar": SIGMA_MODEL, "probe": SIGMA_MODEL_PROBE,
                                           "rtest": SIGMA_MODEL_RTEST}
#: what each scale is called in sentences
SCALE_LABEL = {"sigma_model": "σ_model (ball bar)", "sigma_model_probe": "σ_model (probe)",
               "sigma_model_rtest": "σ_model (R-test)"}

#: which measurements a likelihood uses (``data``), by value: the instruments of each, in the order of the
#: observation vector; ``"both"`` keeps its meaning (ball bar and probe), ``"all"`` is every instrument the campaign
#: has (:func:`data_instruments`)
DATA_INSTRUMENTS: dict[str, tuple[str, ...] | None] = {
    "ballbar": ("ballbar",), "probe": ("probe",), "both": ("ballbar", "probe"), "rtest": ("rtest",),
    "ballbar+rtest": ("ballbar", "rtest"), "probe+rtest": ("probe", "rtest"), "all": None}


def data_instruments(data: str, campaign=None) -> tuple[str, ...]:
    """The instruments whose observations the likelihood of ``data`` (a key of :data:`DATA_INSTRUMENTS`) uses:
    ``"all"`` the ones ``campaign`` has readings of (every instrument without a campaign)."""
    fixed = DATA_INSTRUMENTS[data]
    if fixed is not None:
        return fixed
    if campaign is None:
        return ("ballbar", "probe", "rtest")
    has = {"ballbar": bool(campaign.ballbar.runs), "probe": campaign.has_probe_readings(),
           "rtest": campaign.has_rtest_readings()}
    return tuple(i for i, ok in has.items() if ok)


def ballbar_probe_data(instruments) -> str | None:
    """The ``data`` value (``"ballbar"``, ``"probe"``, ``"both"``) of the ball-bar and probe part of
    ``instruments``, None where they have neither: what a machine's own models (a plug-in's) are asked for."""
    have = tuple(i for i in ("ballbar", "probe") if i in instruments)
    return {("ballbar",): "ballbar", ("probe",): "probe", ("ballbar", "probe"): "both"}.get(have)


def is_scale(name: str) -> bool:
    """Whether ``name`` is a discrepancy scale (``sigma_model``, ``sigma_model_probe``)."""
    return name in SCALE_LABEL


def weights(name: str, available=None) -> dict[str, float]:
    """Deviation weights of a quantity: ``{name: 1.0}``, or the definition of a derived one.

    ``available`` (names of the parameters a posterior has) drops the weights
    of deviations held at zero, such as ``dx_BT`` under the thesis assumption.
    """
    w = dict(DERIVED.get(name, {name: 1.0}))
    if available is not None:
        have = set(available)
        w = {k: v for k, v in w.items() if k in have}
    return w


def combine(name: str, values) -> np.ndarray:
    """Value of a derived quantity from ``values`` (``{deviation: array}``, one unit for all; absent = 0)."""
    return sum(v * values[k] for k, v in DERIVED[name].items() if k in values)

#: nuisance quantities of each tool setup (T-side ball offset and tool-length error)
SETUP_NUISANCE: dict[str, Quantity] = {
    "xT": Quantity("xT", "length", "T-ball centre offset along X of the spindle frame"),
    "yT": Quantity("yT", "length", "T-ball centre offset along Y of the spindle frame"),
    "zT": Quantity("zT", "length", "T-ball centre offset along Z of the spindle frame"),
    "dRB": Quantity("dRB", "length", "tool-length error, true minus programmed R_B"),
}

#: nuisance quantities of each W-ball mount (offset in the C-axis frame)
MOUNT_NUISANCE: dict[str, Quantity] = {
    "xW": Quantity("xW", "length", "W-ball mounting offset along X of the C-axis frame"),
    "yW": Quantity("yW", "length", "W-ball mounting offset along Y of the C-axis frame"),
    "zW": Quantity("zW", "length", "W-ball mounting offset along Z of the C-axis frame"),
}


#: nuisance quantities of each touch-probe stylus (its tool point is the stylus-ball centre, like the T ball's)
STYLUS_NUISANCE: dict[str, Quantity] = {
    "xS": Quantity("xS", "length", "stylus-ball centre offset along X of the spindle frame"),
    "yS": Quantity("yS", "length", "stylus-ball centre offset along Y of the spindle frame"),
    "zS": Quantity("zS", "length", "stylus-ball centre offset along Z (a described machine whose spindle is not "
                   "along Z)"),
    "dRS": Quantity("dRS", "length", "stylus tool-length error, true minus programmed"),
    "rS": Quantity("rS", "length", "effective stylus-ball radius error (pre-travel): moves a probed sphere "
                   "centre along the stylus axis, towards the spindle"),
}

#: nuisance quantities of a probed sphere: its placement on the C table (C frame), and the datum of the
#: readings (where the sphere is in the reading frame; broad: readings are often zeroed on the sphere)
SPHERE_NUISANCE: dict[str, Quantity] = {
    "xP": Quantity("xP", "length", "sphere placement on the C table, radial (C frame, X at C = 0)"),
    "yP": Quantity("yP", "length", "sphere placement on the C table, tangential (C frame, Y at C = 0)"),
    "zP": Quantity("zP", "length", "sphere placement along Z on the workpiece side (a described machine)"),
    "xD": Quantity("xD", "length", "reading datum along X: sphere position / zero of the reading frame"),
    "yD": Quantity("yD", "length", "reading datum along Y: sphere position / zero of the reading frame"),
    "zD": Quantity("zD", "length", "reading datum along Z: sphere position / zero of the reading frame"),
}

#: every touch-probe nuisance quantity, by base name
PROBE_NUISANCE: dict[str, Quantity] = {**STYLUS_NUISANCE, **SPHERE_NUISANCE}

#: nuisance quantities of the R-test (SPEC §22): per run its sensors' zero (``zero = "first"``), per placement the
#: sphere's placement error, per nest its length error and its centre's offset across the spindle
RTEST_NUISANCE: dict[str, Quantity] = {
    "xZR": Quantity("xZR", "length", "R-test zero of a run along the sensors' first axis (X at the home pose)"),
    "yZR": Quantity("yZR", "length", "R-test zero of a run along the sensors' second axis (Y at the home pose)"),
    "zZR": Quantity("zZR", "length", "R-test zero of a run along the sensors' third axis (Z at the home pose)"),
    "xPR": Quantity("xPR", "length", "R-test sphere placement along X, workpiece side at the home pose"),
    "yPR": Quantity("yPR", "length", "R-test sphere placement along Y, workpiece side at the home pose"),
    "zPR": Quantity("zPR", "length", "R-test sphere placement along Z, workpiece side at the home pose"),
    "xNR": Quantity("xNR", "length", "R-test nest centre offset along X of the spindle frame"),
    "yNR": Quantity("yNR", "length", "R-test nest centre offset along Y of the spindle frame"),
    "zNR": Quantity("zNR", "length", "R-test nest centre offset along Z of the spindle frame"),
    "dLR": Quantity("dLR", "length", "R-test nest length error, true minus stated (+ = longer)"),
}

#: what each nuisance base name stands for, in a calibration engineer's words (for sentences naming a prior)
NUISANCE_MEANING: dict[str, str] = {
    "xT": "T-ball centring, X", "yT": "T-ball centring, Y", "zT": "T-ball centre along the spindle axis",
    "dRB": "tool-length error, dial gauge", "xW": "W-ball clamping, X", "yW": "W-ball clamping, Y",
    "zW": "W-ball clamping, Z", "xS": "stylus centring, X", "yS": "stylus centring, Y",
    "zS": "stylus centring, Z", "zP": "sphere placement, Z", "dRS": "stylus length", "rS": "stylus-ball radius / pre-travel", "xP": "sphere placement, radial",
    "yP": "sphere placement, tangential", "xD": "reading datum, X", "yD": "reading datum, Y",
    "zD": "reading datum, Z", "xZR": "R-test zero, X", "yZR": "R-test zero, Y", "zZR": "R-test zero, Z",
    "xPR": "R-test sphere placement, X", "yPR": "R-test sphere placement, Y", "zPR": "R-test sphere placement, Z",
    "xNR": "R-test nest centring, X", "yNR": "R-test nest centring, Y", "zNR": "R-test nest centring, Z",
    "dLR": "R-test nest length",
}


def quantity_unit(name: str) -> str:
    """Display unit (``"arcsec"`` or ``"um"``) of a deviation, derived quantity, nuisance parameter
    (base name ``"xT"`` or full name ``"xT[RB1]"``) or a discrepancy scale."""
    base = name.split("[")[0]
    scales = {q.name: q for q in DISCREPANCY_SCALES.values()}
    for table in (QUANTITIES, SETUP_NUISANCE, MOUNT_NUISANCE, PROBE_NUISANCE, RTEST_NUISANCE, scales):
        if base in table:
            return table[base].unit
    kind = iso_kind(base)
    if kind is not None:
        return "arcsec" if kind == "angle" else "um"
    raise KeyError(name)


def iso_kind(symbol: str) -> str | None:
    """``"length"`` or ``"angle"`` of an ISO 230-7 location-error symbol (``E_X0C``, ``E_A(0C1)B``), else None:
    E_X/E_Y/E_Z are positions, E_A/E_B/E_C orientations; an inclined axis' (SPEC §21): E_U/E_V/E_W positions,
    E_RU/E_RV orientations."""
    if not symbol.startswith("E_"):
        return None
    if len(symbol) > 5 and symbol[2] == "R" and symbol[3] in "UV" and symbol[4] in "0(":
        return "angle"
    if len(symbol) > 4 and symbol[2] in "XYZUVWABC" and symbol[3] in "0(":
        return "length" if symbol[2] in "XYZUVW" else "angle"
    return None


@dataclass(frozen=True)
class Parameter:
    """One entry of a parameter vector.

    ``name`` is unique in its space: a deviation name (``"beta_XB"``) or a
    nuisance base name with its owner (``"xT[RB1]"``, ``"xW[C]"``).
    """

    name: str
    base: str
    group: str  # "deviation", "setup", "mount", "probe" or "rtest"
    owner: str | None
    kind: str

    @property
    def unit(self) -> str:
        return "arcsec" if self.kind == "angle" else "um"


def nuisance_name(base: str, owner: str) -> str:
    """Name of a nuisance parameter, e.g. ``nuisance_name("xT", "RB1") == "xT[RB1]"``."""
    return f"{base}[{owner}]"


class ParameterSpace:
    """Ordered parameters of a campaign: deviations, then per setup, per mount, then the probe terms.

    Parameters
    ----------
    setups, mounts:
        Ids of the tool setups and W-ball mounts, in campaign order.
    deviations:
        Names of the deviations to include (default all of ``table``, in its order);
        forward models hold the others at zero.
    table:
        The deviations to choose from, by name (default the thesis' 13, :data:`DEVIATIONS`, in Table 2.1
        order; a described machine's from :func:`mtmcal_bayes.machines.deviations.quantities`).
    probe:
        Touch-probe nuisance terms as ``(owner, base)`` pairs, in order (e.g. ``("short", "xS")``,
        ``("run1", "xP")``); see :data:`PROBE_NUISANCE`.
    rtest:
        R-test nuisance terms as ``(owner, base)`` pairs, in order, after the probe's; see :data:`RTEST_NUISANCE`.
    """

    def __init__(self, setups, mounts, deviations=None, probe=(), *, table: dict[str, Quantity] | None = None,
                 rtest=()):
        table = DEVIATIONS if table is None else table
        names = list(table) if deviations is None else [d for d in table if d in set(deviations)]
        params = [Parameter(n, n, "deviation", None, table[n].kind) for n in names]
        for s in setups:
            params += [Parameter(nuisance_name(q.name, s), q.name, "setup", s, q.kind) for q in SETUP_NUISANCE.values()]
        for m in mounts:
            params += [Parameter(nuisance_name(q.name, m), q.name, "mount", m, q.kind) for q in MOUNT_NUISANCE.values()]
        params += [Parameter(nuisance_name(b, o), b, "probe", o, PROBE_NUISANCE[b].kind) for o, b in probe]
        params += [Parameter(nuisance_name(b, o), b, "rtest", o, RTEST_NUISANCE[b].kind) for o, b in rtest]
        self.parameters: tuple[Parameter, ...] = tuple(params)
        self._index = {p.name: i for i, p in enumerate(self.parameters)}

    @classmethod
    def for_campaign(cls, campaign, deviations=None, data: str = "ballbar") -> ParameterSpace:
        """The space of ``campaign`` for ``data`` (:data:`DATA_INSTRUMENTS`): the ball-bar nuisance terms with
        ball-bar data, the probe terms with probe data, the R-test terms with R-test data."""
        used = data_instruments(data, campaign)
        bb = "ballbar" in used
        probe = (campaign.probe.nuisance_terms(campaign.machine.description)
                 if "probe" in used and campaign.probe else ())
        rtest = campaign.rtest.nuisance_terms(campaign.machine.description) \
            if "rtest" in used and campaign.rtest else ()
        return cls(list(campaign.ballbar.setups) if bb else [], list(campaign.ballbar.mounts) if bb else [],
                   deviations, probe, rtest=rtest)

    def __len__(self) -> int:
        return len(self.parameters)

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.parameters]

    def index(self, name: str) -> int:
        """Column of ``name`` in a parameter batch."""
        return self._index[name]

    def display_scale(self) -> np.ndarray:
        """Internal units per display unit for every column, shape ``(p,)``."""
        return np.array([units.to_internal(1.0, p.unit) for p in self.parameters])

    def vector(self, values: dict[str, float] | None = None) -> np.ndarray:
        """Parameter vector, shape ``(p,)``, internal units, from ``{name: internal value}`` (others zero)."""
        theta = np.zeros(len(self))
        for name, v in (values or {}).items():
            theta[self.index(name)] = v
        return theta
