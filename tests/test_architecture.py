"""The package's structure: layers that import only downward, no import cycle, a thin CLI, single sources of facts.

Every ``import`` statement of every module is read from the source (those inside
functions too: a lazy import is still a dependency), so these tests fail as
soon as a change reaches the wrong way, whether or not the import runs.
"""

from __future__ import annotations

import ast
import functools
from collections.abc import Mapping
from pathlib import Path

import pytest

import mtmcal_bayes

PACKAGE = Path(mtmcal_bayes.__file__).parent

#: the allowed layer order, lowest first: a unit (top-level module or subpackage) may import only units of
#: lower layers; units of one layer are siblings and may not import each other
LAYERS: tuple[tuple[str, ...], ...] = (
    ("errors", "units", "progress", "version", "datasets", "arviz_import", "without_dask", "lazy_names"),  # foundation: nothing of the package
    ("parameters", "patterns", "sphere", "iso", "cluster"),        # quantity names (ISO symbols), patterns, sphere fit, Dask
    ("conventions", "machines"),                                   # what a ball-bar offset means in machine axes;
                                                                   # machines described: chains and location errors
    ("pattern_frames",),                                           # every machine's reading frames, from its chain
    ("campaign", "observations", "machine_time", "sigma_prior"),   # the data of a calibration, its machine time, a
                                                                   # σ_model prior learnt elsewhere
    ("io",),                                                       # files in and out
    ("models",),                                                   # forward models
    ("identification", "inference", "figure_style", "html_page"),  # DPRNT sphere fit, Bayesian engine, figure and page look
    ("analysis",),                                                 # one campaign's analysis, built once, passed down
    ("posterior", "planning", "compensation", "validation", "simulation", "histories"),  # features
    ("reporting",),                                                # the report, built on posterior and planning
    ("fleets",),                                                   # many machines on Dask: posteriors, histories, overview
    ("plugins",),                                                  # what is particular to one machine (SPEC §20), loaded by
                                                                   # name; imported by no other unit (below)
    ("api",),                                                      # the Python API: one function per command
    ("cli_options",),                                              # the command line's flags
    ("cli", "__init__"),                                           # the command line; the package's public face
)
LAYER_OF = {unit: i for i, layer in enumerate(LAYERS) for unit in layer}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


FILES = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _resolve(module: str, is_package: bool, node: ast.ImportFrom | ast.Import) -> list[str]:
    """The package modules an import statement of ``module`` names (a submodule where it is one)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name.split(".")[0] == "mtmcal_bayes"]
    if node.level == 0:
        base = node.module or ""
        if base.split(".")[0] != "mtmcal_bayes":
            return []
    else:
        parts = module.split(".")
        if not is_package:
            parts = parts[:-1]
        parts = parts[: len(parts) - (node.level - 1)]
        base = ".".join(parts + ([node.module] if node.module else []))
    out = []
    for alias in node.names:
        sub = f"{base}.{alias.name}"
        out.append(sub if sub in FILES else base)
    return out


@functools.cache
def _nodes(module: str) -> tuple[ast.AST, ...]:
    """Every node of ``module``'s syntax tree (``ast.walk`` order), parsed once for all the tests of this file (each
    reads every module; the nodes are only read)."""
    return tuple(ast.walk(ast.parse(FILES[module].read_text(encoding="utf-8"))))


def _imports() -> dict[str, set[str]]:
    """module -> the package modules it imports."""
    graph = {}
    for module, path in FILES.items():
        targets = set()
        for node in _nodes(module):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                targets.update(_resolve(module, path.name == "__init__.py", node))
        graph[module] = {t for t in targets if t in FILES and t != module}
    return graph


class _Graph(Mapping):
    """The import graph of :func:`_imports`, parsed when a test first reads it: each worker of ``pytest -n`` collects
    (imports) every test module, and parsing the whole package at collection cost each of them 0.3 s."""

    @functools.cached_property
    def _graph(self) -> dict[str, set[str]]:
        return _imports()

    def __getitem__(self, module: str) -> set[str]:
        return self._graph[module]

    def __iter__(self):
        return iter(self._graph)

    def __len__(self) -> int:
        return len(self._graph)


GRAPH = _Graph()


def unit(module: str) -> str:
    """Layer unit of a module: ``mtmcal_bayes.io.gcode`` -> ``io``; the package itself -> ``__init__``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def test_every_unit_has_a_layer():
    assert {unit(m) for m in FILES} <= set(LAYER_OF), sorted({unit(m) for m in FILES} - set(LAYER_OF))


