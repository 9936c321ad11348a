"""A machine's plug-ins (SPEC §20): what is particular to one machine, contributed by name, asked for by the engine.

A description names its plug-ins (``plugins = ["thesis"]`` in its TOML): a built-in name (:data:`BUILTIN`) or the
path of an importable module whose ``PLUGIN`` is the plug-in object.  A plug-in is an object with any of the
contributions the engine asks for (an attribute per contribution; one it lacks is ``None``):

* ``models`` — the names of the forward models it offers, ``kinematic_model`` the default kinematic one,
  ``make_model(name, campaign, space, data, observations=, probe_layout=)`` and ``first_order_gap(...)``;
* ``default_data`` — which instruments a likelihood uses when none is asked for (the engine's rule: every
  instrument the campaign has);
* ``probe_layout(campaign)``, ``probe_noise`` — the layout of the campaign's probe runs whose nominal readings its
  own kernel gives, and the rule of
  the probe's noise (:data:`mtmcal_bayes.models.probe.NOISE_RULES`; one that takes only a stated repeatability:
  a probe that states none is not simulated; the engine's: the pooled repeat scatter, 1 µm assumed);
* ``patterns``, ``pattern_components(pattern)``, ``mount_conflict(pattern, mount)`` — its patterns in its own
  order, their eccentricity components, why a mount cannot serve a pattern in its campaign format (the engine's:
  every ``<K><d>``, :mod:`mtmcal_bayes.machines.patterns`; any mount serves);
* ``ballbar_keys`` — its own keys of ``[ballbar]`` in the engine's one reader and one writer of it: its set-ups',
  its mounts' and the table's, read into the engine's set-ups and mounts and written back from them, and the ball
  bar completed in the engine's terms (the members of :class:`mtmcal_bayes.io.ballbar_section.EngineKeys`, the
  engine's own); ``probe_keys`` — the names of its own sub-tables of ``[probe]``, which
  ``read_probe_keys(r, table, probe, ballbar=, base_dir=)`` reads into the engine's probe runs and styli
  (:class:`mtmcal_bayes.campaign.Probe`, each run with its ``section``, and whatever record of its own keys it needs
  in ``Probe.own``; the engine reads the rest of ``[probe]``, its instrument, ``[probe.styli]`` and
  ``[[probe.runs]]``, on every machine), ``probe_document(probe, path_of)`` their writing (its runs; the engine's
  writes the others)
  (``[machine]`` is the engine's on every machine: name, serial, type, travels and the description, a built-in type
  by its name);
* ``identify(campaign)`` — a deterministic identification with the values its source published (its result gives
  its tables, ``table("ballbar")``), ``read_reported(r, table, text)`` — the campaign's ``[reported]`` table of those
  values (a machine without it refuses the table), and ``report_section(page, ident, effect, sigma_um)`` — the report's section of
  it, ``report_tables(ident, effect)`` — that section's CSVs;
* ``compensation_kinematics(campaign, model=, point=, setup=, mount=)`` — the tool point its compensation inverts
  (the engine's: the description's chain), ``compensation_methods`` and ``compensation_values`` (``{name:
  function}``, beside the engine's exact method and posterior values), ``compensation_posterior(campaign)`` — its
  default posterior (:mod:`mtmcal_bayes.compensation.compensate`);
* ``program_format`` — how its measuring programs are written (the engine selects, checks and computes them on
  every machine: :mod:`mtmcal_bayes.io.chain_programs`, whose ``ChainFormat`` is the engine's own and states the
  protocol: its own options, default step, grid, tool length, the writer);
* and, while the engine still has two paths for them, the whole of a command (``report``, ...): each one the engine
  takes over is one contribution fewer.

The engine never asks which machine it holds: it asks :func:`provided` for a contribution and uses its own where no
plug-in gives one.  This module is the one place that resolves a machine's plug-ins; the plug-ins are loaded by
name when first asked for, so that no layer of the package imports them (they sit above every layer they use).
"""

from __future__ import annotations

import functools
import importlib

#: the plug-ins that ship with the package, by the name a description gives
BUILTIN = {"thesis": "mtmcal_bayes.plugins.thesis"}
#: the plug-ins of a campaign in the thesis' own format, which names no description (the thesis machine's)
THESIS_FORMAT = ("thesis",)


def plugin_names(machine) -> tuple[str, ...]:
    """The names of the plug-ins of a campaign's ``machine`` (its description's; a campaign in the thesis' own
    format has the thesis machine's), or of a description itself."""
    if hasattr(machine, "plugins"):
        return machine.plugins
    desc = machine.description
    return desc.plugins if desc is not None else THESIS_FORMAT


@functools.cache
def load(name: str):
    """The plug-in object of ``name`` (a built-in name or a module path); ``ImportError`` / ``AttributeError`` when
    there is none (the description's reader checks its names when it reads them)."""
    return importlib.import_module(BUILTIN.get(name, name)).PLUGIN


def provided(machine, what: str, default=None):
    """The first contribution ``what`` of the plug-ins of ``machine`` (a campaign's machine or a description), else
    ``default`` (the engine's own)."""
    for name in plugin_names(machine):
        value = getattr(load(name), what, None)
        if value is not None:
            return value
    return default
