"""The ``mtmcal-bayes`` command line: parse the arguments, call one API function, print its result.

Every command works without a campaign argument on the built-in thesis campaign.  ``--json`` prints a
result's ``to_json()``, otherwise its ``to_text()``.  Problems with the input are one line on stderr and exit
status 2, never a traceback; an API parameter named in an error is shown as the flag that sets it (set
``MTMCAL_DEBUG=1`` to see a traceback for an unexpected internal error).
"""

from __future__ import annotations

import atexit
import gc
import os
import sys
import time
from typing import NoReturn

# One BLAS thread (unless the user chose otherwise), set before numpy starts: the matrices here are small (tens of
# parameters), so a second thread gains nothing, and the report draws its figures in two forked processes on a
# 2-core machine while this process plans, where OpenBLAS threads spinning against them made the plan 3x slower.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from . import api, cli_options  # noqa: E402 - after the BLAS threads are chosen
from .cli_options import PROG, flag_of
from .errors import MtmcalError, ParameterError, StepFailure
from .io.json_text import json_text
from .progress import StderrProgress
from .without_dask import hide_dask


def _show(result, args) -> int:
    markdown = getattr(args, "markdown", False)
    print(result.to_markdown() if markdown else json_text(result.to_json()) if args.json else result.to_text())
    return 0


def _warn(warnings) -> None:
    print("".join(f"WARNING: {w}\n" for w in warnings), end="", file=sys.stderr)


# --------------------------------------------------------------------------- commands
def cmd_identify(args) -> int:
    return _show(api.identify(args.campaign), args)


def cmd_probe_fit(args) -> int:
    return _show(api.probe_fit(args.file, stylus_radius_mm=args.stylus_radius_mm), args)


def _simulate_history(args) -> int:
    series = api.simulate_history(
        args.campaign, truth=args.truth, n=args.campaigns, every_days=args.every_days, start=args.start,
        steps=args.step or (), ramps=args.ramp or (), serial=args.serial, model=args.model, seed=args.seed or 0,
        output=args.history, temperatures=args.temperatures, thermal=args.thermal or (), machine_type=args.machine_type)
    print(f"wrote {len(series)} campaigns of machine {args.serial} to {args.history}/, simulated from "
          f"{series.truth_source}")
    return 0


def cmd_simulate(args) -> int:
    if args.history:
        return _simulate_history(args)
    sim = api.simulate(args.campaign, truth=args.truth, model=args.model, noise=args.noise, seed=args.seed,
                       output=args.output)
    _warn(sim.warnings)
    return _show(sim, args)


def cmd_history(args) -> int:
    result = api.history(args.campaigns, model=args.model, seed=args.seed, tolerances=args.tolerances,
                         output=args.output, trend=args.trend, data=args.data)
    return _show(result, args)


def cmd_sensitivity(args) -> int:
    return _show(api.sensitivity(args.campaign, model=args.model), args)


def cmd_sample(args) -> int:
    if args.closed_form:
        return _show(api.closed_form(args.campaign, sigma_model_um=args.sigma_model_um or 0.0, fix_dx_BT=args.fix_dx_BT,
                                     model=args.model, sigma_model_prior=args.sigma_model_prior), args)
    result = api.sample(args.campaign, model=args.model, seed=args.seed, fix_dx_BT=args.fix_dx_BT,
                        target_ess=args.target_ess, sampler=args.sampler, max_steps=args.max_steps,
                        checkpoint=args.checkpoint, output=args.output, progress=None if args.quiet else StderrProgress(), data=args.data,
                        tolerances=args.tolerances, sigma_model_um=args.sigma_model_um, sigma_model_prior=args.sigma_model_prior)
    _warn(result.warnings)
    return _show(result, args)


def cmd_report(args) -> int:
    command = " ".join([PROG] + (sys.argv[1:] if args.argv is None else args.argv))
    rep = api.report(args.campaign, output=args.output, model=args.model, seed=args.seed, fix_dx_BT=args.fix_dx_BT,
                     compare_models=args.compare_models, target_ess=args.target_ess, sampler=args.sampler,
                     max_steps=args.max_steps, progress=None if args.quiet else StderrProgress(), command=command, data=args.data,
                     tolerances=args.tolerances, sigma_model_um=args.sigma_model_um, sigma_model_prior=args.sigma_model_prior)
    _warn(rep.posterior.warnings)
    return _show(rep, args)


