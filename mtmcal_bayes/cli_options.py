"""The options of the ``mtmcal-bayes`` command line: one parser, its subcommands and their flags.

:func:`build_parser` takes the function that runs each command (from :mod:`mtmcal_bayes.cli`), so this module
knows the flags and ``cli`` the commands.  :func:`flag_of` maps an API parameter named in an error back to
the flag that sets it.
"""

from __future__ import annotations

import argparse
import datetime
import os

from . import api
from .io.machine_reader import BUILTIN_TYPES
from .models import DATA, MODELS
from .version import __version__

PROG = "mtmcal-bayes"
#: API parameters set by something other than the flag of the same name
FLAG_OF = {"start": "--x0/--y0/--z0", "steps": "--step", "ramps": "--ramp", "n": "--campaigns"}
DATA_OPTION = dict(choices=DATA, default=None, help="measurements in the likelihood: ball bar, probe, both (the two), "
                   "rtest, ballbar+rtest, probe+rtest, or all (every instrument the campaign has) (default: "
                   "every instrument the campaign has; the thesis machine: the ball bar, as the thesis identifies)")


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def _command(sub, name: str, func, help: str, *, campaign: str | None = "campaign TOML (default: the built-in "
             "thesis campaign)", json_help: str | None = "print JSON"):
    s = sub.add_parser(name, help=help)
    if campaign:
        s.add_argument("campaign", nargs="?", metavar="CAMPAIGN", help=campaign)
        s.add_argument("--machine", choices=list(BUILTIN_TYPES), default=None, metavar="TYPE",
                       help="instead of CAMPAIGN, the demo campaign of a built-in machine type: "
                            + ", ".join(BUILTIN_TYPES) + " (docs/machines.md)")
        _demo_option(s)
    if json_help:
        s.add_argument("--json", action="store_true", help=json_help)
    s.set_defaults(func=func, parser=s)
    return s


def _demo_option(s) -> None:
    s.add_argument("--demo", choices=["rtest"], default=None, help="with --machine: the type's R-test demo (R-test runs "
                   "alone, docs/rtest.md) instead of its demo campaign")


