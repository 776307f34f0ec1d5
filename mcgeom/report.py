"""Writing trajectories: CSV files and a PNG plot drawn with OpenCV (no math here
beyond mapping metres to pixels)."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import cv2
import numpy as np

__all__ = ["write_trajectory_csv", "plot_trajectories_png"]


def write_trajectory_csv(path: str | Path, poses: Sequence[np.ndarray]) -> None:
    """One row per world_from_rig pose: index, x, y, z (m), then the 9 rotation entries."""
    rows = [[i, *T[:3, 3], *T[:3, :3].ravel()] for i, T in enumerate(poses)]
    header = "index,x,y,z,r00,r01,r02,r10,r11,r12,r20,r21,r22"
    np.savetxt(path, np.asarray(rows), delimiter=",", header=header, comments="",
               fmt=["%d"] + ["%.9g"] * 12)


def plot_trajectories_png(path: str | Path, curves: dict, size: int = 900,
                          title: str = "") -> None:
    """Top view (x, y) of several trajectories, ``curves`` = {label: (poses, BGR colour)}."""
    pts = {k: np.array([T[:2, 3] for T in v[0]]) for k, v in curves.items()}
    allp = np.vstack(list(pts.values()))
    lo, hi = allp.min(0), allp.max(0)
    span = float(max(hi - lo)) or 1.0
    margin = 60
    scale = (size - 2 * margin) / span
    img = np.full((size, size, 3), 255, np.uint8)

    def px(p):
        q = (p - lo) * scale + margin
        return int(round(q[0])), int(round(size - q[1]))  # y up

    for i, (label, (poses, colour)) in enumerate(curves.items()):
        p = pts[label]
        for a, b in zip(p[:-1], p[1:]):
            cv2.line(img, px(a), px(b), colour, 2, cv2.LINE_AA)
        for q in p:
            cv2.circle(img, px(q), 3, colour, -1, cv2.LINE_AA)
        cv2.putText(img, label, (20, 30 + 25 * i), cv2.FONT_HERSHEY_SIMPLEX, 0.7, colour, 2,
                    cv2.LINE_AA)
    if title:
        cv2.putText(img, title, (20, size - 20), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 0), 1,
                    cv2.LINE_AA)
    bar = 10 ** np.floor(np.log10(span / 4))
    x0, y0 = size - margin - int(bar * scale), size - 40
    cv2.line(img, (x0, y0), (x0 + int(bar * scale), y0), (0, 0, 0), 2)
    cv2.putText(img, f"{bar:g} m", (x0, y0 - 8), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1)
    if not cv2.imwrite(str(path), img):
        raise OSError(f"could not write {path}")
