"""The thesis plug-in: what the INTEGREX i-200 of the thesis has that no other machine has (SPEC §20).

The thesis machine is the built-in description ``integrex-i200`` plus this plug-in.  It contributes:

* **its published models**: ``linear`` (the thesis relations, Eqs 4.1–4.9 and Table 2.6, with the nuisance terms)
  and ``htm-thesis`` (the thesis' pivots), beside ``htm-literal`` (Eq 2.10 as printed, the test oracle of the chain)
  and ``chain``, the engine's chain on its campaign translated into W-ball positions, arcs, bar sides and the
  Tables' commands (:mod:`.translation`); all three kinematic models are the engine's one ball-bar model
  (:mod:`mtmcal_bayes.models.ballbar`), the first two with the thesis' Eq 2.10 as its kernel (:mod:`.kinematic`);
  ``htm-thesis`` is its default kinematic model;
* **its default data**: the ball bar (the thesis identifies from the ball bar and checks with the probe);
* **its names**: the thesis' 13 deviation names as aliases of their ISO 230-7 symbols;
* **its campaign keys**, read and written by the engine's one reader and one writer (``[machine]`` names the
  ``integrex-i200`` description as any built-in type's campaign does; the thesis' first form, ``configuration =
  "w-C'bZYXB(C1)-t"``, is still read): in ``[ballbar]`` the thesis' lever arms R_B, Z_T, X_T and mounts Z_C, R_C and its
  ``cr_geometry`` (``ballbar_keys``; a run's W ball, arc and bar side in the engine's terms: ``run_placement``,
  :mod:`.translation`); the touch probe's ``[probe.c_axis]`` and ``[probe.b_axis]`` (Tables 4.2–4.4, 5.1/5.2;
  ``probe_keys``, ``read_probe_keys``, ``probe_document``; the engine reads and writes the rest of ``[probe]``,
  ``[[probe.runs]]`` among it), its 13 deviation names and the derived dx_CZ − dx_BT;
* **its patterns**: its 12 in the order of Tables 2.2/2.3 (B before C), their components, B patterns only with the
  W ball on the C axis (Table 2.2), and the geometry line of its sensitivity table (Tables 2.4–2.6);
* **its deterministic identification**: Eqs 4.10–4.18 and 5.1–5.19 beside Tables 4.5 and 5.3, and the report's
  section of them (thesis values recomputed);
* **its program format**: how Fig 4.30(a) writes a ball-bar program (its blocks, NC frame, grid and options ``R_B_mm``,
  ``start``, ``n``), which the engine's one path of ``ncgen`` and ``design`` writes with;
* **its parts of the engine's compensation**: its kinematic models' tool point in their model frame (which the
  engine's Newton inverts), Eqs 3.4–3.13 as printed (``method="thesis"``), the published ball-bar values
  (``values="ballbar"``) and its default posterior (the closed form at σ_model 2 µm from the ball bar).

The package holds the thesis' own code beside these contributions: :mod:`.linear`, :mod:`.kinematic`,
:mod:`.probe_model`, :mod:`.htm` (its models) and :mod:`.translation`, :mod:`.names`, :mod:`.campaign_keys` and
:mod:`.campaign_document` (its names and keys), :mod:`.identification` (Eqs 4.10–4.18, 5.1–5.19),
:mod:`.compensation` (Eqs 3.4–3.13 and the tool point of its models), :mod:`.program_format` (Fig 4.30(a)),
:mod:`.report_section`.  No layer of the package imports them: the engine asks the machine
(:func:`mtmcal_bayes.machines.plugins.provided`).  Each contribution imports its code when asked for, so loading the
plug-in costs nothing.
"""

from __future__ import annotations


def read_probe_keys(r, t: dict, probe, *, ballbar=None, base_dir=None) -> None:
    """Its sub-tables of ``[probe]``, ``[probe.c_axis]`` and ``[probe.b_axis]`` (``probe_keys``), read into the
    engine's probe runs and styli of ``probe`` (:mod:`.probe_runs`); the engine reads the rest of ``[probe]``."""
    from .campaign_keys import read_probe_keys as read

    read(r, t, probe, ballbar=ballbar, base_dir=base_dir)


def read_reported(r, t: dict, text: str) -> dict:
    """``[reported]``: the values it published, with their printed decimals (:mod:`.reported`)."""
    from .reported import read_reported as read

    return read(r, t, text)


def ballbar_keys():
    """Its keys of ``[ballbar]`` in the engine's reader: set-ups by R_B, Z_T, X_T, mounts by Z_C, R_C, cr_geometry
    (:class:`.campaign_keys.BallbarKeys`)."""
    from .campaign_keys import BallbarKeys

    return BallbarKeys