def test_imports_only_go_down():
    upward = [f"{m} imports {t} ({unit(m)} is layer {LAYER_OF[unit(m)]}, {unit(t)} layer {LAYER_OF[unit(t)]})"
              for m, targets in GRAPH.items() for t in targets
              if unit(t) != unit(m) and LAYER_OF[unit(t)] >= LAYER_OF[unit(m)]]
    assert not upward, "\n".join(upward)


def test_no_import_cycle():
    index, low, stack, on_stack, cycles = {}, {}, [], set(), []

    def visit(v):  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in GRAPH[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in GRAPH:
        if v not in index:
            visit(v)
    assert not cycles, cycles


@pytest.mark.parametrize("importer,forbidden", [
    (("compensation", "validation", "inference"), "planning"),
    (("planning", "validation"), "reporting"),
    (("inference",), "identification"),
])
def test_named_sideways_imports_are_absent(importer, forbidden):
    bad = [f"{m} imports {t}" for m, targets in GRAPH.items() if unit(m) in importer
           for t in targets if unit(t) == forbidden]
    assert not bad, bad


def test_no_engine_layer_imports_the_plugins():
    """A plug-in holds one machine's own code (the thesis': its models, identification, compensation, program format,
    campaign keys) and is reached only through ``machines.plugins.provided``: no other unit imports it, neither the
    layers below it nor ``api`` and the command line above it (``__init__`` re-exports a few of its public names by
    module name, lazily, which is no import statement)."""
    bad = [f"{m} imports {t}" for m, targets in GRAPH.items() if unit(m) != "plugins"
           for t in targets if unit(t) == "plugins"]
    assert not bad, "\n".join(bad)


def test_layer_test_sees_real_imports():
    """The graph is read correctly: known downward imports are in it (a test that finds nothing proves nothing)."""
    assert "mtmcal_bayes.planning.plan" in GRAPH["mtmcal_bayes.reporting.build"]
    assert "mtmcal_bayes.inference.marginal" in GRAPH["mtmcal_bayes.validation.samplers"]
    assert "mtmcal_bayes.units" in GRAPH["mtmcal_bayes.parameters"]  # from . import units
    assert "mtmcal_bayes.api" in GRAPH["mtmcal_bayes.cli"]
    # inside a plug-in, and from it down to the engine (relative imports three and four levels up)
    assert "mtmcal_bayes.plugins.thesis.kinematic" in GRAPH["mtmcal_bayes.plugins.thesis.linear"]
    assert "mtmcal_bayes.compensation.values" in GRAPH["mtmcal_bayes.plugins.thesis.compensation.values"]
    assert "mtmcal_bayes.plugins.thesis.htm" in GRAPH["mtmcal_bayes.plugins.thesis.kinematic"]


# --------------------------------------------------------------------------- the command line
CLI = FILES["mtmcal_bayes.cli"]
CLI_TREE = ast.parse(CLI.read_text(encoding="utf-8"))


def test_cli_is_thin():
    assert len(CLI.read_text(encoding="utf-8").splitlines()) < 300
    commands = [f for f in CLI_TREE.body if isinstance(f, ast.FunctionDef) and f.name.startswith("cmd_")]
    assert len(commands) >= 10
    long = {f.name: f.end_lineno - f.lineno + 1 for f in commands if f.end_lineno - f.lineno + 1 > 11}
    assert not long, long


def test_cli_calls_the_api_only():
    """The CLI reaches the library through ``api`` (and the errors, the model names, progress and JSON printing, and
    the process set-up that keeps Dask out of the commands that do not use it)."""
    allowed = {"mtmcal_bayes.api", "mtmcal_bayes.errors", "mtmcal_bayes.models", "mtmcal_bayes.progress",
               "mtmcal_bayes.version", "mtmcal_bayes.io.json_text", "mtmcal_bayes.cli_options",
               "mtmcal_bayes.without_dask"}
    assert GRAPH["mtmcal_bayes.cli"] <= allowed, GRAPH["mtmcal_bayes.cli"] - allowed


def test_library_errors_do_not_name_cli_flags():
    """Messages name API parameters (``ParameterError``); only the CLI knows its flags."""
    offenders = []
    for module in FILES:
        if module == "mtmcal_bayes.cli":
            continue
        for node in _nodes(module):
            if isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", "")).endswith("Error"):
                for arg in node.args:
                    for s in ast.walk(arg):
                        if isinstance(s, ast.Constant) and isinstance(s.value, str) and " --" in f" {s.value}":
                            offenders.append(f"{module}:{node.lineno}: {s.value[:60]!r}")
    assert not offenders, offenders


# --------------------------------------------------------------------------- signatures and single sources
def _functions():
    for module in FILES:
        for node in _nodes(module):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                yield module, node


def test_long_signatures_are_keyword_only():
    """A function taking more than four arguments takes at most four positionally."""
    bad = []
    for module, f in _functions():
        positional = [a.arg for a in f.args.posonlyargs + f.args.args if a.arg not in ("self", "cls")]
        total = len(positional) + len(f.args.kwonlyargs)
        if total > 4 and len(positional) > 4:
            bad.append(f"{module}.{f.name}({', '.join(positional)}, ...)")
    assert not bad, "\n".join(bad)


def _literals(kind):
    for module in FILES:
        for node in _nodes(module):
            if isinstance(node, kind):
                yield module, node


def _strings(node) -> set[str]:
    elts = node.keys if isinstance(node, ast.Dict) else node.elts
    return {e.value for e in elts if isinstance(e, ast.Constant) and isinstance(e.value, str)}


def test_derived_quantity_weights_are_defined_once():
    places = [m for m, d in _literals(ast.Dict) if _strings(d) == {"dx_CZ", "dx_BT"}]
    assert places == ["mtmcal_bayes.parameters"], places


def test_one_model_registry():
    places = [m for m, t in _literals((ast.Tuple, ast.List, ast.Dict, ast.Set))
              if {"htm-literal", "htm-thesis"} <= _strings(t)]
    assert places == ["mtmcal_bayes.models"], places
    tests = Path(__file__).parent
    copies = [p.name for p in tests.glob("*.py") if p.name != Path(__file__).name
              and '("linear", "htm-literal", "htm-thesis")' in p.read_text(encoding="utf-8")]
    assert not copies, f"tests keep their own list of models: {copies} (use mtmcal_bayes.MODELS)"


def test_units_are_converted_by_the_units_module():
    """No hand-written µm/mm factor: ``x * 1e3`` and friends go through :mod:`mtmcal_bayes.units`."""
    factors = {1e3, 1e-3, 1000, 0.001}
    bad = [f"{m}:{n.lineno}" for m, n in _literals(ast.BinOp)
           if m != "mtmcal_bayes.units" and isinstance(n.op, (ast.Mult, ast.Div))
           and any(isinstance(x, ast.Constant) and type(x.value) in (int, float) and x.value in factors
                   for x in (n.left, n.right))]
    assert not bad, bad


def test_no_global_plotting_state_and_one_arviz_import():
    bad = []
    for module, node in _literals((ast.Import, ast.ImportFrom, ast.Call)):
        if isinstance(node, ast.Call):
            if isinstance(node.func, ast.Attribute) and node.func.attr == "use" and \
                    getattr(node.func.value, "id", "") == "matplotlib":
                bad.append(f"{module}: matplotlib.use")
            continue
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
        if any(n == "matplotlib.pyplot" for n in names):
            bad.append(f"{module}: imports matplotlib.pyplot")
        if any(n.split(".")[0] == "arviz" for n in names) and module != "mtmcal_bayes.arviz_import":
            bad.append(f"{module}: imports arviz itself")
    assert not bad, bad
