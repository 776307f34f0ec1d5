"""cffi builder for mcgeom._mcgeom_cffi (out-of-line API mode).

Run by meson through ``python -m cffi.gen_src exec-python`` (cffi >= 2.1), which
executes this file and emits the C source of the extension. The declarations are
taken from the block of ``include/mcgeom.h`` between MCG_CDEF_BEGIN and
MCG_CDEF_END, so the header stays the single source of truth.
"""

import os
import re

import cffi

_HERE = os.path.dirname(os.path.abspath(__file__))
_HEADER = os.path.join(_HERE, "include", "mcgeom.h")


def _cdef_from_header(path: str) -> str:
    with open(path, encoding="utf-8") as f:
        text = f.read()
    m = re.search(r"MCG_CDEF_BEGIN.*?\*/(.*)/\*\s*MCG_CDEF_END", text, re.S)
    if m is None:
        raise RuntimeError(f"{path}: MCG_CDEF_BEGIN/END markers not found")
    return m.group(1)


ffibuilder = cffi.FFI()
ffibuilder.cdef(_cdef_from_header(_HEADER))
ffibuilder.set_source("mcgeom._mcgeom_cffi", '#include "mcgeom.h"\n')
