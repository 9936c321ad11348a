"""Follow the campaign down ``build_report``: which modules receive it, in what order, and how often it is rebuilt.

    python bench/campaign_walk.py [--data both|ballbar] [--list]

Every call of a package function whose arguments include the campaign object is recorded (``sys.setprofile``,
in this process: the figures drawn in forked workers are not followed).  The walk is the sequence of the modules
(files) of those calls in call order; a *move* is a step to another module, a *climb* a move to a module of a
higher layer (the layers of ``tests/test_architecture.py``).  It also counts how often the campaign is turned into
a parameter space (``ParameterSpace.for_campaign``), into observations (``Observations.from_campaign``) and into the
deterministic identification (the thesis plug-in's ``identification.identify``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_architecture import LAYER_OF  # noqa: E402

import mtmcal_bayes as mb  # noqa: E402
from mtmcal_bayes.reporting.build import build_report  # noqa: E402

PACKAGE = str(Path(mb.__file__).resolve().parent)


def _module(code) -> str | None:
    path = str(Path(code.co_filename).resolve())
    if not path.startswith(PACKAGE):
        return None
    rel = Path(path).relative_to(PACKAGE).with_suffix("")
    parts = [p for p in rel.parts if p != "__init__"]
    return ".".join(parts) or "__init__"


def _layer(module: str) -> int:
    return LAYER_OF[module.split(".")[0]]


def walk(campaign, data: str) -> tuple[list[tuple[str, str]], Counter]:
    """The (module, function) of every package call receiving ``campaign``, in call order, and the build counts."""
    seen: list[tuple[str, str]] = []
    builds: Counter = Counter()

    def profiler(frame, event, arg):
        if event != "call":
            return
        module = _module(frame.f_code)
        if module is None:
            return
        code = frame.f_code
        args = code.co_varnames[: code.co_argcount + code.co_kwonlyargcount]
        if any(frame.f_locals.get(a) is campaign for a in args):
            seen.append((module, code.co_qualname))
            if code.co_qualname == "ParameterSpace.for_campaign":
                builds["parameter space"] += 1
            elif code.co_qualname in ("Observations.from_campaign", "ProbeLayout.__init__"):
                builds["observations"] += 1
            elif module.startswith("plugins.thesis.identification") and code.co_qualname == "identify":
                builds["identification"] += 1

    with tempfile.TemporaryDirectory() as tmp:
        sys.setprofile(profiler)
        try:
            build_report(campaign, Path(tmp) / "rep", data=data)
        finally:
            sys.setprofile(None)
    return seen, builds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default="both", choices=["ballbar", "probe", "both"])
    ap.add_argument("--list", action="store_true", help="print the walk itself")
    args = ap.parse_args()
    campaign = mb.load_campaign()
    seen, builds = walk(campaign, args.data)
    modules = [m for m, _ in seen]
    moves = [(a, b) for a, b in zip(modules, modules[1:]) if a != b]
    climbs = [(a, b) for a, b in moves if _layer(b) > _layer(a)]
    if args.list:
        for m, f in seen:
            print(f"  {m:32s} {f}")
    print(f"report --data {args.data}: {len(seen)} calls receive the campaign, in {len(set(modules))} modules")
    print(f"moves between modules: {len(moves)}, climbing to a higher layer: {len(climbs)}")
    for what, n in sorted(builds.items()):
        print(f"campaign turned into {what}: {n}")


if __name__ == "__main__":
    main()
