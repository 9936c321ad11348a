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


# --------------------------------------------------------------------------- parser
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
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except MtmcalError as exc:
        print(f"{PROG} {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # an internal error: still one line unless debugging
        if os.environ.get("MTMCAL_DEBUG"):
            raise
        print(f"{PROG} {args.command}: internal error: {type(exc).__name__}: {exc} "
              "(set MTMCAL_DEBUG=1 for a traceback and please report it)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
