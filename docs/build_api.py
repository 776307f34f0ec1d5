#!/usr/bin/env python3
"""Build the API reference of the installed mcgeom from its docstrings (pdoc).

    python docs/build_api.py [--out DIR]      (default: build/api)

Every public module of the package is documented: those whose dotted name has
no component starting with an underscore (``mcgeom._core``, the only cffi
user, and private helpers are left out). Any warning pdoc raises -- a module
that fails to import, a docstring it cannot parse, a spec it cannot resolve --
is an error: CI runs this and fails on it.
"""
from __future__ import annotations

import argparse
import os
import pkgutil
import sys
import tempfile
import warnings
from pathlib import Path


def public_modules() -> list[str]:
    """The module specs to hand to pdoc: the package and its public direct
    children. pdoc walks a package spec itself (through its ``__all__`` if it
    has one), so children it reaches from ``mcgeom`` and grandchildren are
    not repeated (a repeated spec is a pdoc warning)."""
    import mcgeom

    reached = set(getattr(mcgeom, "__all__", ()))
    names = ["mcgeom"]
    for info in pkgutil.iter_modules(mcgeom.__path__):
        if not info.name.startswith("_") and info.name not in reached:
            names.append(f"mcgeom.{info.name}")
    return names


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("--out", type=Path, default=Path("build/api"), help="output folder")
    args = ap.parse_args(argv)
    warnings.simplefilter("error")          # warnings as errors
    import pdoc

    pdoc.render.configure(docformat="restructuredtext", show_source=False)
    modules = public_modules()
    out = args.out.resolve()
    # document the installed package: from a checkout's root, the spec "mcgeom"
    # would also name the source folder (a pdoc warning, hence an error here)
    with tempfile.TemporaryDirectory() as neutral:
        os.chdir(neutral)
        pdoc.pdoc(*modules, output_directory=out)
    print(f"API reference of {len(modules)} modules in {out}/index.html")
    return 0


if __name__ == "__main__":
    sys.exit(main())