def cmd_plan(args) -> int:
    return _show(api.plan(args.campaign, targets=args.targets, model=args.model, candidates=args.candidates,
                          sigma_model_um=args.sigma_model_um, sweep_pattern=args.sweep_pattern, output=args.output,
                          data=args.data, sigma_model_prior=args.sigma_model_prior, times=args.times),
                 args)


def _targets(items) -> dict | None:
    """``--target NAME=SD`` flags as ``{NAME: SD}``."""
    if not items:
        return None
    out = {}
    for item in items:
        name, eq, sd = item.partition("=")
        if not eq or not name.strip():
            raise ParameterError("targets", f"{item!r}: expected NAME=SD, e.g. alpha_XB=2 (″) or dy_CZ=5 (µm)")
        try:
            out[name.strip()] = float(sd)
        except ValueError:
            raise ParameterError("targets", f"{item!r}: {sd!r} is not a number") from None
    return out


def cmd_design(args) -> int:
    return _show(api.design(args.campaign, targets=_targets(args.targets), tolerances=args.tolerances,
                            budget_min=args.budget_min, contraction=None if args.contraction == 0 else args.contraction,
                            candidates=args.candidates, times=args.times, seed=args.seed, model=args.model,
                            output=args.output, sigma_model_prior=args.sigma_model_prior,
                            instruments=args.instruments), args)


def cmd_next(args) -> int:
    return _show(api.next_run(args.campaign, targets=_targets(args.targets), contraction=args.contraction,
                              budget_min=args.budget_min, candidates=args.candidates, times=args.times, seed=args.seed,
                              model=args.model, output=args.output, sigma_model_prior=args.sigma_model_prior,
                              instruments=args.instruments), args)


def cmd_ncgen(args) -> int:
    if (args.x0 is None) != (args.z0 is None):
        raise MtmcalError("--x0 and --z0 go together (the NC position of the first block)")
    if (args.run is not None or args.probe is not None or args.rtest is not None) and args.campaign is None:  # the one positional: CAMPAIGN
        args.campaign, args.pattern = args.pattern, None
    text = api.ncgen(args.pattern, campaign=args.campaign, R_B_mm=args.R_B_mm, start=None if args.x0 is None else (
        args.x0, args.y0, args.z0), step_deg=args.step_deg, feed=args.feed, n=args.n, setup=args.setup, mount=args.mount,
        run=args.run, probe=args.probe, rtest=args.rtest, arc_deg=args.arc_deg, hold_deg=dict(args.hold_deg or {}) or None,
        dwell_ms=args.dwell_ms, output=args.output)
    sys.stdout.write("" if args.output else text)
    return 0


def cmd_instruments(args) -> int:
    return _show(api.instruments(args.campaign), args)


def cmd_axes(args) -> int:
    if args.format == "isg-csv":
        text = api.isg_csv(args.campaign, data=args.data, seed=args.seed, output=args.output)
        print(text if args.output is None else f"wrote {args.output}: position errors in the ISG CSV format", end=""
              if args.output is None else "\n")
        return 0
    return _show(api.axis_lines(args.campaign, data=args.data, seed=args.seed, csv=args.csv), args)


def cmd_compensate(args) -> int:
    result = api.compensate(args.program, campaign=args.campaign, output=args.output, method=args.method,
                            model=args.model, values=args.values, posterior=args.posterior, point=args.point,
                            setup=args.setup, mount=args.mount, integer_unit=args.integer_unit,
                            accept_disagreement=args.accept_disagreement)
    _warn(result.warnings)
    return _show(result, args)