def complete_ballbar(ballbar, machine) -> None:
    """A ball bar built in Python for the thesis machine in the engine's terms: in its own campaign format (mounts by
    R_C and Z_C) its patterns' arcs and bar sides and its runs' frames (:func:`.translation.complete`); with W-ball
    positions (the generic format) its runs' frames only."""
    import functools

    from ...io.machine_reader import description_of
    from ...pattern_frames import chain_frame
    from .translation import complete

    desc = description_of(machine)
    if any(m.position is not None for m in ballbar.mounts.values()):
        ballbar.pattern_frames = functools.partial(chain_frame, desc)
    else:
        complete(ballbar, desc)


def run_placement(campaign, pattern: str, mount) -> tuple:
    """A run of ``pattern`` on ``mount`` (Z_C, R_C) in the engine's terms: ``(W-ball position (3,) mm, arc (k,)
    degrees, bar reversed)`` (Tables 2.2/2.3, :mod:`.translation`)."""
    from .translation import run_placement as placement

    return placement(campaign, pattern, mount)


def probe_document(probe, path_of) -> dict:
    """``[probe.b_axis]`` and ``[probe.c_axis]`` written (the inverse of :func:`read_probe_keys`: its runs; the
    engine writes the others as ``[[probe.runs]]``); ``path_of`` gives a DPRNT file's name as seen from the saved campaign."""
    from .campaign_document import probe_document as document

    return document(probe, path_of)


def pattern_components(pattern: str) -> tuple[str, ...]:
    """The eccentricity components of a thesis pattern (Tables 2.2/2.3)."""
    from ...patterns import COMPONENTS

    return COMPONENTS[pattern]


def mount_conflict(pattern: str, mount) -> str | None:
    """Why its campaign format cannot measure ``pattern`` on ``mount`` (a B pattern puts the W ball on the C axis,
    Table 2.2: R_C = 0), or None."""
    from ...patterns import mount_conflict as conflict

    return conflict(pattern, mount.id, mount.R_C)


def sensitivity_geometry(c) -> str:
    """The geometry line of its sensitivity table (Tables 2.4–2.6) of a campaign ``c`` with one run of every pattern,
    B before C: the first run's set-up and the C patterns' mount by their lever arms, the bar, the CR geometry."""
    bb = c.ballbar
    s, m = bb.setups[bb.runs[0].setup], bb.mounts[bb.runs[-1].mount]
    return (f"R_B = {s.R_B:g} mm, Z_T = {s.Z_T:g} mm, X_T = {s.X_T:g} mm, Z_C = {m.Z_C:g} mm, R_C = {m.R_C:g} mm, "
            f"L_B = {bb.length:g} mm, CR geometry {bb.cr_geometry}")


def compensation_kinematics(campaign, *, model, point: str, setup, mount):
    """The kinematics the engine's compensation inverts on its machine: its model (default ``htm-thesis``) in its
    model frame at a set-up's and a mount's lever arms, the program in its NC frame (:mod:`.compensation`)."""
    from .compensation.compensate import kinematics

    return kinematics(campaign, model=model, point=point, setup=setup, mount=mount)


def printed_method(kin, values, program, q):
    """Eqs 3.4–3.13 as printed (``method="thesis"``): X, Y, Z ``(k, 3)`` mm of ``program``."""
    from .compensation.compensate import printed_method as method

    return method(kin, values, program, q)


def ballbar_values(campaign) -> dict:
    """The deterministic ball-bar values of Table 4.5 (``values="ballbar"``), ``{name: value}`` mm and rad."""
    from .compensation.compensate import ballbar

    return ballbar(campaign)


def compensation_posterior(campaign):
    """Its default posterior of a compensation: 1000 draws of the closed form at σ_model 2 µm from the ball bar."""
    from .compensation.values import default_posterior

    return default_posterior(campaign)


def sample_notes(result) -> list[str]:
    """What ``sample`` adds on the thesis machine: the effect of the thesis assumption dx_BT = 0 (Eq 4.2)."""
    from .assumption import sample_notes as notes

    return notes(result)


def assumption_effect(analysis, *, sigma_model_um: float):
    """The report's table of the effect of dx_BT = 0 (Eq 4.2) on ``analysis``' posterior (``thesis_assumption_dx_BT.csv``)."""
    from .assumption import assumption_effect as effect

    return effect(analysis, sigma_model_um=sigma_model_um)


