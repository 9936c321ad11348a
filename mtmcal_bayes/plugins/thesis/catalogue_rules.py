"""The thesis' own rules of the candidate catalogue (SPEC §6, §20): what its campaign format varies.

The catalogue is the engine's (:mod:`mtmcal_bayes.planning.catalogue`) at the thesis' W balls; this plug-in states
only what is the thesis' own:

* **Step 5's extension bars** (Table 4.3): an extension of ``e`` mm gives ``R_B + e`` and ``Z_T − e`` (R_B + Z_T
  stays constant: the spindle head moves back by the extension), ``X_T`` unchanged; extensions 25–150 mm by 25 mm,
  measured with the four patterns whose readings depend on the tool length first (CR, CA, BX, BY);
* **Table 2.2's rule** that a B pattern measures with the W ball on the C axis (R_C = 0): a new run of a B pattern
  goes to the campaign's mount for B patterns, or to a new placement at R_C = 0 at that mount's height;
* its **other R_C** (50, 100, 150 mm, CR and CA) and **bar lengths** (50, 100, 150 mm) in place of the engine's
  placements and bars, no held axes (its campaign format holds the other axis at 0), and its published labels
  (``BZ @ RB1``, ``CA @ RB1, R_C 100 mm``: the mount follows from the pattern, docs/planning.md);
* its **probe positions** (Table 5.2, Sec 5.2): B indexed within its patterns' 0–90° (the description states no B
  travel), with 45° between, whose Y step separates alpha_XB from gamma_XB (at 90° the probe sees only their sum).
"""

from __future__ import annotations

from ...campaign import Mount, Setup
from ...patterns import mount_conflict

#: extension bars of the catalogue, mm
EXTENSIONS_MM = (25.0, 50.0, 75.0, 100.0, 125.0, 150.0)
#: other W-ball radii and bar lengths of the catalogue, mm
OTHER_R_C_MM = (50.0, 100.0, 150.0)
OTHER_L_B_MM = (50.0, 100.0, 150.0)
#: patterns measured at additional tool lengths and bar lengths
TOOL_LENGTH_PATTERNS = ("CR", "CA", "BX", "BY")
#: the indexed positions of its probe candidates, degrees, by axis (the others: the engine's)
PROBE_POSITIONS = (("B", (0.0, 45.0, 90.0)),)


def extended_setup(base: Setup, extension: float) -> Setup:
    """The tool setup with an extension bar of ``extension`` mm (Step 5 of the thesis)."""
    return Setup(f"{base.id}+{extension:g}", base.R_B + extension, base.Z_T - extension, base.X_T)


def candidate_mount(campaign, pattern: str) -> Mount:
    """The mount of a new run of ``pattern``: ``campaign.mount_for``, except that a B pattern measures with the W
    ball on the C axis (thesis Table 2.2) — without such a mount in the campaign, a new placement there
    (``<id>@R_C0``, at that mount's height, with its own W-ball offsets)."""
    m = campaign.mount_for(pattern)
    if mount_conflict(pattern, m.id, m.R_C):
        return Mount(f"{m.id}@R_C0", m.Z_C, 0.0)
    return m


def pattern_mounts(campaign, patterns) -> list[tuple[str, Mount]]:
    """Each pattern with its one mount (:func:`candidate_mount`, the campaign asked once per pattern)."""
    return [(p, candidate_mount(campaign, p)) for p in patterns]


def other_R_C(campaign) -> list[tuple[str, str, Mount, tuple[str, ...]]]:
    """CR and CA with the W ball at each other radius of :data:`OTHER_R_C_MM`, at the C patterns' mount height."""
    c_mount = campaign.mount_for("CR")
    return [("other R_C", f"R_C {R_C:g} mm", Mount(f"{c_mount.id}@R_C{R_C:g}", c_mount.Z_C, R_C), ("CR", "CA"))
            for R_C in OTHER_R_C_MM if R_C != c_mount.R_C]


def catalogue_rules():
    """The engine's :class:`~mtmcal_bayes.planning.catalogue.CatalogueRules` with the thesis' own (module
    docstring)."""
    from ...planning.catalogue import CatalogueRules

    return CatalogueRules(extensions_mm=EXTENSIONS_MM, tool_length_patterns=TOOL_LENGTH_PATTERNS,
                          bar_lengths_mm=OTHER_L_B_MM, bar_length_patterns=TOOL_LENGTH_PATTERNS, hold=False,
                          label_mount=False, extended_setup=extended_setup, pattern_mounts=pattern_mounts,
                          placements=other_R_C, probe_positions=PROBE_POSITIONS)
