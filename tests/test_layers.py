"""Layering of the installed package: no library module imports the synthetic-data
generator (mcgeom.synth, mcgeom.synth_views). Only the application layer
(mcgeom.experiments: demo, benchmarks, experiments) and the synth modules
themselves may; library code measures errors with mcgeom.metrics.

Checked on the imports as written (ast), so that a new import cannot slip in,
whether at module level or inside a function."""

from __future__ import annotations

import ast
from pathlib import Path

import mcgeom

PACKAGE = Path(mcgeom.__file__).parent
SYNTH = {"synth", "synth_views"}


def _module_name(path: Path, root: Path) -> str:
    parts = path.relative_to(root.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imported(path: Path, root: Path = PACKAGE) -> set[str]:
    """Absolute names of every module imported in ``path``, a file of the package
    at ``root`` (``from X import y`` gives X and X.y: y may be a submodule)."""
    name = _module_name(path, root)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module
            out.add(mod)
            out.update(f"{mod}.{a.name}" for a in node.names)
    return out


def _library_modules() -> list[Path]:
    return [p for p in sorted(PACKAGE.rglob("*.py"))
            if "experiments" not in p.relative_to(PACKAGE).parts and p.stem not in SYNTH]


def test_the_checker_sees_every_form_of_import(tmp_path):
    pkg = tmp_path / "mcgeom"
    (pkg / "sub").mkdir(parents=True)
    forms = {"a.py": "from . import synth\n", "b.py": "from .synth import make_problem\n",
             "c.py": "import mcgeom.synth_views\n", "d.py": "def f():\n    from mcgeom import synth\n",
             "sub/e.py": "from ..synth import as_rng\n"}
    for name, text in forms.items():
        (pkg / name).write_text(text)
    for name in forms:
        assert _imported(pkg / name, pkg) & {"mcgeom.synth", "mcgeom.synth_views"}, name


def test_no_library_module_imports_synth():
    modules = _library_modules()
    assert any(p.name == "odometry.py" for p in modules)   # the walk found the package
    bad = {str(p.relative_to(PACKAGE)): sorted(_imported(p) & {f"mcgeom.{s}" for s in SYNTH})
           for p in modules}
    bad = {k: v for k, v in bad.items() if v}
    assert not bad, f"library modules importing the synthetic-data generator: {bad}"


def test_odometry_uses_metrics():
    assert "mcgeom.metrics" in _imported(PACKAGE / "odometry.py")