def cmd_validate_sbc(args) -> int:
    t0 = time.perf_counter()
    _show(api.sbc(args.campaign, n=args.n, model=args.model, sampler=args.sampler, n_ranked=args.n_ranked, data=args.data,
                  max_steps=args.max_steps, workers=args.workers, seed=args.seed, output=args.output,
                  scheduler=args.scheduler, progress=None if args.quiet else StderrProgress()), args)
    if not args.quiet:
        print(f"sbc: done in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    return 0


def cmd_fleet(args) -> int:
    result = api.fleet(args.directory, scheduler=args.scheduler, workers=args.workers, seed=args.seed,
                       model=args.model, output=args.output, cache=args.cache, sampler=args.sampler,
                       target_ess=args.target_ess, max_steps=args.max_steps, tolerances=args.tolerances,
                       progress=None if args.quiet else StderrProgress())
    for e in result.errors:
        print(f"{PROG} fleet: error: {e['message']}", file=sys.stderr)
    _show(result, args)
    return result.exit_status


def build_parser():
    """The argument parser, each command run by its ``cmd_*`` function (:mod:`mtmcal_bayes.cli_options`)."""
    return cli_options.build_parser({
        "identify": cmd_identify, "probe-fit": cmd_probe_fit, "simulate": cmd_simulate, "sensitivity": cmd_sensitivity,
        "sample": cmd_sample, "history": cmd_history, "report": cmd_report, "plan": cmd_plan, "design": cmd_design, "next": cmd_next, "ncgen": cmd_ncgen, "compensate": cmd_compensate, "instruments": cmd_instruments, "axes": cmd_axes,
        "sbc": cmd_validate_sbc, "fleet": cmd_fleet})


#: the commands that run work on a Dask cluster (``fleet``, ``validate sbc``)
USES_DASK = frozenset({"fleet", "validate"})
#: the commands that may run for minutes (histories, fleets, validations): their process keeps the cyclic collector
LONG_RUNNING = frozenset({"history", "fleet", "validate"})


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    args.argv = argv
    if argv is None and args.command not in USES_DASK:
        hide_dask(f"{PROG} {args.command}")
    short = argv is None and args.command not in LONG_RUNNING
    if short:
        # a command that ends in seconds: Python's cyclic collector walks every object it has imported, again and
        # again, 5-10 % of its time, for cycles that would be freed at exit anyway (peak memory measured unchanged)
        gc.disable()
    code = _run(args, process=argv is None)
    if short:
        _exit_now(code)
    return code


def _exit_now(code: int) -> NoReturn:
    """End the process with ``code`` once its work is done: the exit handlers run and the output is flushed, but
    Python's teardown of every object and module it has loaded (0.3 s of a 5 s report, a fifth of the import time;
    the memory goes back to the system with the process either way) is skipped.  Every file the commands write is
    closed before they return."""
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (AttributeError, OSError, ValueError):  # no stream (a closed pipe: see BrokenPipeError below)
            pass
    os._exit(code)


def _run(args, *, process: bool) -> int:
    """Run the parsed command; its exit status (errors as one line on stderr, status 2).  ``process``: the command
    line's own process, which an interruption ends at once."""
    if getattr(args, "demo", None) and not getattr(args, "machine", None):
        args.parser.error("--demo needs --machine TYPE")
    if getattr(args, "machine", None) and args.campaign:
        args.parser.error("give a CAMPAIGN or --machine, not both")
    try:
        if getattr(args, "machine", None):
            args.campaign = (api.rtest_demo_campaign if args.demo == "rtest" else api.demo_campaign)(args.machine)
        return args.func(args)
    except ParameterError as exc:
        print(f"{PROG} {args.command}: error: {flag_of(args.parser, exc.parameter)}: {exc.message}", file=sys.stderr)
        return 2
    except MtmcalError as exc:
        print(f"{PROG} {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        # the command line's process ends here, while the interrupted frames are alive: freeing them would run the
        # finalisers of objects the interrupt left half-made (a Dask future's prints an "ignored" traceback)
        if process:
            _exit_now(130)
        return 130
    except BrokenPipeError:  # output piped into head & co.: stop quietly, like other Unix tools
        sys.stdout = None
        return 141
    except StepFailure as exc:  # an internal error in another process: the step it stopped, and its traceback there
        if os.environ.get("MTMCAL_DEBUG"):
            print(exc.trace, end="", file=sys.stderr)
        print(f"{PROG} {args.command}: internal error in {exc.step}: {exc.kind}: {exc.message} "
              "(set MTMCAL_DEBUG=1 for a traceback and please report it)", file=sys.stderr)
        return 1
    except Exception as exc:  # an internal error: still one line unless debugging
        if os.environ.get("MTMCAL_DEBUG"):
            raise
        print(f"{PROG} {args.command}: internal error: {type(exc).__name__}: {exc} "
              "(set MTMCAL_DEBUG=1 for a traceback and please report it)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
