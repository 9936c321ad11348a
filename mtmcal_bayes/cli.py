"""The ``mtmcal-bayes`` command line: parse arguments, call the API, print.

Every command works without a campaign argument on the built-in thesis
campaign.  ``--json`` prints machine-readable results.  Problems with the
input are one line on stderr and exit status 2, never a traceback (set
``MTMCAL_DEBUG=1`` to see one for an unexpected internal error).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys

from .errors import MtmcalError

PROG = "mtmcal-bayes"
MODEL_NAMES = ("linear", "htm-literal", "htm-thesis")


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def _round(obj, digits: int = 10):
    """Floats to ``digits`` significant digits for JSON; NaN/inf become null."""
    if isinstance(obj, float):
        if not math.isfinite(obj):
            return None
        return float(f"{obj:.{digits}g}")
    if isinstance(obj, dict):
        return {k: _round(v, digits) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_round(v, digits) for v in obj]
    return obj


def print_json(obj) -> None:
    print(json.dumps(_round(obj), indent=2, ensure_ascii=False))


# --------------------------------------------------------------------------- commands
def cmd_identify(args) -> int:
    from .campaign import load_campaign
    from .identify import identify
    from .tables import format_identification

    result = identify(load_campaign(args.campaign))
    if args.json:
        print_json(result.to_json())
    else:
        print(format_identification(result))
    return 0


def cmd_probe_fit(args) -> int:
    from .models.probe import fit_sphere
    from .ncode import read_dprnt

    pts = read_dprnt(args.file)
    if args.stylus_radius_mm is not None and not math.isfinite(args.stylus_radius_mm):
        raise MtmcalError(f"--stylus-radius-mm: {args.stylus_radius_mm} is not a finite number")
    try:
        fit = fit_sphere(pts.xyz, args.stylus_radius_mm or 0.0)
    except MtmcalError as exc:
        raise MtmcalError(f"{args.file}: {exc}") from None
    notes = []
    if pts.declared is not None and pts.declared != len(pts.xyz):
        notes.append(f"header declares {pts.declared} points, the file holds {len(pts.xyz)}")
    if len({tuple(r) for r in pts.bc}) > 1:
        notes.append("points were probed at different B/C positions; fitted as one sphere in machine coordinates")
    if args.json:
        print_json({
            "file": str(args.file), "n_points": len(pts.xyz),
            "centre_mm": fit.centre.tolist(), "radius_mm": fit.radius,
            "fitted_radius_mm": fit.fitted_radius, "stylus_radius_mm": fit.stylus_radius,
            "rms_residual_um": fit.rms * 1e3, "max_abs_residual_um": float(abs(fit.residuals).max()) * 1e3,
            "notes": notes,
        })
    else:
        x, y, z = fit.centre
        print(f"Sphere fit of {len(pts.xyz)} probed points in {args.file}")
        print(f"  centre   X {x:.4f}  Y {y:.4f}  Z {z:.4f} mm")
        print(f"  radius   {fit.radius:.4f} mm" + (f" (fitted {fit.fitted_radius:.4f} mm − stylus {fit.stylus_radius:g} mm)"
                                                   if fit.stylus_radius else ""))
        print(f"  residual rms {fit.rms * 1e3:.2f} µm, max |{abs(fit.residuals).max() * 1e3:.2f}| µm")
        for n in notes:
            print(f"  note: {n}")
    return 0


def cmd_simulate(args) -> int:
    from .campaign import load_campaign, save_campaign
    from .simulate import eccentricity_records, load_truth, predict_truth, synthetic_campaign

    campaign = load_campaign(args.campaign)
    truth = load_truth(args.truth, campaign)
    obs, pred = predict_truth(campaign, truth, args.model, source=str(args.truth))
    if args.model == "linear":  # first order: say so when the truth is too large for it
        gap = float(abs(predict_truth(campaign, truth, "htm-thesis", source=str(args.truth))[1] - pred).max())
        if gap > campaign.ballbar.accuracy:
            print(f"WARNING: the linear model is first order and this truth is too large for it: htm-thesis "
                  f"predicts eccentricities up to {gap * 1e3:.1f} µm away (instrument accuracy "
                  f"{campaign.ballbar.accuracy * 1e3:g} µm)", file=sys.stderr)
    if args.output:
        synth = synthetic_campaign(campaign, truth, args.model, noise=args.noise, seed=args.seed)
        what = "with noise (seed %s)" % args.seed if args.noise else "noise-free"
        save_campaign(synth, args.output, header=(
            f"Synthetic campaign simulated by mtmcal-bayes with model {args.model}, {what},\n"
            f"from {campaign.source} and truth {args.truth}."))
        if not args.json:
            print(f"wrote {args.output}: {len(obs)} eccentricity components, {what}, model {args.model}")
    if args.json:
        print_json({"model": args.model, "eccentricities": eccentricity_records(obs, pred)})
    elif not args.output:
        print(f"Predicted eccentricities (µm), model {args.model}, truth {args.truth}")
        for rec in eccentricity_records(obs, pred):
            print(f"  {rec['pattern']:2s} {rec['setup']:>6s} {rec['mount']:>4s}  {rec['component']}  "
                  f"{rec['value_um']:10.3f}")
    return 0


def cmd_sensitivity(args) -> int:
    from .campaign import load_campaign
    from .sensitivity import sensitivity_table, to_markdown

    df = sensitivity_table(load_campaign(args.campaign), args.model)
    if args.json:
        print_json({"model": args.model, "geometry": df.attrs["geometry"],
                    "unit": "um per arcsec (angles) or um per um (lengths)",
                    "sensitivity": {idx: row.to_dict() for idx, row in df.iterrows()}})
    elif args.markdown:
        print(to_markdown(df))
    else:
        print(f"Eccentricity per unit deviation, model {args.model} (µm per ″ for angles, µm per µm for lengths)")
        print(f"Geometry: {df.attrs['geometry']}")
        print(df.to_string(float_format=lambda v: "." if v == 0 else f"{v:.3f}"))
    return 0


def _progress_printer(label: str):
    import time

    t0 = time.perf_counter()

    def show(step, max_steps, tau_max):
        print(f"sampling [{label}]: step {step} (budget {max_steps}), τ_max ≈ {tau_max:.0f} steps, "
              f"{time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)

    return show


def _check_writable(path, what: str) -> None:
    from pathlib import Path

    parent = Path(path).resolve().parent
    if not parent.is_dir():
        raise MtmcalError(f"{path}: cannot write the {what}: directory {parent} does not exist")


def _posterior_json(rep, args, campaign) -> dict:
    """JSON of a posterior: summary and comparison per quantity, diagnostics (SPEC §10)."""
    cols = ["mean", "sd", "median", "hdi_low", "hdi_high", "r_hat", "ess_bulk", "ess_tail", "unit"]
    return {
        "model": args.model, "campaign": campaign.source, "fix_dx_BT": args.fix_dx_BT,
        "summary": {n: {c: (row[c] if c == "unit" else float(row[c])) for c in cols}
                    for n, row in rep.summary.iterrows()},
        "comparison": {n: {k: (None if v is None or (isinstance(v, float) and math.isnan(v)) else v)
                           for k, v in row.items()} for n, row in rep.comparison.iterrows()},
        "diagnostics": rep.diagnostics(),
    }


def cmd_sample(args) -> int:
    from .campaign import load_campaign
    from .inference.run import posterior_report, thesis_assumption_effect, write_netcdf_atomic
    from .inference.sampling import SamplerSettings

    campaign = load_campaign(args.campaign)
    for path, what in ((args.output, "posterior"), (args.checkpoint, "checkpoint")):
        if path:
            _check_writable(path, what)
    if args.closed_form:
        return _closed_form(campaign, args)
    settings = SamplerSettings(seed=args.seed, max_steps=args.max_steps)
    progress = None if args.quiet else _progress_printer(args.model)
    rep = posterior_report(campaign, args.model, args.fix_dx_BT, settings, args.checkpoint, progress)
    if args.output:
        write_netcdf_atomic(rep.idata, args.output)
    for w in rep.warnings:
        print(f"WARNING: {w}", file=sys.stderr)
    if args.json:
        print_json({**_posterior_json(rep, args, campaign), "output": args.output})
        return 0
    from .tables import format_posterior

    print(format_posterior(rep, args.model))
    if not args.fix_dx_BT:
        sigma_um = float(rep.summary.loc["sigma_model", "median"])
        print(f"\nThe thesis assumption dx_BT = 0 (Eq 4.2), closed form at sigma_model = {sigma_um:.2f} µm "
              "(the posterior median; run with --fix-dx-BT to sample it):")
        print(thesis_assumption_effect(campaign, args.model, sigma_um).round(2).to_string())
    if args.output:
        print(f"\nposterior written to {args.output} (ArviZ InferenceData, NetCDF)")
    return 0


def _closed_form(campaign, args) -> int:
    from . import units
    from .inference.analytic import gaussian_posterior
    from .inference.posterior import Posterior
    from .parameters import IDENTIFIABLE, QUANTITIES

    if args.model != "linear":
        raise MtmcalError("--closed-form is exact for the linear model only (use --model linear)")
    sigma = args.sigma_model_um * 1e-3
    post = Posterior(campaign, "linear", fix_dx_BT=args.fix_dx_BT, sigma_model=sigma)
    g = gaussian_posterior(post, sigma_model=sigma)
    out = {}
    for name in IDENTIFIABLE:
        w = {"dx_CZ": 1.0, "dx_BT": -1.0} if name == "dx_CZ_minus_dx_BT" else {name: 1.0}
        w = {k: v for k, v in w.items() if k in g.names}
        m, sd = g.linear_combination(w)
        unit = QUANTITIES[name].unit
        m, sd = units.from_internal(m, unit), units.from_internal(sd, unit)
        out[name] = {"mean": m, "sd": sd, "hdi_low": m - 1.959964 * sd, "hdi_high": m + 1.959964 * sd, "unit": unit}
    if args.json:
        print_json({"model": "linear", "closed_form": True, "sigma_model_um": args.sigma_model_um, "summary": out})
    else:
        print(f"Closed-form Gaussian posterior, linear model, sigma_model fixed at {args.sigma_model_um:g} µm")
        for n, r in out.items():
            print(f"  {n:18s} {r['mean']:9.2f} ± {r['sd']:6.2f} {units.SYMBOL[r['unit']]}   "
                  f"95 %: [{r['hdi_low']:.2f}, {r['hdi_high']:.2f}]")
    return 0


def cmd_report(args) -> int:
    from .campaign import load_campaign
    from .inference.sampling import SamplerSettings
    from .report.build import build_report

    campaign = load_campaign(args.campaign)
    if args.max_steps < 500:
        raise MtmcalError(f"--max-steps: {args.max_steps} is below one block of 500 steps")
    settings = SamplerSettings(seed=args.seed, max_steps=args.max_steps)
    progress = None if args.quiet else _progress_printer
    say = None if args.quiet else (lambda text: print(f"report: {text}", file=sys.stderr, flush=True))
    command = " ".join([PROG] + (sys.argv[1:] if args.argv is None else args.argv))
    rep = build_report(campaign, args.output, args.model, settings, args.fix_dx_BT, args.compare_models,
                       progress, say, command)
    for w in rep.posterior.warnings:
        print(f"WARNING: {w}", file=sys.stderr)
    if args.json:
        print_json({**_posterior_json(rep.posterior, args, campaign), "directory": str(rep.directory),
                    "files": rep.files, "missing": rep.missing, "wall_time_s": rep.wall_time})
    else:
        print(rep.console)
    return 0


def cmd_plan(args) -> int:
    from .campaign import load_campaign
    from .planning.candidates import read_candidates
    from .planning.output import format_plan, write_plan
    from .planning.plan import plan

    campaign = load_campaign(args.campaign)
    if args.output:
        _check_writable(args.output, "plan")
    if args.sigma_model_um is not None and not (math.isfinite(args.sigma_model_um) and args.sigma_model_um >= 0):
        raise MtmcalError(f"--sigma-model-um: {args.sigma_model_um} is not a non-negative number")
    extra = read_candidates(args.candidates, campaign) if args.candidates else []
    result = plan(campaign, args.target, extra, args.sigma_model_um, args.sweep_pattern, args.model)
    files = write_plan(result, args.output) if args.output else []
    if args.json:
        print_json({**result.to_json(), "campaign": campaign.source, "output": args.output, "files": files})
    else:
        print(format_plan(result))
        if files:
            print(f"\nplan written to {args.output}/: {', '.join(files)}")
    return 0


def cmd_ncgen(args) -> int:
    from .campaign import load_campaign
    from .compensation.compensate import geometry_for
    from .models.htm import nc_origin
    from .ncgen import pattern_program
    from .patterns import PATTERNS

    start = origin = None
    if (args.x0 is None) != (args.z0 is None):
        raise MtmcalError("--x0 and --z0 go together (the NC position of the first block)")
    if args.x0 is not None:
        start = (args.x0, args.y0, args.z0)
        if not all(math.isfinite(v) for v in start):
            raise MtmcalError("--x0/--y0/--z0: must be finite numbers")
    campaign = load_campaign(args.campaign) if (args.campaign or args.R_B_mm is None or start is None) else None
    if campaign is not None:
        from .planning.candidates import mount_for

        mount = args.mount or (mount_for(campaign, args.pattern).id if args.pattern in PATTERNS else None)
        geo = geometry_for(campaign, args.setup, mount)
        R_B = args.R_B_mm if args.R_B_mm is not None else geo.R_B
        origin = None if start is not None else nc_origin(geo)
        L_B, Z_C, R_C, cr = campaign.ballbar.length, geo.Z_C, geo.R_C, campaign.ballbar.cr_geometry
    else:
        R_B, L_B, Z_C, R_C, cr = args.R_B_mm, 100.0, 0.0, 0.0, "RC-LB"
    lines = pattern_program(args.pattern, R_B, args.step_deg, args.n, L_B=L_B, Z_C=Z_C, R_C=R_C, start=start,
                            origin=origin, feed=args.feed, cr_geometry=cr)
    text = "\n".join(lines) + "\n"
    if args.output:
        from .textfiles import write_text_atomic

        _check_writable(args.output, "program")
        write_text_atomic(args.output, text)
    else:
        sys.stdout.write(text)
    return 0


def cmd_compensate(args) -> int:
    from .campaign import load_campaign
    from .compensation.compensate import OFF_TOOL_MM, compensate
    from .gcode import read_program
    from .textfiles import write_text_atomic

    campaign = load_campaign(args.campaign)
    program = read_program(args.program)
    _check_writable(args.output, "compensated program")
    res = compensate(campaign, program, args.method, args.model, args.values, args.posterior, args.point,
                     args.setup, args.mount)
    write_text_atomic(args.output, res.text)
    if args.json:
        print_json({**res.to_json(), "program": str(args.program), "output": args.output})
        return 0
    j = res.to_json()
    print(f"{args.program}: {j['blocks']} motion blocks compensated ({args.method}, {args.model}, "
          f"tool point {args.point}, deviations = {args.values}) -> {args.output}")
    c = j["correction_um"]["max_abs"]
    print(f"  largest correction: X {c['X']:.1f} µm, Y {c['Y']:.1f} µm, Z {c['Z']:.1f} µm; "
          f"tool-point error before {j['error_before_um']['max']:.1f} µm")
    print(f"  residual tool-point error ({j['uncertainty_from']}): mean ≤ {j['residual_um']['mean_max']:.1f} µm, "
          f"95 % ≤ {j['residual_um']['p95_max']:.1f} µm per block")
    print(f"  not compensable by X/Y/Z (tool-axis tilt; error {OFF_TOOL_MM:g} mm along the tool from the "
          "compensated point):")
    for r in j["not_compensable"]:
        print(f"    {r['name']:14s} {r['tool_tilt_arcsec']:7.2f} ″  {r[f'error_at_{OFF_TOOL_MM:g}mm_off_the_tool_point_um']:6.2f} µm")
    return 0


def cmd_validate_sbc(args) -> int:
    import time

    from .campaign import load_campaign
    from .validation import SBCSettings, run_sbc
    from .validation.output import format_sbc, write_sbc

    campaign = load_campaign(args.campaign)
    if args.output:
        _check_writable(args.output, "SBC")
    settings = SBCSettings(n=args.n, model=args.model, sampler=args.sampler, n_ranked=args.draws,
                           max_steps=args.max_steps, workers=args.workers, seed=args.seed)
    t0 = time.perf_counter()
    last = [0.0]

    def progress(done, n, elapsed):
        if args.quiet or (done < n and time.perf_counter() - last[0] < 10):
            return
        last[0] = time.perf_counter()
        eta = elapsed / done * (n - done)
        print(f"sbc [{args.model}, {args.sampler}]: {done}/{n} replicates, {elapsed:.0f} s, about {eta:.0f} s to go",
              file=sys.stderr, flush=True)

    result = run_sbc(campaign, settings, progress)
    files = write_sbc(result, args.output) if args.output else []
    if args.json:
        print_json({**result.to_json(), "output": args.output, "files": files})
    else:
        print(format_sbc(result))
        if files:
            print(f"\nSBC written to {args.output}/: {', '.join(files)}")
    if not args.quiet:
        print(f"sbc: done in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    return 0


# --------------------------------------------------------------------------- parser
def _sampler_options(s) -> None:
    """Options of the commands that run the sampler (sample, report)."""
    s.add_argument("--fix-dx-BT", action="store_true", help="impose the thesis assumption dx_BT = 0 (Eq 4.2)")
    s.add_argument("--max-steps", type=int, default=20_000, help="step budget per ensemble (default 20000)")
    s.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog=PROG, description="Bayesian uncertainty analysis of turn-mill (B/C axis) machine-tool calibration.")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    s = sub.add_parser("identify", help="deterministic ball-bar and touch-probe identification (thesis Eqs 4.10–4.18, 5.1–5.19)")
    s.add_argument("campaign", nargs="?", metavar="CAMPAIGN", help="campaign TOML (default: the built-in thesis campaign)")
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=cmd_identify)

    s = sub.add_parser("probe-fit", help="least-squares sphere fit of DPRNT probe output")
    s.add_argument("file", metavar="FILE", help="DPRNT output file (e.g. thesis Fig 5.13)")
    s.add_argument("--stylus-radius-mm", type=float, metavar="R", default=None,
                   help="stylus-ball radius, subtracted from the fitted radius (centre unchanged)")
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=cmd_probe_fit)

    s = sub.add_parser("simulate", help="predicted eccentricities for a known truth, or a synthetic campaign")
    s.add_argument("campaign", nargs="?", metavar="CAMPAIGN", help="campaign TOML (default: the built-in thesis campaign)")
    s.add_argument("--truth", required=True, metavar="TRUTH.toml",
                   help="[deviations] <name>_arcsec/_um, [setups.<id>] xT_um.., [mounts.<id>] xW_um..; missing = 0")
    s.add_argument("--model", choices=MODEL_NAMES, default="htm-thesis", help="forward model (default htm-thesis)")
    s.add_argument("-o", "--output", metavar="FILE", help="write a synthetic campaign TOML with the truth recorded")
    s.add_argument("--noise", action="store_true", help="with -o: scatter like a real measurement (repeats, instrument accuracy)")
    s.add_argument("--seed", type=int, default=None, help="random seed for --noise")
    s.add_argument("--json", action="store_true", help="print the noise-free eccentricities as JSON")
    s.set_defaults(func=cmd_simulate)

    s = sub.add_parser("sensitivity", help="eccentricity of every pattern per unit deviation and mounting offset")
    s.add_argument("campaign", nargs="?", metavar="CAMPAIGN", help="campaign whose geometry to use (default: thesis)")
    s.add_argument("--model", choices=MODEL_NAMES, default="htm-thesis", help="forward model (default htm-thesis)")
    g = s.add_mutually_exclusive_group()
    g.add_argument("--json", action="store_true", help="print JSON")
    g.add_argument("--markdown", action="store_true", help="print a Markdown table")
    s.set_defaults(func=cmd_sensitivity)

    s = sub.add_parser("sample", help="posterior of the deviations by MCMC (emcee ensembles), with diagnostics")
    s.add_argument("campaign", nargs="?", metavar="CAMPAIGN", help="campaign TOML (default: the built-in thesis campaign)")
    s.add_argument("--model", choices=MODEL_NAMES, default="linear", help="forward model (default linear)")
    s.add_argument("--seed", type=int, default=None, help="random seed: the same seed gives the same draws")
    s.add_argument("-o", "--output", metavar="posterior.nc", help="write the ArviZ InferenceData (NetCDF)")
    s.add_argument("--checkpoint", metavar="FILE", help="HDF5 checkpoint: written as it goes, resumed if it exists")
    _sampler_options(s)
    s.add_argument("--closed-form", action="store_true",
                   help="instant closed-form Gaussian posterior (linear model, fixed sigma_model)")
    s.add_argument("--sigma-model-um", type=float, default=0.0, help="sigma_model for --closed-form (default 0)")
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=cmd_sample)

    s = sub.add_parser("report", help="sample the posterior and write an HTML report with figures, tables and NetCDF")
    s.add_argument("campaign", nargs="?", metavar="CAMPAIGN", help="campaign TOML (default: the built-in thesis campaign)")
    s.add_argument("-o", "--output", metavar="DIR", default="report",
                   help="report directory, created if needed (default ./report)")
    s.add_argument("--model", choices=MODEL_NAMES, default="linear", help="forward model (default linear)")
    s.add_argument("--compare-models", action="store_true",
                   help="also sample under the other two models and compare (takes several minutes)")
    s.add_argument("--seed", type=int, default=1, help="random seed (default 1: the same report every time)")
    _sampler_options(s)
    s.add_argument("--json", action="store_true", help="print the summary, diagnostics and written files as JSON")
    s.set_defaults(func=cmd_report)

    s = sub.add_parser("plan", help="rank candidate extra measurements by how much they reduce uncertainty")
    s.add_argument("campaign", nargs="?", metavar="CAMPAIGN", help="campaign TOML (default: the built-in thesis campaign)")
    s.add_argument("--target", action="append", metavar="NAME",
                   help="quantity to make more certain (repeatable; default the eight identified quantities)")
    s.add_argument("--model", choices=MODEL_NAMES, default="linear",
                   help="forward model (default linear; htm models are linearised at zero)")
    s.add_argument("--candidates", metavar="FILE.toml", help="extra candidates of your own ([[candidate]] tables)")
    s.add_argument("--sigma-model-um", type=float, default=None,
                   help="fixed model-discrepancy sd of the closed form (default: rms of its prior, 2 µm)")
    s.add_argument("--sweep-pattern", choices=("CR", "CA", "BX", "BY"), default=None,
                   help="pattern of the tool-length sweep (default: that of the best tool-length candidate)")
    s.add_argument("-o", "--output", metavar="DIR", help="write plan.csv, plan.json and the figures to DIR")
    s.add_argument("--json", action="store_true", help="print JSON, best candidate first")
    s.set_defaults(func=cmd_plan)

    s = sub.add_parser("ncgen", help="measuring NC program of a ball-bar pattern (e.g. thesis Fig 4.30(a))")
    s.add_argument("pattern", metavar="PATTERN", help="one of BR BT BA BX BY BZ CR CT CA CX CY CZ")
    s.add_argument("campaign", nargs="?", metavar="CAMPAIGN", help="campaign whose setup geometry to use (default: thesis)")
    s.add_argument("--R-B-mm", dest="R_B_mm", type=float, default=None, help="tool length R_B, mm (default: the setup's)")
    s.add_argument("--x0", type=float, default=None, help="NC X of the first block, mm (with --z0)")
    s.add_argument("--y0", type=float, default=0.0, help="NC Y of the first block, mm (default 0)")
    s.add_argument("--z0", type=float, default=None, help="NC Z of the first block, mm (with --x0)")
    s.add_argument("--step-deg", type=float, default=2.5, help="B or C step, degrees (default 2.5)")
    s.add_argument("--feed", type=float, default=None, help="feed word F (default none)")
    s.add_argument("-n", type=int, default=None, help="number of blocks (default: 0–90° for B, one turn for C)")
    s.add_argument("--setup", default=None, help="campaign setup for R_B and the NC origin (default: that of BX)")
    s.add_argument("--mount", default=None, help="campaign mount for Z_C, R_C")
    s.add_argument("-o", "--output", metavar="FILE.nc", help="write the program to FILE (default: print)")
    s.set_defaults(func=cmd_ncgen)

    s = sub.add_parser("compensate", help="rewrite X/Y/Z of an NC program for the identified deviations, with uncertainty")
    s.add_argument("campaign", nargs="?", metavar="CAMPAIGN", help="campaign TOML (default: the built-in thesis campaign)")
    s.add_argument("program", metavar="PROGRAM.nc", help="NC program (G00/G01 blocks, absolute)")
    s.add_argument("-o", "--output", required=True, metavar="OUT.nc", help="compensated program")
    s.add_argument("--method", choices=("exact", "thesis"), default="exact",
                   help="exact inversion (default) or thesis Eqs 3.4–3.13 as printed (double correction)")
    s.add_argument("--model", choices=MODEL_NAMES, default="htm-thesis", help="kinematic model (default htm-thesis)")
    s.add_argument("--values", choices=("posterior", "ballbar"), default="posterior",
                   help="compensate with the posterior mean (default) or the deterministic ball-bar values")
    s.add_argument("--posterior", metavar="post.nc", help="posterior draws (from sample -o); default: closed form")
    s.add_argument("--point", choices=("tcp", "nose"), default="tcp",
                   help="compensate the tool centre point (default) or the spindle nose as the thesis does")
    s.add_argument("--setup", default=None, help="campaign setup of the tool (R_B, NC origin; default: that of BX)")
    s.add_argument("--mount", default=None, help="campaign mount (Z_C of the C-axis pivot)")
    s.add_argument("--json", action="store_true", help="print JSON: corrections, residuals, what is not compensable")
    s.set_defaults(func=cmd_compensate)

    s = sub.add_parser("validate", help="check the inference itself: simulation-based calibration")
    vsub = s.add_subparsers(dest="check", metavar="CHECK", parser_class=_Parser)
    vsub.required = True
    v = vsub.add_parser("sbc", help="simulation-based calibration (Talts et al. 2018): rank histograms, coverage")
    v.add_argument("campaign", nargs="?", metavar="CAMPAIGN",
                   help="campaign whose design (runs, repeats, priors) to simulate (default: thesis)")
    v.add_argument("--n", type=int, default=200, help="replicates: truths drawn from the prior (default 200)")
    v.add_argument("--model", choices=MODEL_NAMES, default="linear", help="forward model (default linear)")
    v.add_argument("--sampler", choices=("emcee", "exact"), default="emcee",
                   help="emcee (default: what sample/report use) or the exact linear posterior (checks SBC itself)")
    v.add_argument("--draws", type=int, default=99, help="posterior draws each truth is ranked among (default 99)")
    v.add_argument("--max-steps", type=int, default=4000, help="emcee step budget per ensemble (default 4000)")
    v.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                   help=f"parallel processes (default: the CPU count, {os.cpu_count() or 1})")
    v.add_argument("--seed", type=int, default=1, help="random seed (default 1)")
    v.add_argument("-o", "--output", metavar="DIR",
                   help="write sbc.json, sbc_summary.csv, sbc_replicates.csv, sbc_ranks.png, sbc_ecdf.png")
    v.add_argument("--json", action="store_true", help="print JSON: p_uniform and coverage_50/90/95 per quantity")
    v.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    v.set_defaults(func=cmd_validate_sbc)
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    args.argv = argv
    try:
        return args.func(args)
    except MtmcalError as exc:
        print(f"{PROG} {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into head & co.: stop quietly, like other Unix tools
        sys.stdout = None
        return 141
    except Exception as exc:  # an internal error: still one line unless debugging
        if os.environ.get("MTMCAL_DEBUG"):
            raise
        print(f"{PROG} {args.command}: internal error: {type(exc).__name__}: {exc} "
              "(set MTMCAL_DEBUG=1 for a traceback and please report it)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