def planning():
    """The planning of the thesis' campaign format: the engine's catalogue under its rules (Step 5's extension bars
    with Z_T − e, its other R_C and bar lengths, B patterns with R_C = 0, its labels: :mod:`.catalogue_rules`), its
    clock and run records; its probe runs are the engine's catalogue's, like every machine's."""
    from ...planning.candidates import read_candidates
    from .run_records import RUN_COLUMNS, thesis_records
    from ...planning.machine_kit import PlanningKit
    from .catalogue_rules import catalogue_rules
    from .timing import campaign_clock

    def where(c) -> dict:
        return {"setup": c.setup.id, "R_B_mm": c.setup.R_B, "Z_T_mm": c.setup.Z_T, "mount": c.mount.id,
                "R_C_mm": c.mount.R_C}

    def sweep_pattern(table, campaign) -> str:
        best = table[table["kind"] == "tool length"]
        return str(best.iloc[0]["pattern"]) if len(best) else "CR"

    return PlanningKit(
        catalogue_rules=catalogue_rules(), clock=campaign_clock, where=where, sweep_pattern=sweep_pattern,
        feasibility_note="feasible = the span of each linear-axis command fits the axis travel of [machine] (the "
                         "campaign does not give where the C axis sits within the travels)",
        run_columns=RUN_COLUMNS,
        run_records=thesis_records, planned_geometry=lambda planned, candidate, campaign: None,
        read_candidates=read_candidates)


def make_model(name: str, campaign, space=None, data: str = "ballbar", *, observations=None, probe_layout=None):
    """The model ``name`` for a campaign in the thesis' format (thesis lever arms, probe runs of Tables 5.1/5.2)."""
    from ...models.ballbar import BallbarModel
    from ...models.joint import JointModel
    from ...observations import Observations
    from .translation import translated
    from .kinematic import HTMModel
    from .linear import LinearModel
    from .probe_model import LinearProbeModel, ProbeModel
    from ...parameters import ParameterSpace

    if space is None:
        space = ParameterSpace.for_campaign(campaign, data=data)
    parts = []
    if data in ("ballbar", "both"):
        parts.append(LinearModel(campaign, space, observations=observations) if name == "linear"
                     else BallbarModel(translated(campaign), space,
                                       observations=observations or Observations.from_campaign(campaign))
                     if name == "chain"
                     else HTMModel(campaign, name, space, observations=observations))
    if data in ("probe", "both"):
        probe = (LinearProbeModel(campaign, space, probe_layout) if name == "linear"
                 else ProbeModel(campaign, "htm-literal" if name == "chain" else name, space, probe_layout))
        if name == "chain":
            probe.name = "chain"  # the thesis machine's chain is htm-literal, its probe model too
        parts.append(probe)
    return parts[0] if len(parts) == 1 else JointModel(parts)


def first_order_gap(campaign, theta, space=None, *, observations=None) -> float:
    """Largest difference, mm, between ``htm-thesis`` and its first order (``linear``) at ``theta`` (p,)."""
    import numpy as np

    from .kinematic import HTMModel
    from .linear import LinearModel

    linear = LinearModel(campaign, space, observations=observations)
    kinematic = HTMModel(campaign, "htm-thesis", linear.space, observations=linear.observations)
    return float(np.abs(kinematic.predict(theta) - linear.predict(theta)).max())


def parameter_space(campaign, fix_dx_BT: bool, data: str):
    """The thesis' sampled deviations (Table 2.1 without the linear axes' squareness; without dx_BT under the
    thesis assumption ``fix_dx_BT``, Eq 4.2) and the nuisance terms of its campaign format."""
    from ...inference.log_posterior import SAMPLED_DEVIATIONS
    from ...parameters import ParameterSpace

    devs = [d for d in SAMPLED_DEVIATIONS if not (fix_dx_BT and d == "dx_BT")]
    return ParameterSpace.for_campaign(campaign, devs, data=data)


def probe_layout(campaign):
    """The engine's probe layout of the thesis' campaign format (Tables 5.1/5.2), its nominal readings through
    ``htm-thesis``."""
    from .probe_model import thesis_layout

    return thesis_layout(campaign)


def report_section(page, ident, effect, sigma_um: float) -> None:
    """The report's section "Thesis values recomputed": ``ident`` (its identification) beside the printed values,
    its checks and assumptions, and ``effect`` (a DataFrame or ``None``), that of dx_BT = 0 at ``sigma_um`` µm."""
    from .report_section import report_section as section

    section(page, ident, effect, sigma_um)


