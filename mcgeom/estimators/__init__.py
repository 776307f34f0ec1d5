"""Built-in estimator plugins; importing this package registers them all.

Every public module of this folder is imported here, in name order, and
registers its estimators with :func:`mcgeom.registry.register` when imported:
adding an estimator is adding its module (no list to keep here). Modules
whose name starts with an underscore are shared helpers, imported by the
estimators that need them.
"""

import importlib
import pkgutil

__all__ = sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_"))
for _name in __all__:
    importlib.import_module(f"{__name__}.{_name}")