def _floats(text: str) -> list[float]:
    """``"19.5,21,20.2"`` -> floats (argparse type)."""
    try:
        return [float(x) for x in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected numbers separated by commas") from None


def _hold(text: str) -> tuple[str, float]:
    """``"A=-45"`` -> ``("A", -45.0)`` (argparse type)."""
    letter, sep, value = text.partition("=")
    try:
        if not sep or not letter.strip():
            raise ValueError
        return letter.strip().upper(), float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected AXIS=DEGREES, e.g. A=-45") from None


#: help of a --model whose default is the machine's kinematic model
KINEMATIC_DEFAULT = "forward model (default htm-thesis; on a described machine chain)"


def _model(s, default: str | None, choices=MODELS, help: str | None = None) -> None:
    s.add_argument("--model", choices=choices, default=default, help=help or f"forward model (default {default})")


def _sampler_options(s) -> None:
    """Options of the commands that run the sampler (sample, report)."""
    s.add_argument("--data", **DATA_OPTION)
    s.add_argument("--fix-dx-BT", action="store_true", help="impose the thesis assumption dx_BT = 0 (Eq 4.2)")
    s.add_argument("--target-ess", type=float, default=api.TARGET_ESS, help="stop when the bulk and tail ESS of "
                   "each quantity the stopping rule is over (the thesis machine's eight of Table 4.5, a described "
                   f"machine's deviations) reach this (default {api.TARGET_ESS:g}) and R-hat ≤ 1.01")
    s.add_argument("--sampler", choices=("emcee", "exact"), default="emcee",
                   help="emcee ensembles (default) or independent draws of the exact posterior (linear model)")
    s.add_argument("--max-steps", type=int, default=api.MAX_STEPS, help=f"step budget per ensemble (default {api.MAX_STEPS})")
    s.add_argument("--tolerances", metavar="FILE.toml", help="[tolerances] to decide conformity against "
                   "(default: the campaign's own section, if any)")
    s.add_argument("--sigma-model-um", type=float, default=None, help="fix sigma_model at this value, µm "
                   "(default: sampled from its prior; 0 with --closed-form)")
    _sigma_prior_option(s)
    s.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def _sigma_prior_option(s, uses: str = "") -> None:
    """``--sigma-model-prior FILE`` (sample, report, plan, design, next); ``uses``: what the command does with it."""
    s.add_argument("--sigma-model-prior", metavar="FILE.toml", default=None, help="the σ_model prior learnt "
                   "elsewhere, e.g. by a fleet of the machine type (format mtmcal-sigma-model-prior/1; default: the "
                   f"assumed HalfNormal(2 µm); docs/inference.md){uses}")


def _design_goal(s, *, contraction_default) -> None:
    """Options of design and next: what to reach, the candidates, the time model."""
    s.add_argument("--target", dest="targets", action="append", metavar="NAME=SD",
                   help="target standard uncertainty of a quantity, ″ or µm (repeatable), e.g. alpha_XB=2"
                   + ("" if contraction_default is not None else " (default: the campaign's [design])"))
    if contraction_default is not None:
        s.add_argument("--tolerances", metavar="FILE.toml", help="[tolerances]: targets at which the ISO 14253-1 "
                       "decision is expected to be made, for quantities without --target")
    s.add_argument("--budget-min", type=float, default=None, metavar="MINUTES",
                   help="machine minutes available (alone: the most improvement within them)")
    s.add_argument("--contraction", type=float, default=contraction_default, metavar="C",
                   help="target contraction of σ_model's uncertainty, 0–1 ("
                   + ("default 0.5: the data, not the prior, set σ_model; 0: none)" if contraction_default is not None
                      else "default: the campaign's [design], else 0.5)"))
    s.add_argument("--candidates", metavar="FILE.toml", help="candidate runs of your own ([[candidate]] tables), "
                   "added to the catalogue")
    s.add_argument("--times", metavar="FILE.toml", help="override the machine-time model (docs/design.md)")
    s.add_argument("--instruments", metavar="LIST", default=None, help="the instruments to choose among, "
                   "comma-separated: ballbar, probe, rtest (default: every one the campaign has a set-up for)")
    s.add_argument("--seed", type=int, default=0, help="random seed of the search and the check (default 0)")
    _model(s, "linear", help="forward model (default linear; htm models are linearised at zero)")
    _sigma_prior_option(s, ": σ_model is integrated out over it, and its contraction measured against the wider "
                        "of it and the assumed prior (docs/design.md)")


def build_parser(handlers: dict) -> argparse.ArgumentParser:
    """The argument parser; ``handlers`` maps each command name to the function that runs it."""
    p = _Parser(prog=PROG, description="Bayesian uncertainty analysis of turn-mill (B/C axis) machine-tool calibration.")
    p.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser, required=True)

    _command(sub, "identify", handlers["identify"], "deterministic ball-bar and touch-probe identification (thesis Eqs 4.10–4.18, 5.1–5.19)")

    s = _command(sub, "probe-fit", handlers["probe-fit"], "least-squares sphere fit of DPRNT probe output", campaign=None)
    s.add_argument("file", metavar="FILE", help="DPRNT output file (e.g. thesis Fig 5.13)")
    s.add_argument("--stylus-radius-mm", type=float, metavar="R", default=None,
                   help="stylus-ball radius, subtracted from the fitted radius (centre unchanged)")

    s = _command(sub, "simulate", handlers["simulate"], "predicted eccentricities for a known truth, or a synthetic campaign",
                 json_help="print the noise-free eccentricities as JSON")
    s.add_argument("--truth", metavar="TRUTH.toml", help="[deviations] <name>_arcsec/_um (or [truth.deviations]), "
                   "[setups.<id>] xT_um.., [mounts.<id>] xW_um..; missing = 0.  Required, except with --history "
                   "(default there: the campaign's [truth], else its posterior mean)")
    _model(s, None, help=KINEMATIC_DEFAULT)
    s.add_argument("-o", "--output", metavar="FILE", help="write a synthetic campaign TOML with the truth recorded")
    s.add_argument("--noise", action="store_true", help="with -o: scatter like a real measurement (repeats, instrument accuracy)")
    s.add_argument("--seed", type=int, default=None, help="random seed for --noise (and --history)")
    h = s.add_argument_group("a history of one machine (docs/history.md)")
    h.add_argument("--history", metavar="DIR", help="write a series of noisy campaigns of one machine into DIR")
    h.add_argument("--campaigns", type=int, default=5, help="number of campaigns (default 5)")
    h.add_argument("--every-days", type=float, default=91.0, help="days between campaigns (default 91)")
    h.add_argument("--start", type=datetime.date.fromisoformat, default=None, metavar="YYYY-MM-DD",
                   help="date of the first campaign (default 2026-01-05)")
    h.add_argument("--step", action="append", metavar="NAME=SIZE@K", help="a step of SIZE (″ or µm) from campaign K on")
    h.add_argument("--ramp", action="append", metavar="NAME=RATE@K", help="a ramp of RATE per year from campaign K on")
    h.add_argument("--serial", default="SIM-001", help="the machine's serial (default SIM-001)")
    h.add_argument("--type", dest="machine_type", metavar="TYPE", default=None,
                   help="the machine's [machine] type (make and model): a fleet pools σ_model over one type")
    h.add_argument("--temperatures", type=_floats, metavar="T1,T2,...", default=None,
                   help="workshop temperature of each campaign, °C (one value for all, or one per campaign)")
    h.add_argument("--thermal", action="append", metavar="NAME=K",
                   help="a thermal sensitivity: NAME moves by K ″ or µm per °C away from 20 °C (needs --temperatures)")

    s = _command(sub, "history", handlers["history"], "one machine's history: every quantity at every date, real "
                 "changes, when to recalibrate", campaign=None, json_help="print JSON: serial, dates, summary, changes, forecast")
    s.add_argument("campaigns", nargs="+", metavar="DIR|FILES", help="a directory of campaign files, or the files")
    _model(s, "linear", help="forward model (default linear; a kinematic model is linearised per campaign at the "
           "history's estimate, and the linearisation checked)")
    s.add_argument("--trend", choices=("auto", "off"), default="auto", help="auto: a drift rate per deviation where the "
                   "Bayes factor wants one (default); off: random walks only")
    s.add_argument("--seed", type=int, default=1, help="random seed (default 1)")
    s.add_argument("--tolerances", metavar="FILE.toml", help="[tolerances] for the forecast (default: the latest campaign's)")
    s.add_argument("--data", choices=DATA, default=None, help="what each campaign's likelihood uses (default: every "
                   "instrument it has, as sample; the thesis machine: the ball bar)")
    s.add_argument("-o", "--output", metavar="DIR", help="write history.json, CSV files, trend.png and index.html to DIR")

    s = _command(sub, "sensitivity", handlers["sensitivity"], "eccentricity of every pattern per unit deviation and mounting offset",
                 campaign="campaign whose geometry to use (default: thesis)", json_help=None)
    _model(s, None, help=KINEMATIC_DEFAULT)
    g = s.add_mutually_exclusive_group()
    g.add_argument("--json", action="store_true", help="print JSON")
    g.add_argument("--markdown", action="store_true", help="print a Markdown table")

    s = _command(sub, "sample", handlers["sample"], "posterior of the deviations by MCMC (emcee ensembles), with diagnostics")
    _model(s, "linear")
    s.add_argument("--seed", type=int, default=None, help="random seed: the same seed gives the same draws")
    s.add_argument("-o", "--output", metavar="posterior.nc", help="write the ArviZ InferenceData (NetCDF)")
    s.add_argument("--checkpoint", metavar="FILE", help="HDF5 checkpoint: written as it goes, resumed if it exists")
    _sampler_options(s)
    s.add_argument("--closed-form", action="store_true", help="instant closed-form Gaussian posterior (linear model)")

    s = _command(sub, "report", handlers["report"], "sample the posterior and write an HTML report with figures, tables and NetCDF",
                 json_help="print the summary, diagnostics and written files as JSON")
    s.add_argument("-o", "--output", metavar="DIR", default="report", help="report directory, created if needed (default ./report)")
    _model(s, "linear")
    s.add_argument("--compare-models", action="store_true",
                   help="also sample under the other two models and compare (takes several minutes)")
    s.add_argument("--seed", type=int, default=1, help="random seed (default 1: the same report every time)")
    _sampler_options(s)

    s = _command(sub, "plan", handlers["plan"], "rank candidate extra measurements by how much they reduce uncertainty",
                 json_help="print JSON, best candidate first")
    s.add_argument("--target", dest="targets", action="append", metavar="NAME",
                   help="quantity to make more certain (repeatable; default the quantities the campaign identifies: the "
                   "thesis machine's eight, a described machine's determined deviations)")
    _model(s, "linear", help="forward model (default linear; htm models are linearised at zero)")
    s.add_argument("--candidates", metavar="FILE.toml", help="extra candidates of your own ([[candidate]] tables)")
    s.add_argument("--sigma-model-um", type=float, default=None,
                   help="fixed model-discrepancy sd of the closed form (default: rms of its prior, 2 µm)")
    s.add_argument("--data", choices=DATA, default=None, help="what the current posterior rests on (default: every "
                   "instrument the campaign has; the thesis machine: the ball bar); probe runs are candidates whenever "
                   "the campaign has a [probe], R-test runs whenever it has an [rtest]")
    s.add_argument("--sweep-pattern", choices=("CR", "CA", "BX", "BY"), default=None,
                   help="pattern of the tool-length sweep (default: that of the best tool-length candidate)")
    _sigma_prior_option(s, ": the closed form at its rms, the σ_model information and the Monte-Carlo check under it "
                        "(docs/planning.md)")
    s.add_argument("--times", metavar="FILE.toml", help="override the machine-time model: an R-test candidate's "
                   "minutes (docs/design.md)")
    s.add_argument("-o", "--output", metavar="DIR", help="write plan.csv, plan.json and the figures to DIR")

    s = _command(sub, "design", handlers["design"], "design the whole campaign: the runs that reach target "
                 "uncertainties in the fewest machine minutes, in measuring order, with their NC programs",
                 json_help="print JSON: runs, total_minutes, expected, sigma_model, campaign")
    _design_goal(s, contraction_default=0.5)
    s.add_argument("-o", "--output", metavar="DIR", help="write design.json, campaign.toml, programs/ and "
                   "design.html to DIR")

    s = _command(sub, "next", handlers["next"], "on a partly measured designed campaign: the next run to measure, "
                 "or stop: every target reached", json_help="print JSON: status, run, minutes_left, "
                 "probability_targets_met, expected")
    _design_goal(s, contraction_default=None)
    s.add_argument("-o", "--output", metavar="DIR", help="write the re-planned campaign.toml and programs to DIR")

    s = _command(sub, "ncgen", handlers["ncgen"], "measuring NC program of a ball-bar pattern, of a campaign's "
                 "ball-bar run, of a probe run or of an R-test run, in the machine's program format (the thesis machine's: Fig 4.30(a))",
                 campaign=None, json_help=None)
    s.add_argument("pattern", nargs="?", metavar="PATTERN", help="<rotary axis><R|T|A|X|Y|Z>, e.g. BX on the thesis "
                   "machine, AR on a trunnion (with --run/--probe/--rtest: the campaign)")
    s.add_argument("campaign", nargs="?", metavar="CAMPAIGN", help="campaign whose setup geometry to use (default: thesis)")
    s.add_argument("--machine", choices=list(BUILTIN_TYPES), default=None, metavar="TYPE",
                   help="instead of CAMPAIGN, the demo campaign of a built-in machine type: " + ", ".join(BUILTIN_TYPES))
    _demo_option(s)
    s.add_argument("--R-B-mm", dest="R_B_mm", type=float, default=None, help="a format that takes it (the thesis "
                   "machine's): tool length R_B, mm (default: the setup's)")
    s.add_argument("--x0", type=float, default=None, help="a format that takes it (the thesis machine's): NC X of the "
                   "first block, mm (with --z0)")
    s.add_argument("--y0", type=float, default=0.0, help="NC Y of the first block, mm (default 0)")
    s.add_argument("--z0", type=float, default=None, help="NC Z of the first block, mm (with --x0)")
    s.add_argument("--step-deg", type=float, default=None, help="the swivelled axis' step, degrees (default: the "
                   "format's, 2.5 on the thesis machine; else the run's arc, or 1 with --arc-deg)")
    s.add_argument("--feed", type=float, default=None, help="feed word F (default: the campaign's feed_mm_per_min "
                   "where the format takes it, none on the thesis machine; the probing moves F100, an R-test run's F200)")
    s.add_argument("-n", type=int, default=None, help="a format that takes it (the thesis machine's): number of "
                   "blocks (default: the arc's span, B 0–90°, C one turn)")
    s.add_argument("--setup", default=None, help="campaign setup for the tool length (default: that of the pattern's "
                   "first run, else the first)")
    s.add_argument("--mount", default=None, help="campaign mount of the W ball (default: that of the pattern's first "
                   "run, else the first that serves the pattern)")
    s.add_argument("--run", type=int, default=None, metavar="N", help="the campaign's N-th ball-bar run (from 1; "
                   "measured, then planned)")
    s.add_argument("--probe", default=None, metavar="ID", help="the probe run ID (or its number) of [[probe.runs]]")
    s.add_argument("--rtest", default=None, metavar="RUN", help="the R-test run RUN (its id or number) of "
                   "[[rtest.runs]]: one block per position through the nominal inverse chain, a dwell at each")
    s.add_argument("--dwell-ms", type=int, default=None, metavar="MS", help="with --rtest: the dwell at each "
                   "position for the reading, G04 P in ms (default 2000)")
    s.add_argument("--arc-deg", type=float, nargs=2, default=None, metavar=("START", "END"),
                   help="the swivelled axis' arc, degrees (default: the campaign format's or the axis' grid)")
    s.add_argument("--hold", dest="hold_deg", type=_hold, action="append", default=None, metavar="AXIS=DEG",
                   help="a held rotary axis' position, e.g. A=-45 (repeatable; default 0)")
    s.add_argument("-o", "--output", metavar="FILE.nc", help="write the program to FILE (default: print)")

    _command(sub, "instruments", handlers["instruments"], "do the instruments agree (every pair of the ball bar, the "
             "touch probe and the R-test the campaign has)? consistency, each instrument's σ_model, disputed "
             "deviations, explanations weighed by the data (docs/probe.md, docs/rtest.md)",
             json_help="print JSON: agree, scales_um, disputed, consistency, explanations")
    s = _command(sub, "axes", handlers["axes"], "the identified axis lines: direction and point of each rotary axis and "
                 "the spindle, pivot distances, each with its uncertainty (a controller's kinematic description)")
    s.add_argument("--csv", metavar="FILE", default=None, help="write the table as CSV")
    s.add_argument("--format", choices=("table", "isg-csv"), default="table", help="isg-csv: the identified position "
                   "errors in the ISG CSV format of the ISG kernel / Beckhoff TF5280 volumetric compensation")
    s.add_argument("-o", "--output", metavar="FILE", default=None, help="with --format isg-csv: write it to FILE")
    s.add_argument("--data", **DATA_OPTION)
    s.add_argument("--seed", type=int, default=1, help="seed of the posterior draws (default 1)")

    s = _command(sub, "compensate", handlers["compensate"], "rewrite X/Y/Z of an NC program for the identified deviations, "
                 "with uncertainty", json_help="print JSON: corrections, residuals, what is not compensable")
    s.add_argument("program", metavar="PROGRAM.nc", help="NC program (G00/G01 blocks, absolute)")
    s.add_argument("-o", "--output", required=True, metavar="OUT.nc", help="compensated program")
    s.add_argument("--method", choices=("exact", "thesis"), default="exact",
                   help="exact inversion (default) or thesis Eqs 3.4–3.13 as printed (double correction; the thesis "
                   "machine's)")
    _model(s, None, help="kinematic model (default the machine's: its chain, htm-thesis on the thesis machine; linear "
           "cannot compensate)")
    s.add_argument("--values", choices=("posterior", "ballbar"), default="posterior",
                   help="compensate with the posterior mean (default) or the deterministic ball-bar values (thesis "
                   "Table 4.5, the thesis machine's)")
    s.add_argument("--posterior", metavar="post.nc", help="posterior draws (from sample -o); default: the exact posterior "
                   "(the thesis machine: the closed form at sigma_model 2 µm)")
    s.add_argument("--point", choices=("tcp", "nose"), default="tcp",
                   help="compensate the tool centre point (default) or the spindle nose as the thesis does")
    s.add_argument("--setup", default=None, help="campaign setup of the tool (R_B, NC origin; default: that of BX; on a "
                   "described machine the first setup)")
    s.add_argument("--mount", default=None, help="campaign mount (Z_C of the C-axis pivot)")
    s.add_argument("--integer-unit", choices=("um", "mm"), default=None, help="how to read X/Y/Z/B/C words "
                   "without a decimal point (X100): increments of 1 µm / 0.001°, or mm / ° (default: refuse them)")
    s.add_argument("--accept-disagreement", action="store_true", help="compensate even with deviations two of the "
                   "instruments (ball bar, touch probe, R-test) disagree on (default: refuse them; see mtmcal-bayes "
                   "instruments)")

    s = _command(sub, "fleet", handlers["fleet"], "every machine's campaigns in a folder tree, in parallel on Dask: "
                 "posteriors, histories, one overview (docs/fleet.md)", campaign=None,
                 json_help="print JSON: machines (campaigns, changes, forecast), errors, run")
    s.add_argument("directory", metavar="DIR", help="folder searched recursively for campaign files (*.toml)")
    s.add_argument("-o", "--output", metavar="OUTDIR", help="write index.html, fleet.json, fleet_summary.csv and "
                   "machines/<serial>/ to OUTDIR (created if needed)")
    s.add_argument("--scheduler", metavar="ADDRESS", default=None, help="a running Dask scheduler "
                   "(tcp://host:8786, or its scheduler file) instead of a local cluster")
    s.add_argument("--workers", type=int, default=None,
                   help=f"local worker processes (default: the CPU count, {os.cpu_count() or 1})")
    s.add_argument("--cache", metavar="CACHEDIR", default=None, help="cache of finished campaigns and histories "
                   "(default OUTDIR/.cache, else ~/.cache/mtmcal-bayes/fleet)")
    _model(s, "linear", help="forward model of each campaign's posterior (default linear; histories: linear)")
    s.add_argument("--seed", type=int, default=1, help="random seed (default 1), combined with each campaign's content")
    s.add_argument("--sampler", choices=("emcee", "exact"), default="emcee",
                   help="emcee ensembles (default) or independent draws of the exact posterior (linear model)")
    s.add_argument("--target-ess", type=float, default=api.TARGET_ESS,
                   help=f"ESS each campaign's sampling aims for (default {api.TARGET_ESS:g})")
    s.add_argument("--max-steps", type=int, default=api.MAX_STEPS, help=f"step budget per ensemble (default {api.MAX_STEPS})")
    s.add_argument("--tolerances", metavar="FILE.toml", help="plant-wide [tolerances] for every machine: each "
                   "campaign's conformity, each history's forecast (default: each campaign's own)")
    s.add_argument("--quiet", action="store_true", help="no progress lines on stderr")

    vsub = sub.add_parser("validate", help="check the inference itself: simulation-based calibration").add_subparsers(
        dest="check", metavar="CHECK", parser_class=_Parser, required=True)
    v = _command(vsub, "sbc", handlers["sbc"], "simulation-based calibration (Talts et al. 2018): rank histograms, "
                 "coverage", campaign="campaign whose design (runs, repeats, priors) to simulate (default: thesis)",
                 json_help="print JSON: p_uniform and coverage_50/90/95 per quantity")
    v.add_argument("--n", type=int, default=200, help="replicates: truths drawn from the prior (default 200)")
    _model(v, "linear")
    v.add_argument("--data", **DATA_OPTION)
    v.add_argument("--sampler", choices=("emcee", "exact"), default="emcee",
                   help="emcee (default: what sample/report use) or the exact linear posterior (checks SBC itself)")
    v.add_argument("--draws", dest="n_ranked", type=int, default=99,
                   help="posterior draws each truth is ranked among (default 99)")
    v.add_argument("--max-steps", type=int, default=api.MAX_STEPS, help=f"emcee step budget per ensemble (default {api.MAX_STEPS})")
    v.add_argument("--workers", type=int, default=None,
                   help=f"processes of the local Dask cluster (default: the CPU count, {os.cpu_count() or 1})")
    v.add_argument("--scheduler", metavar="ADDRESS", default=None, help="run the replicates on a running Dask "
                   "scheduler (tcp://host:8786, or its scheduler file) instead of a local cluster; same result")
    v.add_argument("--seed", type=int, default=1, help="random seed (default 1)")
    v.add_argument("-o", "--output", metavar="DIR",
                   help="write sbc.json, sbc_summary.csv, sbc_replicates.csv, sbc_ranks.png, sbc_ecdf.png")
    v.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    return p


def flag_of(parser: argparse.ArgumentParser, parameter: str) -> str:
    """The flag (or positional metavar) of ``parser`` that sets the API parameter ``parameter``."""
    for action in parser._actions:
        if action.dest == parameter:
            longest = [o for o in action.option_strings if o.startswith("--")] or action.option_strings
            return longest[0] if longest else (action.metavar or parameter)
    return FLAG_OF.get(parameter, parameter)