def report_tables(ident, effect) -> list:
    """The CSVs of its report section, ``(file name, table, with its index)``: its identification beside the printed
    values (``ident``, None: none) and the effect of dx_BT = 0 (``effect``, None: not computed)."""
    tables = []
    if ident is not None:
        tables.append(("identification_ballbar.csv", ident.table("ballbar"), False))
        if ident.probe:
            tables.append(("identification_probe.csv", ident.table("probe"), False))
    if effect is not None:
        tables.append(("thesis_assumption_dx_BT.csv", effect, True))
    return tables


def identify(campaign):
    """Eqs 4.10–4.18 (ball bar) and 5.1–5.19 (touch probe), each value beside the published one."""
    from .identification import identify as identify_campaign

    return identify_campaign(campaign)


class ThesisPlugin:
    """The contributions of the thesis plug-in (see the module's docstring)."""

    name = "thesis"
    # its names and campaign keys
    probe_sections = "[probe.c_axis] or [probe.b_axis.styli]"
    selection_source = "the thesis' 13 deviations (Table 2.1)"
    description_key = "thesis"  # a history's or a fleet's key of the machine's kinematics
    description_label = "thesis machine"
    probe_keys = ("c_axis", "b_axis")
    read_probe_keys = staticmethod(read_probe_keys)
    read_reported = staticmethod(read_reported)
    probe_document = staticmethod(probe_document)
    complete_ballbar = staticmethod(complete_ballbar)
    run_placement = staticmethod(run_placement)
    pattern_components = staticmethod(pattern_components)
    mount_conflict = staticmethod(mount_conflict)
    # its models and likelihood
    kinematic_model = "htm-thesis"
    default_data = "ballbar"
    make_model = staticmethod(make_model)
    first_order_gap = staticmethod(first_order_gap)
    parameter_space = staticmethod(parameter_space)
    probe_layout = staticmethod(probe_layout)
    probe_noise = "run scatter plus repeatability"  # each run's repeat scatter plus the stated one, which it needs
    # its published method, programs and compensation
    identify = staticmethod(identify)
    sample_notes = staticmethod(sample_notes)
    assumption_effect = staticmethod(assumption_effect)
    report_section = staticmethod(report_section)
    report_tables = staticmethod(report_tables)
    compensation_kinematics = staticmethod(compensation_kinematics)
    compensation_methods = {"thesis": printed_method}
    compensation_values = {"ballbar": ballbar_values}
    compensation_posterior = staticmethod(compensation_posterior)
    sensitivity_geometry = staticmethod(sensitivity_geometry)

    @property
    def patterns(self) -> tuple[str, ...]:
        """Its 12 patterns in the order of Tables 2.2/2.3 (B before C; its description's axes give C first)."""
        from ...patterns import PATTERNS

        return PATTERNS

    @property
    def ballbar_keys(self):
        """Its keys of ``[ballbar]`` (:func:`ballbar_keys`)."""
        return ballbar_keys()

    @property
    def program_format(self):
        """Its program format: Fig 4.30(a)'s blocks in its NC frame (:class:`.program_format.Fig430Format`)."""
        from .program_format import FORMAT

        return FORMAT

    @property
    def planning(self):
        """Its planning kit (:func:`planning`)."""
        return planning()

    @property
    def aliases(self) -> tuple[tuple[str, str], ...]:
        """The thesis' names of its deviations by ISO 230-7 symbol (SPEC §19: dx_CZ = E_X0C, ...)."""
        from .names import THESIS_NAMES

        return tuple(THESIS_NAMES.items())

    @property
    def reported_quantities(self) -> tuple[str, ...]:
        """The eight quantities the thesis identifies (Table 4.5), the combination dx_CZ − dx_BT among them."""
        from ...parameters import IDENTIFIABLE

        return IDENTIFIABLE

    @property
    def summary_quantities(self) -> tuple[str, ...]:
        """What a posterior summary reports: the eight, and dx_CZ, dx_BT and dz_BT apart."""
        from .names import REPORTED

        return REPORTED

    @property
    def deviation_table(self) -> dict:
        """The thesis' 13 deviations by their thesis names (Table 2.1), each with its ISO 230-7 symbol."""
        from ...parameters import DEVIATIONS

        return DEVIATIONS

    @property
    def quantity_table(self) -> dict:
        """The deviations and the derived quantity dx_CZ − dx_BT, which a design may target."""
        from ...parameters import QUANTITIES

        return QUANTITIES

    @property
    def models(self) -> tuple[str, ...]:
        """Every model of the registry (:data:`mtmcal_bayes.models.MODELS`): the thesis' and the chain."""
        from ...models import MODELS

        return MODELS


PLUGIN = ThesisPlugin()
