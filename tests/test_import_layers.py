"""Import structure of mcgeom: no import cycle, layers that import only
downwards, no library module importing the synthetic-data generator, no
private access across modules.

Read from the installed package with ``ast``, so that a new import cannot slip
in, whether at module level or inside a function.
A cycle through the package ``mcgeom/__init__.py`` (which imports the public
API, e.g. ``from . import estimate`` in demo.py) is allowed; any other is not,
including one through a subpackage's ``__init__`` (importing
``mcgeom.estimators._common`` runs ``mcgeom/estimators/__init__.py``, which
imports every estimator). Function-level (deferred) imports count too.
"""

from __future__ import annotations

import ast
from pathlib import Path

import mcgeom

SRC = Path(mcgeom.__file__).resolve().parent
SYNTH = {"mcgeom.synth", "mcgeom.synth_views", "mcgeom.synth_kinds"}


def _modules(src: Path = SRC) -> dict[str, Path]:
    out = {}
    for p in src.rglob("*.py"):
        parts = list(p.relative_to(src.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = p
    return out


def _graph(src: Path = SRC) -> dict[str, set[str]]:
    """Module -> the package modules it imports (``from X import y`` counts X.y
    when y is a submodule, and importing a submodule counts its packages)."""
    mods = _modules(src)
    graph: dict[str, set[str]] = {m: set() for m in mods}
    for mod, path in mods.items():
        is_pkg = path.name == "__init__.py"
        here = mod if is_pkg else mod.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = here.split(".")[: len(here.split(".")) - (node.level - 1)]
                    base = ".".join(base + ([node.module] if node.module else []))
                else:
                    base = node.module or ""
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in mods else base
                           for a in node.names]
            for t in targets:
                if t not in mods:
                    continue
                # importing a submodule first runs its parent packages' __init__
                # (not for a module inside that package: it is already running)
                parts = t.split(".")
                for k in range(2, len(parts) + 1):
                    dep = ".".join(parts[:k])
                    if dep != mod and not mod.startswith(dep + "."):
                        graph[mod].add(dep)
    graph.pop("mcgeom", None)
    for deps in graph.values():
        deps.discard("mcgeom")
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph.get(v, ()):
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycle():
    assert _cycles(_graph()) == []


def test_layers():
    """The façade sits above the library; I/O, the rig and its pixel-noise
    model, the verdict and the shared geometry below the estimators and the
    robust layer."""
    g = _graph()
    # the sequence pipeline runs the façade's robust two-frame pipeline per step
    apps = ("mcgeom.cli", "mcgeom.__main__", "mcgeom.experiments", "mcgeom.sequence")
    users_of_cv = {m for m in g if "mcgeom.cv" in g[m]}
    assert all(m.startswith(apps) for m in users_of_cv), users_of_cv
    io = [m for m in g if m.startswith("mcgeom.io")]
    for low in ("mcgeom.geometry", "mcgeom.observability", "mcgeom.metrics",
                "mcgeom.validation", "mcgeom.types", "mcgeom.rig", "mcgeom.pixel_noise", *io):
        above = ("mcgeom.estimators", "mcgeom.robust", "mcgeom.cv", "mcgeom.experiments",
                 *(() if low.startswith("mcgeom.io") else ("mcgeom.io",)))
        assert not any(d.startswith(above) for d in g[low]), (low, g[low])
    assert not any(d in ("mcgeom.robust", "mcgeom.cv") for m in g
                   if m.startswith("mcgeom.estimators") for d in g[m])


def _library(g: dict[str, set[str]]) -> list[str]:
    """Every module but the application layer (experiments: demo, benchmarks,
    experiments) and the synthetic-data generator itself."""
    return [m for m in g if not m.startswith("mcgeom.experiments") and m not in SYNTH]


def test_no_library_module_imports_synth():
    """Library code measures errors with mcgeom.metrics, never with synth."""
    g = _graph()
    assert "mcgeom.odometry" in _library(g) and "mcgeom.metrics" in g["mcgeom.odometry"]
    bad = {m: sorted(g[m] & SYNTH) for m in _library(g) if g[m] & SYNTH}
    assert not bad, f"library modules importing the synthetic-data generator: {bad}"


def test_the_graph_sees_every_form_of_import(tmp_path):
    pkg = tmp_path / "mcgeom"
    (pkg / "sub").mkdir(parents=True)
    for name in ("__init__.py", "synth.py", "synth_views.py", "sub/__init__.py"):
        (pkg / name).write_text("")
    forms = {"a.py": "from . import synth\n", "b.py": "from .synth import make_problem\n",
             "c.py": "import mcgeom.synth_views\n",
             "d.py": "def f():\n    from mcgeom import synth\n",
             "sub/e.py": "from ..synth import as_rng\n"}
    for name, text in forms.items():
        (pkg / name).write_text(text)
    g = _graph(pkg)
    for name in forms:
        mod = "mcgeom." + name[:-3].replace("/", ".")
        assert g[mod] & SYNTH, (name, g[mod])


_ALLOWED_OWNERS = {"self", "cls", "_core", "lib", "ffi"}   # _core: the cffi wrapper


def test_no_private_access_across_modules():
    """No ``obj._name`` on another module's object (self/cls aside) and no
    ``from .x import _name``: what crosses a module boundary is public API (a
    private module such as ``io/_common.py`` shares public names within its
    package)."""
    found = []
    for p in SRC.rglob("*.py"):
        rel = p.relative_to(SRC).as_posix()
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if (isinstance(node, ast.Attribute) and node.attr.startswith("_")
                    and not node.attr.startswith("__") and isinstance(node.value, ast.Name)
                    and node.value.id not in _ALLOWED_OWNERS):
                found.append(f"{rel}:{node.lineno}: {node.value.id}.{node.attr}")
            elif isinstance(node, ast.ImportFrom):
                found += [f"{rel}:{node.lineno}: import {a.name}" for a in node.names
                          if a.name.startswith("_") and not a.name.startswith("__")
                          and a.name != "_core"]
    assert found == []


DASK = ("dask", "distributed")


def _third_party_imports(path: Path) -> set[str]:
    """Top-level names of the absolute imports of a module, at any depth."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            names.add(node.module.split(".")[0])
    return names


def test_only_the_batch_package_imports_dask():
    """Dask is an optional extra: only mcgeom.batch (and the CLI's batch
    command, inside its function, after checking that Dask is there) may
    import it; the rest of mcgeom must import without it."""
    users = {m for m, p in _modules().items() if _third_party_imports(p) & set(DASK)}
    assert "mcgeom.batch.runner" in users
    assert users <= {"mcgeom.batch", "mcgeom.batch.runner", "mcgeom.cli"}, users
    # the CLI imports it lazily: not at module level
    tree = ast.parse((SRC / "cli.py").read_text(encoding="utf-8"))
    top = {a.name.split(".")[0] for n in tree.body if isinstance(n, ast.Import)
           for a in n.names}
    top |= {n.module.split(".")[0] for n in tree.body
            if isinstance(n, ast.ImportFrom) and not n.level and n.module}
    assert not top & set(DASK)
    # and nothing imports mcgeom.batch but the CLI and the experiments
    g = _graph()
    importers = {m for m in g if any(d == "mcgeom.batch" or d.startswith("mcgeom.batch.")
                                     for d in g[m]) and not m.startswith("mcgeom.batch")}
    assert importers <= {"mcgeom.cli"} | {m for m in g if m.startswith("mcgeom.experiments")}, \
        importers
