"""The manifest of a batch: a CSV file with one row per sequence.

The header starts with ``name,rig,images,gt`` (``gt`` may be left empty on a
row: no ground truth, no errors); further columns carry per-sequence options
of :func:`mcgeom.sequence.run.run_odometry`, each optional and empty for its
default: ``start``, ``end``, ``step``, ``features`` (``sift`` / ``orb``),
``n_features``, ``threshold`` (pixels), ``cross_camera`` (``true`` /
``false``), ``rig_frame`` (``body``, ``camera:NAME`` or ``camera:INDEX``: the
rig frame of the motions, as ``mcgeom odometry --rig-frame``) and
``calibration_check`` (``sampled`` / ``first_order``, as ``mcgeom odometry
--calibration-check``). Paths are relative to the manifest's folder (absolute ones are
kept); they are resolved here and not opened: a missing images folder is the
failure of that one sequence, not of the batch.

Every problem of the file itself (header, an empty required cell, a value
that is not a number, a duplicate name) is a ValueError naming the line and
the column, before any work starts.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional

__all__ = ["REQUIRED_COLUMNS", "OPTION_COLUMNS", "ManifestEntry", "read_manifest"]

#: the first columns of the header, in this order
REQUIRED_COLUMNS = ("name", "rig", "images", "gt")


def _int(lower: int) -> Callable[[str], int]:
    def parse(text: str) -> int:
        value = int(text)
        if value < lower:
            raise ValueError(f"expected an integer >= {lower}")
        return value
    parse.__doc__ = f"an integer >= {lower}"
    return parse


def _positive_float(text: str) -> float:
    """a positive number"""
    value = float(text)
    if not math.isfinite(value) or value <= 0:
        raise ValueError("expected a positive number")
    return value


def _features(text: str) -> str:
    """sift or orb"""
    if text not in ("sift", "orb"):
        raise ValueError("expected sift or orb")
    return text


def _boolean(text: str) -> bool:
    """true or false"""
    low = text.lower()
    if low in ("true", "1", "yes"):
        return True
    if low in ("false", "0", "no"):
        return False
    raise ValueError("expected true or false")


def _rig_frame(text: str) -> str:
    """body or camera:NAME or camera:INDEX"""
    if text == "body" or (text.startswith("camera:") and len(text) > len("camera:")):
        return text
    raise ValueError("expected body, camera:NAME or camera:INDEX")


def _calibration_check(text: str) -> str:
    """sampled or first_order (first-order too)"""
    value = text.replace("-", "_")
    if value in ("sampled", "first_order"):
        return value
    raise ValueError("expected sampled or first_order")


#: option column -> parser of its cell (the keyword of run_odometry is the name)
OPTION_COLUMNS: dict[str, Callable[[str], Any]] = {
    "start": _int(0), "end": _int(1), "step": _int(1), "features": _features,
    "n_features": _int(1), "threshold": _positive_float, "cross_camera": _boolean,
    "rig_frame": _rig_frame, "calibration_check": _calibration_check,
}


@dataclass(frozen=True)
class ManifestEntry:
    """One sequence of a batch: its ``name`` (the output folder ``DIR/<name>``),
    absolute paths of the ``rig`` file, the ``images`` folder and the ``gt``
    TUM file (None: no ground truth), the keyword ``options`` of
    :func:`mcgeom.sequence.run.run_odometry` given on its row, and ``line``,
    its line in the manifest."""

    name: str
    rig: Path
    images: Path
    gt: Optional[Path] = None
    options: dict = field(default_factory=dict)
    line: int = 0

    def identity(self) -> dict:
        """What makes the work of this entry: its paths and options (as text,
        for the done-marker; an entry whose identity changed is run again)."""
        return {"name": self.name, "rig": str(self.rig), "images": str(self.images),
                "gt": None if self.gt is None else str(self.gt),
                "options": {k: self.options[k] for k in sorted(self.options)}}


def _check_name(name: str, where: str) -> str:
    # the name becomes a folder of the output: one path component, not hidden
    # (hidden names are the partial folders of the atomic writes)
    if not name:
        raise ValueError(f"{where}: the name is empty")
    if (name in (".", "..") or name.startswith(".") or "/" in name or "\\" in name
            or "\0" in name):
        raise ValueError(f"{where}: the name {name!r} cannot be a folder name (no '/', "
                         f"'\\', leading '.')")
    return name


def read_manifest(path: Any) -> list[ManifestEntry]:
    """Read and check a manifest (see the module docstring); the entries in
    file order. ValueError naming the line and column of what is wrong."""
    try:
        path = Path(path)
    except TypeError:
        raise ValueError(f"manifest must be a path, got {path!r}") from None
    if not path.is_file():
        raise ValueError(f"manifest {str(path)!r} is not a file")
    base = path.resolve().parent
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except UnicodeDecodeError as exc:
        raise ValueError(f"manifest {str(path)!r} is not UTF-8 text ({exc.reason})") from None
    except csv.Error as exc:
        raise ValueError(f"manifest {str(path)!r}: not a CSV file ({exc})") from None
    if not rows:
        raise ValueError(f"manifest {str(path)!r} is empty (expected the header "
                         f"{','.join(REQUIRED_COLUMNS)})")
    header = [h.strip() for h in rows[0]]
    if tuple(header[:4]) != REQUIRED_COLUMNS:
        raise ValueError(f"manifest {str(path)!r} line 1: the header must start with "
                         f"{','.join(REQUIRED_COLUMNS)}, got {','.join(header)}")
    extra = header[4:]
    for col in extra:
        if col not in OPTION_COLUMNS:
            raise ValueError(f"manifest {str(path)!r} line 1: unknown column {col!r} (options: "
                             f"{', '.join(OPTION_COLUMNS)})")
    if len(set(header)) != len(header):
        raise ValueError(f"manifest {str(path)!r} line 1: a column appears twice")
    entries: list[ManifestEntry] = []
    seen: dict[str, int] = {}
    for lineno, row in enumerate(rows[1:], start=2):
        if not any(c.strip() for c in row):
            continue                                  # blank line
        where = f"manifest {str(path)!r} line {lineno}"
        if len(row) != len(header):
            raise ValueError(f"{where}: {len(row)} columns, the header has {len(header)}")
        cells = dict(zip(header, (c.strip() for c in row)))
        name = _check_name(cells["name"], f"{where} column 'name'")
        if name in seen:
            raise ValueError(f"{where} column 'name': duplicate name {name!r} (first on line "
                             f"{seen[name]})")
        seen[name] = lineno
        for col in ("rig", "images"):
            if not cells[col]:
                raise ValueError(f"{where} column {col!r}: empty (a path is required)")
        options = {}
        for col in extra:
            if cells[col]:
                try:
                    options[col] = OPTION_COLUMNS[col](cells[col])
                except ValueError:
                    raise ValueError(f"{where} column {col!r}: expected "
                                     f"{OPTION_COLUMNS[col].__doc__}, got "
                                     f"{cells[col]!r}") from None
        if "end" in options and options["end"] <= options.get("start", 0):
            raise ValueError(f"{where} column 'end': {options['end']} is not after start "
                             f"{options.get('start', 0)}")
        entries.append(ManifestEntry(name, base / cells["rig"], base / cells["images"],
                                     base / cells["gt"] if cells["gt"] else None,
                                     options, lineno))
    if not entries:
        raise ValueError(f"manifest {str(path)!r} has no sequence (only the header)")
    return entries
