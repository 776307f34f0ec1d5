"""Bad input, end to end (issue 7): one test per row of the table in docs/bad_input.md.

Every row runs through the public entry points: ``mcgeom.cv.estimate`` /
``mcgeom.estimateRigMotion`` for pixels, ``mcgeom.estimate(rays, name)`` for
EVERY registered estimator (``mcgeom.registry.names()``) where the row applies,
``mcgeom.load_rig`` for files. The rows live here (``@row``); the table in
docs/bad_input.md is generated from them (``MCGEOM_WRITE_BAD_INPUT_TABLE=1 pytest tests/test_bad_input.py -k table``)
and ``test_table_lists_exactly_the_rows`` checks that the two agree.
"""

from __future__ import annotations

import functools
import os
import re
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

import mcgeom
from mcgeom import cv, metrics, synth
from mcgeom.rig import Camera, Rig
from mcgeom.types import RayPairs

ROOT = Path(__file__).resolve().parent.parent
TABLE = ROOT / "docs" / "bad_input.md"
CALIB = Path(__file__).resolve().parent / "data" / "calibration"

#: (id, input, what it gets) in table order
ROWS: list[tuple[str, str, str]] = []


def row(rid: str, given: str, gets: str) -> Callable:
    """Register a table row; the decorated function is its test."""
    assert re.fullmatch(r"[a-z0-9-]+", rid) and rid not in [r[0] for r in ROWS], rid
    ROWS.append((rid, given, gets))

    def deco(fn: Callable) -> Callable:
        fn.row_id = rid
        return fn
    return deco


# ------------------------------------------------------------------ data

#: 0.3 px of noise on a 4-camera ring (f = 800 px): every estimator gets R
#: within a few hundredths of a degree; these tolerances leave a wide margin
R_TOL = np.radians(0.5)
DIR_TOL = np.radians(10.0)   # 15 rays of one camera at 0.3 px: e_socp is 5 deg off
MOTION = (synth.rotation_about([0, 0, 1], 0.2), np.array([0.3, 0.1, 0.05]))
#: the vertical in rig frame 1 given to estimators that take it (``gravity1``)
GRAVITY1 = np.array([0.0, -1.0, 0.1]) / np.linalg.norm([0.0, -1.0, 0.1])


def names() -> list[str]:
    return mcgeom.registry.names()


def est(rp, name: str, R=None, **kw):
    """``mcgeom.estimate(rp, name)``; an estimator that declares it needs the
    rotation (registry ``needs_rotation``) is given the row's true rotation
    ``R`` (default: that of ``MOTION``), as its users would; one that takes the
    vertical (``gravity1``/``gravity2``) gets ``GRAVITY1`` and ``R GRAVITY1``."""
    info = mcgeom.registry.get(name)
    R_true = MOTION[0] if R is None else R
    if info.needs_rotation:
        kw.setdefault("rotation", R_true)
    if "gravity1" in info.options:   # the vertical of an IMU, consistent with R
        kw.setdefault("gravity1", GRAVITY1)
        kw.setdefault("gravity2", R_true @ GRAVITY1)
    return mcgeom.estimate(rp, name, **kw)


@functools.lru_cache(maxsize=None)
def ring() -> Rig:
    return synth.ring_rig(4)


@functools.lru_cache(maxsize=None)
def problem(kind: str = "ring", n: int = 60, seed: int = 1):
    """Seeded synthetic problems shared by the rows (built once per session)."""
    R, t = MOTION
    rig = ring()
    if kind == "static":
        R, t = np.eye(3), np.zeros(3)
    elif kind == "translation":
        R, t = np.eye(3), np.array([0.3, 0.1, 0.0])
    elif kind == "central":
        rig = central_rig()
    elif kind == "single":
        rig = Rig((ring().cameras[0],))
        R = synth.rotation_about([0, 0, 1], 0.1)
    elif kind == "near-pi":
        rig = upward_rig()
        R = synth.rotation_about([0.1, -0.2, 1.0], np.pi - 1e-3)
    return synth.make_problem(rig, R, t, n, rng=seed, depth_range=(1.0, 8.0), pixel_noise=0.3)


def central_rig() -> Rig:
    """Four cameras with one centre, looking 90 degrees apart (a central rig)."""
    return Rig(tuple(synth.look_at_camera(f"c{k}", (0.1, 0.2, 0.0), synth._heading(90.0 * k),
                                          f=800, width=1024, height=768) for k in range(4)))


def upward_rig() -> Rig:
    """Four cameras at different heights around a ring, all looking up: a rotation
    by nearly pi about the vertical keeps every camera's view."""
    return Rig(tuple(synth.look_at_camera(
        f"up{k}", (0.5 * np.cos(k * np.pi / 2), 0.5 * np.sin(k * np.pi / 2), 0.1 * k),
        (0.2 * np.cos(k * np.pi / 2), 0.2 * np.sin(k * np.pi / 2), 1.0), up=(1, 0, 0),
        f=400, width=1024, height=768) for k in range(4)))


def rays() -> RayPairs:
    return problem().rays


def pixels(kind: str = "ring"):
    p = problem(kind)
    return p.pixels1, p.pixels2, p.cam1, p.cam2, p.rig


def with_rays(**arrays) -> RayPairs:
    r = rays()
    d = dict(origins1=r.origins1, dirs1=r.dirs1, origins2=r.origins2, dirs2=r.dirs2,
             cam1=r.cam1, cam2=r.cam2)
    d.update(arrays)
    return RayPairs(**d)


def row_set(a: np.ndarray, k: int, value) -> np.ndarray:
    out = np.array(a, dtype=np.float64)
    out[k] = value
    return out


def rot_err(R, R_true) -> float:
    return metrics.rotation_error(np.asarray(R), R_true)


def dir_err(t, t_true) -> float:
    """Angle (rad) between two translation directions."""
    a, b = np.asarray(t, float), np.asarray(t_true, float)
    return float(np.arccos(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b), -1, 1)))


def raises(exc, match: str):
    return pytest.raises(exc, match=match)


def every_estimator(rp: RayPairs, exc, match: str) -> None:
    for name in names():
        with raises(exc, match):
            est(rp, name)


# ------------------------------------------------------------------ shapes and dtypes

@row("pixels-wrong-shape", "`points1` of shape (N, 3), (2, N) or a scalar",
     "`ValueError`: points1 must have shape (N, 2) or (N, 1, 2), got ...")
def test_pixels_wrong_shape():
    p1, p2, c1, c2, rig = pixels()
    for bad in (np.c_[p1, p1[:, :1]], p1.T, 3.0):
        with raises(ValueError, r"points1 must have shape \(N, 2\) or \(N, 1, 2\), got"):
            cv.estimate(bad, p2, c1, c2, rig)
        with raises(ValueError, "points1 must have shape"):
            mcgeom.estimateRigMotion(bad, p2, c1, c2, rig)


@row("pixels-wrong-dtype", "pixels as strings, objects, complex, booleans or `None`",
     "`ValueError`: points1 must be numeric, got dtype ...")
def test_pixels_wrong_dtype():
    p1, p2, c1, c2, rig = pixels()
    for bad in (p1.astype(str), p1.astype(object), p1.astype(complex), p1 > 300, None):
        with raises(ValueError, "points1 must be numeric, got dtype"):
            cv.estimate(bad, p2, c1, c2, rig)


@row("pixels-ragged", "pixels as a ragged nested list",
     "`ValueError`: points1 must be an (N, 2) array of pixels (...inhomogeneous shape...)")
def test_pixels_ragged():
    p1, p2, c1, c2, rig = pixels()
    with raises(ValueError, r"points1 must be an \(N, 2\) array of pixels \(.*inhomogeneous"):
        cv.estimate([[1.0, 2.0], [3.0]], p2, c1, c2, rig)


@row("pixels-length-mismatch", "`points2` with fewer rows than `points1`",
     "`ValueError`: points2 has N-1 points but points1 has N")
def test_pixels_length_mismatch():
    p1, p2, c1, c2, rig = pixels()
    with raises(ValueError, f"points2 has {len(p1) - 1} points but points1 has {len(p1)}"):
        cv.estimate(p1, p2[:-1], c1, c2, rig)


@row("pixels-opencv-layout", "pixels as OpenCV's (N, 1, 2) float32, or nested lists",
     "accepted: the same motion as (N, 2) float64")
def test_pixels_opencv_layout():
    p1, p2, c1, c2, rig = pixels()
    ref = cv.estimate(p1, p2, c1, c2, rig)
    m = cv.estimate(p1.reshape(-1, 1, 2), p2.tolist(), c1.tolist(), c2, rig)
    np.testing.assert_array_equal(m.R, ref.R)
    m32 = cv.estimate(np.float32(p1).reshape(-1, 1, 2), np.float32(p2), c1, c2, rig)
    assert rot_err(m32.R, ref.R) < 1e-5


@row("ids-wrong-shape", "camera ids of shape (N, 2) or (N-1,)",
     "`ValueError`: cameraIds1 has 2N entries, expected N (one per point)")
def test_ids_wrong_shape():
    p1, p2, c1, c2, rig = pixels()
    n = len(p1)
    with raises(ValueError, rf"cameraIds1 has {2 * n} entries, expected {n} \(one per point\)"):
        cv.estimate(p1, p2, np.c_[c1, c1], c2, rig)
    with raises(ValueError, rf"cameraIds2 has {n - 1} entries, expected {n}"):
        cv.estimate(p1, p2, c1, c2[:-1], rig)
    with raises(ValueError, rf"cam1 has {n - 1} ids but there are {n} pixels"):
        rig.ray_pairs(p1, p2, c1[:-1], c2)


@row("ids-wrong-dtype", "camera ids as floats with a fraction, strings, booleans or `None`",
     "`ValueError`: cameraIds1 must hold integer camera ids, got dtype ...")
def test_ids_wrong_dtype():
    p1, p2, c1, c2, rig = pixels()
    for bad in (c1 + 0.5, c1.astype(str), c1 > 0, None):
        with raises(ValueError, "cameraIds1 must hold integer camera ids"):
            cv.estimate(p1, p2, bad, c2, rig)
    with raises(ValueError, "cam1 must hold integer camera ids"):
        with_rays(cam1=rays().cam1 + 0.5)


@row("ids-out-of-range", "camera id 7, -1, 2**62 or 2**63 (uint64) on a 4-camera rig",
     "`ValueError`: cameraIds1 holds camera id 7, but the rig has cameras 0..3")
def test_ids_out_of_range():
    p1, p2, c1, c2, rig = pixels()
    for bad in (7, -1, 2 ** 62):
        ids = np.where(c1 == 1, bad, c1)
        with raises(ValueError, f"cameraIds1 holds camera id {bad}, but the rig has cameras 0..3"):
            cv.estimate(p1, p2, ids, c2, rig)
        with raises(ValueError, f"cam2: unknown camera id {bad}: rig has cameras 0..3"):
            rig.ray_pairs(p1, p2, c1, ids)
    ids = np.where(c1 == 1, 2 ** 63, c1).astype(np.uint64)
    with raises(ValueError, f"cameraIds1 holds camera id {2 ** 63}"):
        cv.estimate(p1, p2, ids, c2, rig)
    with raises(ValueError, r"cam1 holds a negative camera id \(-1\)"):
        with_rays(cam1=np.where(rays().cam1 == 1, -1, rays().cam1))


@row("rays-wrong-shape", "ray arrays of shape (N, 2), or `dirs2` with N-1 rows",
     "`ValueError`: dirs1 must have shape (N, 3), got (N, 2) / dirs2 has N-1 rows, expected N")
def test_rays_wrong_shape():
    r = rays()
    with raises(ValueError, r"dirs1 must have shape \(N, 3\), got \(60, 2\)"):
        with_rays(dirs1=r.dirs1[:, :2])
    with raises(ValueError, "dirs2 has 59 rows, expected 60"):
        with_rays(dirs2=r.dirs2[:-1])
    with raises(ValueError, r"origins1 must have shape \(N, 3\)"):
        with_rays(origins1=r.origins1.ravel())


@row("rays-wrong-dtype", "ray arrays as objects, complex, booleans or strings",
     "`ValueError`: dirs1 must be a numeric array, got dtype ...")
def test_rays_wrong_dtype():
    r = rays()
    for bad in (r.dirs1.astype(object), r.dirs1.astype(complex), r.dirs1 > 0, r.dirs1.astype(str)):
        with raises(ValueError, "dirs1 must be a numeric array, got dtype"):
            with_rays(dirs1=bad)


@row("rays-not-raypairs", "`mcgeom.estimate` given an array instead of `RayPairs`",
     "`TypeError`: rays must be a RayPairs, got ndarray (every estimator)")
def test_rays_not_raypairs():
    for name in names():
        with raises(TypeError, "rays must be a RayPairs, got ndarray"):
            mcgeom.estimate(np.zeros((20, 3)), name)


@row("rotation-wrong", "a rotation argument that is 2x2, a reflection or 2 I: camera "
     "extrinsics, `initial=(R, t)` of `refine` and `bnb_lp`, `Rig.in_frame`, `RayPairs.in_frame`",
     "`ValueError`: ... must have shape (3, 3) / is not a rotation")
def test_rotation_wrong():
    cam = ring().cameras[0]
    for bad, what in ((np.eye(2), "must have shape"), (np.diag([1.0, 1, -1]), "is not a rotation"),
                      (2 * np.eye(3), "is not a rotation")):
        with raises(ValueError, f"camera 'x': extrinsic R {what}"):
            Camera("x", cam.K, cam.dist, "pinhole", bad, cam.t, 1024, 768)
        with raises(ValueError, f"in_frame: R {what}"):
            ring().in_frame(bad, np.zeros(3))
        with raises(ValueError, f"in_frame: R {what}"):
            rays().in_frame(bad, np.zeros(3))
        for name in ("refine", "bnb_lp"):
            with raises(ValueError, "initial|R0|rotation"):
                mcgeom.estimate(rays(), name, initial=(bad, np.ones(3)))


@row("method-unknown", "`method=` an unknown name or not a string",
     "`ValueError`: unknown estimator 'foo'; registered: [...]")
def test_method_unknown():
    p1, p2, c1, c2, rig = pixels()
    for m in ("foo", "ransac:foo"):
        with raises(ValueError, r"unknown estimator 'foo'; registered: \["):
            cv.estimate(p1, p2, c1, c2, rig, method=m)
    with raises(ValueError, "method must be a flag of mcgeom.cv or a registered estimator name"):
        cv.estimate(p1, p2, c1, c2, rig, method=3)
    with raises(ValueError, "unknown estimator 'foo'"):
        mcgeom.estimate(rays(), "foo")


@row("rig-not-rig", "a path or `None` passed as `rig`",
     "`TypeError`: rig must be an mcgeom.rig.Rig, got str")
def test_rig_not_rig():
    p1, p2, c1, c2, _ = pixels()
    with raises(TypeError, "rig must be an mcgeom.rig.Rig, got str"):
        cv.estimate(p1, p2, c1, c2, "rig.json")
    with raises(TypeError, "rig must be an mcgeom.rig.Rig, got NoneType"):
        mcgeom.estimateRigMotion(p1, p2, c1, c2, None)


@row("ransac-options", "`prob` 2, NaN or `None`, `threshold` 0, -1, NaN or a string, "
     "`maxIters` 0 or 1.5, a mask of the wrong length, with NaN or of strings",
     "`ValueError` naming the option and its valid range")
def test_ransac_options():
    p1, p2, c1, c2, rig = pixels()
    for kw, msg in (({"prob": 2}, r"prob must be in \(0, 1\)"), ({"prob": np.nan}, "prob must be"),
                    ({"threshold": 0}, "threshold must be a positive number"),
                    ({"threshold": -1}, "threshold must be"), ({"threshold": np.nan}, "threshold"),
                    ({"maxIters": 0}, "maxIters must be >= 1"),
                    ({"maxIters": 1.5}, "maxIters must be an integer, got 1.5"),
                    ({"threshold": "1"}, "threshold must be a number, got '1'"),
                    ({"prob": None}, "prob must be a number, got None"),
                    ({"mask": np.ones(5)}, f"mask has 5 entries, expected {len(p1)}"),
                    ({"mask": np.full(len(p1), np.nan)}, "mask must hold finite numbers or "
                                                         "booleans .* with NaN or inf"),
                    ({"mask": np.array(["1"] * len(p1))}, "mask must hold finite numbers")):
        with raises(ValueError, msg):
            cv.estimate(p1, p2, c1, c2, rig, **kw)


# ------------------------------------------------------------------ layouts

@row("non-contiguous", "Fortran-ordered, strided or reversed-stride pixels, ids and rays",
     "accepted: exactly the same motion as the C-contiguous copies (every estimator)")
def test_non_contiguous():
    p1, p2, c1, c2, rig = pixels()
    ref = cv.estimate(p1, p2, c1, c2, rig)
    m = cv.estimate(np.asfortranarray(p1), np.repeat(p2, 2, axis=0)[::2],
                    np.repeat(c1, 2)[::2], c2[::-1][::-1], rig)
    np.testing.assert_array_equal(m.R, ref.R)
    np.testing.assert_array_equal(m.t, ref.t)
    r = rays()
    strided = RayPairs(np.asfortranarray(r.origins1), np.repeat(r.dirs1, 2, axis=0)[::2],
                       r.origins2[::-1][::-1], np.asfortranarray(r.dirs2),
                       np.repeat(r.cam1, 3)[::3], r.cam2)
    for name in names():
        a, b = est(r, name), est(strided, name)
        np.testing.assert_array_equal(a.R, b.R, err_msg=name)
        np.testing.assert_array_equal(a.t, b.t, err_msg=name)


# ------------------------------------------------------------------ non-finite values

@row("pixels-nan-inf", "NaN or inf in `points1` / `points2`",
     "`ValueError`: points1 contains NaN or inf")
def test_pixels_nan_inf():
    p1, p2, c1, c2, rig = pixels()
    with raises(ValueError, "points1 contains NaN or inf"):
        cv.estimate(row_set(p1, 3, np.nan), p2, c1, c2, rig)
    with raises(ValueError, "points2 contains NaN or inf"):
        mcgeom.estimateRigMotion(p1, row_set(p2, 5, np.inf), c1, c2, rig)
    with raises(ValueError, r"pixels1 has 1 non-finite row\(s\) \(first: row 3\)"):
        rig.ray_pairs(row_set(p1, 3, -np.inf), p2, c1, c2)


@row("rays-nan-inf", "NaN or inf in any ray array",
     "`ValueError`: rays.dirs1 contains NaN or inf (every estimator)")
def test_rays_nan_inf():
    r = rays()
    every_estimator(with_rays(dirs1=row_set(r.dirs1, 3, np.nan)), ValueError,
                    "rays.dirs1 contains NaN or inf")
    every_estimator(with_rays(origins2=row_set(r.origins2, 5, np.inf)), ValueError,
                    "rays.origins2 contains NaN or inf")


@row("calibration-nan-inf", "NaN or inf in K, distortion, R or t of a camera",
     "`ValueError`: camera 'x': K has non-finite entries (dist, extrinsic R, extrinsic t alike)")
def test_calibration_nan_inf():
    cam = ring().cameras[0]
    K = cam.K.copy()
    K[0, 2] = np.nan
    with raises(ValueError, "camera 'x': K has non-finite entries"):
        Camera("x", K, cam.dist, "pinhole", cam.R, cam.t, 1024, 768)
    with raises(ValueError, "camera 'x': dist has non-finite entries"):
        Camera("x", cam.K, [0.1, np.inf, 0, 0], "pinhole", cam.R, cam.t, 1024, 768)
    with raises(ValueError, r"camera 'x': extrinsic R is not a rotation \(non-finite entries\)"):
        Camera("x", cam.K, cam.dist, "pinhole", row_set(cam.R, 1, np.nan), cam.t, 1024, 768)
    with raises(ValueError, "camera 'x': extrinsic t has non-finite entries"):
        Camera("x", cam.K, cam.dist, "pinhole", cam.R, [0, np.inf, 0], 1024, 768)


@row("zero-direction", "a ray direction of length 0",
     "`ValueError`: ... dirs1 contains a zero-length direction / d1[k] is a zero bearing "
     "(every estimator, robust too)")
def test_zero_direction():
    r = with_rays(dirs1=row_set(rays().dirs1, 2, 0.0))
    every_estimator(r, ValueError, "zero-length direction|zero bearing")
    with raises(ValueError, "zero-length direction|zero bearing"):
        mcgeom.robust.ransac(r, "five_plus_one")


@row("pixels-huge", "finite pixels of 1e300",
     "`ValueError`: camera 'cam0': pixel (...) has no finite bearing (names camera and pixel)")
def test_pixels_huge():
    p1, p2, c1, c2, rig = pixels()
    with raises(ValueError, r"camera 'cam\d': pixel .* has no finite bearing"):
        cv.estimate(p1 * 1e300, p2, c1, c2, rig)
    with raises(ValueError, r"camera 'cam\d': pixel .* has no finite bearing"):
        rig.ray_pairs(p1, p2 * 1e300, c1, c2)


@row("rays-huge-camera-id", "`RayPairs` camera ids 10**11 + (0..3)",
     "`ValueError`: cam1 holds camera id 100000000003, above the largest supported 1048575 (ids "
     "are 0-based camera indices)")
def test_rays_huge_camera_id():
    r = rays()
    with raises(ValueError, r"cam1 holds camera id 100000000003, above the largest supported "
                            r"1048575 \(ids are 0-based camera indices\)"):
        RayPairs(r.origins1, r.dirs1, r.origins2, r.dirs2, r.cam1 + 10 ** 11, r.cam2)


# ------------------------------------------------------------------ too little data

@row("empty", "no correspondences: (0, 2) pixels, `[]` (what a matcher returns), "
     "empty `RayPairs`",
     "`ValueError`: too few correspondences: <method> needs at least k, got 0 (every method flag "
     "and estimator)")
def test_empty():
    _, _, _, _, rig = pixels()
    z2, zi = np.zeros((0, 2)), np.zeros(0, int)
    for m in [cv.RIG_5P1_RANSAC, cv.RIG_5P1_DIRECT, cv.RIG_LINEAR17, cv.RIG_LINEAR17_RANSAC,
              *names()]:
        with raises(ValueError, "too few correspondences"):
            cv.estimate(z2, z2, zi, zi, rig, method=m)
    with raises(ValueError, "too few correspondences: five_plus_one needs at least 6, got 0"):
        mcgeom.estimateRigMotion(z2, z2, zi, zi, rig)
    with raises(ValueError, "too few correspondences: five_plus_one needs at least 6, got 0"):
        cv.estimate([], [], [], [], rig)
    with raises(ValueError, "too few correspondences: five_plus_one needs at least 6, got 0"):
        cv.estimate(np.float32([]), np.float32([]), np.int32([]), None, rig)
    z3 = np.zeros((0, 3))
    every_estimator(RayPairs(z3, z3, z3, z3, zi, zi), ValueError, "too few correspondences")


@row("too-few", "3 correspondences (2 for `known_rotation_translation`, whose minimal "
     "sample is 3), or a mask that keeps none",
     "`ValueError`: too few correspondences: five_plus_one needs at least 6, got 3 (every method)")
def test_too_few():
    p1, p2, c1, c2, rig = pixels()
    for name in names():
        k = min(3, mcgeom.registry.get(name).min_sample - 1)
        with raises(ValueError, "too few correspondences"):
            cv.estimate(p1[:k], p2[:k], c1[:k], c2[:k], rig, method=name)
        with raises(ValueError, "too few correspondences"):
            est(rays().take(np.arange(k)), name)
    with raises(ValueError, "too few correspondences: five_plus_one needs at least 6, got 0"):
        cv.estimate(p1, p2, c1, c2, rig, mask=np.zeros(len(p1), np.uint8))


@row("duplicated", "every correspondence given twice",
     "accepted: the motion of the correspondences given once (R right, metric `t` within 5 %, "
     "scale observable; every estimator)")
def test_duplicated():
    p1, p2, c1, c2, rig = pixels()
    R, t = MOTION
    twice = lambda a: np.concatenate([a, a])  # noqa: E731
    m = cv.estimate(twice(p1), twice(p2), twice(c1), twice(c2), rig)
    r = rays().take(np.r_[np.arange(len(rays())), np.arange(len(rays()))])
    for name, mm in [("cv", m)] + [(k, est(r, k)) for k in names()]:
        assert rot_err(mm.R, R) < R_TOL, name
        assert mm.scale.observable, (name, mm.scale.reason)
        assert np.linalg.norm(mm.t - t) < 0.05 * np.linalg.norm(t), (name, mm.t)


@row("one-correspondence-repeated", "one correspondence repeated 40 times",
     "`DegenerateError`: <method>: only 1 distinct correspondence(s) among 40 (the others repeat "
     "them); <method> needs at least k (every estimator, robust or not)")
def test_one_correspondence_repeated():
    p1, p2, c1, c2, rig = pixels()
    k = np.zeros(40, int)
    for m in [cv.RIG_5P1_RANSAC, cv.RIG_5P1_DIRECT, cv.RIG_LINEAR17, cv.RIG_LINEAR17_RANSAC]:
        with raises(mcgeom.DegenerateError, "only 1 distinct correspondence"):
            cv.estimate(p1[k], p2[k], c1[k], c2[k], rig, method=m)
    every_estimator(rays().take(k), mcgeom.DegenerateError,
                    r"only 1 distinct correspondence\(s\) among 40 \(the others repeat them\)")


@row("too-few-per-camera", "4 correspondences in each of the 4 cameras, none across cameras",
     "the façade's default: the generic 6-point sampler instead of 5+1 (`info['sampler']`), "
     "the motion; `five_plus_one` (direct, or forced by `'ransac:five_plus_one'`): "
     "`ValueError`: too few correspondences: five_plus_one needs 5 intra-camera correspondences "
     "in one camera, most found: 4 (robust: 'no camera has 5 intra-camera correspondences'); "
     "`linear17`, `refine`, `bnb_lp`, `e_socp`: a motion, or `DegenerateError` when 16 rays do "
     "not determine it")
def test_too_few_per_camera():
    p1, p2, c1, c2, rig = pixels()
    sel = np.concatenate([np.flatnonzero((c1 == k) & (c2 == k))[:4] for k in range(4)])
    m = cv.estimate(p1[sel], p2[sel], c1[sel], c2[sel], rig)
    assert m.info["sampler"] == "six_point" and rot_err(m.R, MOTION[0]) < R_TOL
    for m in ("ransac:five_plus_one", cv.RIG_5P1_DIRECT):
        with raises(ValueError, "5 intra-camera correspondences"):
            cv.estimate(p1[sel], p2[sel], c1[sel], c2[sel], rig, method=m)
    with raises(ValueError, "five_plus_one needs 5 intra-camera correspondences in one camera, "
                            "most found: 4"):
        mcgeom.estimate(rays().take(sel), "five_plus_one")
    R, _ = MOTION
    for name in names():
        if name == "five_plus_one":
            continue
        try:
            m = est(rays().take(sel), name)
        except ValueError as e:      # DegenerateError included
            assert "correspondences" in str(e) or "degenerate" in str(e), (name, e)
        else:                        # noise-free enough to be right, or says it is unsure
            assert rot_err(m.R, R) < R_TOL or not m.scale.observable, name


@row("collinear-points", "every scene point on one 3-D line, seen by one camera",
     "`DegenerateError`: five_plus_one: the 40 bearings of the 5-point camera at time 1 lie in "
     "one plane through its centre ... / linear17: E is not determined by the data (central "
     "camera) ... / bnb_lp: the data do not determine the motion (every estimator); "
     "`known_rotation_translation` (R given): the camera's travel direction, scale unobservable")
def test_collinear_points():
    R, t = MOTION
    rig = ring()
    s = np.linspace(-1.0, 1.0, 40)
    pts = np.array([3.0, 0.5, 0.2]) + s[:, None] * np.array([0.2, 1.0, 0.1])
    o, d1, o2, d2 = [], [], [], []
    c = rig.centres[0]
    for X in pts:    # all seen by camera 0 at both times (rig frame)
        o.append(c); d1.append(X - c)
        X2 = R @ X + t
        o2.append(c); d2.append(X2 - c)
    rp = RayPairs(np.array(o), np.array(d1), np.array(o2), np.array(d2),
                  np.zeros(40, int), np.zeros(40, int))
    for name in names():
        if mcgeom.registry.get(name).needs_rotation:
            # with R given, the epipolar planes of points on a line (a pencil
            # about the baseline) still fix the camera's travel direction
            check_unobservable(est(rp, name, R), R, camera_travel(R, t, c), name)
            continue
        with raises(mcgeom.DegenerateError, "not determined|do not determine"):
            est(rp, name)


# ------------------------------------------------------------------ degenerate geometry

def camera_travel(R: np.ndarray, t: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Direction in which a camera with centre ``c`` moves, ``t + R c - c``: all that
    the correspondences of one camera (or of a central rig) can tell of ``t``."""
    tau = t + R @ c - c
    return tau / np.linalg.norm(tau)


def check_unobservable(m, R_true, direction=None, who="") -> None:
    assert rot_err(m.R, R_true) < R_TOL, (who, np.degrees(rot_err(m.R, R_true)))
    assert not m.scale.observable, (who, m.scale.reason)
    assert abs(np.linalg.norm(m.t) - 1.0) < 1e-9, (who, m.t)
    if direction is not None:
        assert dir_err(m.t, direction) < DIR_TOL, (who, m.t, direction)


@row("one-camera", "every correspondence in camera 0 of a 4-camera rig",
     "R right; scale unobservable (\"one camera only and no cross-camera correspondence\" / "
     "\"central camera\"); `t` unit, along the camera's travel `t + R c - c` (every estimator)")
def test_one_camera():
    p1, p2, c1, c2, rig = pixels()
    R, t = MOTION
    sel = (c1 == 0) & (c2 == 0)
    u = camera_travel(R, t, rig.centres[0])
    check_unobservable(cv.estimate(p1[sel], p2[sel], c1[sel], c2[sel], rig), R, u, "cv")
    one = rays().take(np.flatnonzero(sel))
    for name in names():
        check_unobservable(est(one, name), R, u, name)


@row("single-camera-rig", "a rig of one camera",
     "as `one-camera`: R right, scale unobservable, `t` the camera's unit travel direction")
def test_single_camera_rig():
    p = problem("single")
    u = camera_travel(p.R, p.t, p.rig.centres[0])
    check_unobservable(cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, p.rig), p.R, u, "cv")
    for name in names():
        check_unobservable(est(p.rays, name, p.R), p.R, u, name)


@row("central-rig", "a rig whose 4 cameras share one centre (coincident centres)",
     "R right; scale unobservable (\"central camera\" / \"critical motion\"); `t` unit, along "
     "the centre's travel")
def test_central_rig():
    p = problem("central")
    u = camera_travel(p.R, p.t, p.rig.centres[0])
    check_unobservable(cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, p.rig), p.R, u, "cv")
    for name in names():
        check_unobservable(est(p.rays, name, p.R), p.R, u, name)


@row("zero-motion", "a static rig (R = I, t = 0), 0.3 px noise",
     "pixels and rays: \"no translation detected: a pure rotation explains ...\", `t = 0`, "
     "R = I, scale unobservable (every estimator)")
def test_zero_motion():
    p = problem("static")
    m = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, p.rig)
    assert m.scale.reason.startswith("no translation detected"), m.scale.reason
    assert not m.scale.observable and rot_err(m.R, np.eye(3)) < R_TOL
    np.testing.assert_array_equal(m.t, np.zeros(3))
    retval, R, t, mask = mcgeom.estimateRigMotion(p.pixels1, p.pixels2, p.cam1, p.cam2, p.rig)
    np.testing.assert_array_equal(t, np.zeros((3, 1)))
    for name in names():
        m = est(p.rays, name, np.eye(3))
        assert m.scale.reason.startswith("no translation detected"), (name, m.scale.reason)
        assert not m.scale.observable and rot_err(m.R, np.eye(3)) < R_TOL, name
        np.testing.assert_array_equal(m.t, np.zeros(3))


@row("pure-translation", "R = I, t = (0.3, 0.1, 0) m, intra-camera correspondences only",
     "scale unobservable (\"critical motion: camera displacements parallel ...\" / \"scale too "
     "uncertain\"); R = I; `t` unit along the true direction, sign included (every estimator)")
def test_pure_translation():
    p = problem("translation")
    u = p.t / np.linalg.norm(p.t)
    check_unobservable(cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, p.rig), p.R, u, "cv")
    for name in names():
        check_unobservable(est(p.rays, name, p.R), p.R, u, name)


@row("rotation-near-pi", "a rotation of pi - 1e-3 rad (about a tilted vertical axis), "
     "up-looking cameras",
     "recovered: R right to 0.5 deg, metric `t`, scale observable (every estimator)")
def test_rotation_near_pi():
    p = problem("near-pi")
    ms = [("cv", cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, p.rig))]
    ms += [(name, est(p.rays, name, p.R)) for name in names()]
    for name, m in ms:
        assert rot_err(m.R, p.R) < R_TOL, (name, np.degrees(rot_err(m.R, p.R)))
        assert m.scale.observable, (name, m.scale.reason)
        assert np.linalg.norm(m.t - p.t) < 0.05 * np.linalg.norm(p.t), (name, m.t, p.t)


@row("cross-camera-only-near-pi", "ring rig turned by pi - 1e-3 rad: every correspondence "
     "between opposite cameras, none within a camera",
     "pixels, the façade's default: the 6-point sampler, R right, scale unobservable; "
     "`five_plus_one`, `e_socp`: `ValueError` (... needs 5 intra-camera correspondences "
     "...); `linear17`, `refine`: `DegenerateError` (degenerate data ...); `bnb_lp`: R right "
     "(its global search starts from a rotation of the cube when the identity is too far), "
     "scale unobservable (the rotated rig nearly maps its cameras onto each other)")
def test_cross_camera_only_near_pi():
    R = synth.rotation_about([0, 0, 1], np.pi - 1e-3)
    p = synth.make_problem(ring(), R, MOTION[1], 60, rng=2, depth_range=(1.0, 8.0),
                           pixel_noise=0.3, cross_fraction=1.0)
    m = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, p.rig)
    assert m.info["sampler"] == "six_point" and rot_err(m.R, R) < R_TOL
    assert not m.scale.observable, m.scale.reason
    with raises(ValueError, "5 intra-camera correspondences"):
        cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, p.rig, method="ransac:five_plus_one")
    for name in ("five_plus_one", "e_socp"):
        with raises(ValueError, "needs 5 intra-camera correspondences"):
            mcgeom.estimate(p.rays, name)
    for name in ("linear17", "refine"):
        with raises(mcgeom.DegenerateError, "degenerate data"):
            mcgeom.estimate(p.rays, name)
    m = mcgeom.estimate(p.rays, "bnb_lp")
    assert rot_err(m.R, R) < R_TOL and not m.scale.observable, m.scale.reason


# ------------------------------------------------------------------ calibration

def camera_with(**changes) -> Camera:
    cam = ring().cameras[0]
    fields = dict(name="x", K=cam.K, dist=cam.dist, model="pinhole", R=cam.R, t=cam.t,
                  width=1024, height=768)
    fields.update(changes)
    return Camera(**fields)


def rig_file_with(tmp_path, **camera0) -> Path:
    """tests/data/calibration/mcgeom/rig4.json with camera 0's entries replaced."""
    import json
    d = json.loads((CALIB / "mcgeom" / "rig4.json").read_text())
    d["cameras"][0].update(camera0)
    path = tmp_path / "rig.json"
    path.write_text(json.dumps(d))
    return path


@row("extrinsics-not-rotation", "camera extrinsics that are a reflection (det -1), scaled "
     "(2 R) or sheared, in a `Camera` or a rig file",
     "`ValueError`: <file>: cameras[0]: camera '...': extrinsic R is not a rotation "
     "(det = -1 / not orthonormal: max |R^T R - I| = ...)")
def test_extrinsics_not_rotation(tmp_path):
    R = ring().cameras[0].R
    shear = R.copy()
    shear[0, 1] += 1e-3
    for bad, why in ((R @ np.diag([1.0, 1, -1]), r"\(det = -1"), (2 * R, r"\(not orthonormal"),
                     (shear, r"\(not orthonormal")):
        with raises(ValueError, f"camera 'x': extrinsic R is not a rotation {why}"):
            camera_with(R=bad)
        path = rig_file_with(tmp_path, R_cam_from_rig=bad.tolist())
        with raises(ValueError, rf"rig.json: cameras\[0\]: camera '.*': extrinsic R is not a "
                                rf"rotation {why}"):
            mcgeom.load_rig(path)


@row("intrinsics-degenerate", "a singular K (fx = 0), a negative focal length, K not "
     "upper triangular or K[2, 2] != 1, in a `Camera` or a rig file",
     "`ValueError`: camera '...': K must have positive focal lengths, got fx=0.0 ... / "
     "must be upper triangular / K[2,2] must be 1")
def test_intrinsics_degenerate(tmp_path):
    K = ring().cameras[0].K
    for change, why in (((0, 0, 0.0), "K must have positive focal lengths, got fx=0.0"),
                        ((1, 1, -800.0), "K must have positive focal lengths, got fx=800.0, fy=-800.0"),
                        ((1, 0, 5.0), "K must be upper triangular"),
                        ((2, 2, 0.0), r"K\[2,2\] must be 1, got 0.0")):
        bad = K.copy()
        bad[change[:2]] = change[2]
        with raises(ValueError, f"camera 'x': {why}"):
            camera_with(K=bad)
        with raises(ValueError, rf"rig.json: cameras\[0\]: camera '.*': {why}"):
            mcgeom.load_rig(rig_file_with(tmp_path, K=bad.tolist()))


#: one calibration file of each format (COLMAP's needs cameras.txt and images.txt beside it)
FILES = {"mcgeom-json": CALIB / "mcgeom" / "rig4.json",
         "opencv-yaml": CALIB / "opencv" / "rig4.yml",
         "kalibr": CALIB / "kalibr" / "camchain-imucam-radtan.yaml",
         "colmap": CALIB / "colmap" / "rig_config.json"}


def damaged_copy(tmp_path, fmt: str, text: str) -> Path:
    import shutil
    src = FILES[fmt]
    for extra in ("cameras.txt", "images.txt"):
        if (src.parent / extra).exists():
            shutil.copy(src.parent / extra, tmp_path / extra)
    path = tmp_path / src.name
    path.write_text(text, encoding="utf-8")
    return path


#: per format: (regex, gist) of the message for a truncated file, a syntax error
#: (format given), and another format's file loaded as this one
FILE_MESSAGES = {
    "mcgeom-json": ((r"not valid JSON \(.* at line \d+ column \d+\)",
                     "not valid JSON (Expecting ... at line n column m)"),
                    (r"not valid JSON \(Expecting ',' delimiter", "not valid JSON (Expecting ',' "
                                                                    "delimiter at line 3 ...)"),
                    (r"not valid JSON \(Expecting value at line 1", "not valid JSON (Expecting "
                                                                     "value at line 1 column 1)")),
    # (the YAML structure is read by PyYAML before OpenCV's parser, which
    # can loop forever on malformed input: fuzz/README.md, finding 17)
    "opencv-yaml": ((r"line \d+: malformed or truncated YAML \(could not find expected ':'\)",
                     "line n: malformed or truncated YAML (could not find expected ':')"),
                    (r"line \d+: malformed or truncated YAML \(mapping values are not allowed",
                     "line n: malformed or truncated YAML (mapping values are not allowed "
                     "here)"),
                    (r"not an OpenCV FileStorage file \(it must start with a '%YAML:1.0'",
                     "not an OpenCV FileStorage file (it must start with a '%YAML:1.0' or "
                     "'%YAML 1.2' header, or '<?xml'; got ...)")),
    "kalibr": ((r"line \d+: expected ',' or '\]', but got '<stream end>' \(while parsing a flow "
                r"sequence; truncated file\?\)",
                "line n: expected ',' or ']', but got '<stream end>' (while parsing a flow "
                "sequence; truncated file?)"),
               (r"line \d+: mapping values are not allowed here",
                "line n: mapping values are not allowed here"),
               # JSON is YAML: the file parses, and is no camchain
               (r"not a Kalibr camchain: no top-level 'cam0' \(top-level keys: format, version",
                "not a Kalibr camchain: no top-level 'cam0' (top-level keys: format, version, "
                "cameras)")),
    "colmap": ((r"not valid JSON \(.*; truncated\?\)", "not valid JSON (... ; truncated?)"),
               (r"not valid JSON \(Expecting ',' delimiter", "not valid JSON (Expecting ',' "
                                                               "delimiter at line n ...)"),
               (r"not valid JSON \(Expecting value at line 1 column 1",
                "not valid JSON (Expecting value at line 1 column 1; truncated?)")),
}


def file_rows(fmt: str) -> None:
    """Three rows for a loader: truncated, malformed, another format's file."""
    slug = fmt.split("-")[0]
    text = FILES[fmt].read_text(encoding="utf-8")
    # a syntax error: a key without its ':' (YAML), a list without a ',' (JSON)
    malformed = (text.replace(":", " ", 3) if fmt in ("opencv-yaml", "kalibr")
                 else text.replace(",", "", 2))
    other = FILES["kalibr" if fmt != "kalibr" else "mcgeom-json"]
    (m_trunc, g_trunc), (m_bad, g_bad), (m_other, g_other) = FILE_MESSAGES[fmt]
    detected = (" (detected from the content: the same, plus which signature chose the format)")

    @row(f"file-truncated-{slug}", f"a `{fmt}` calibration file cut in half",
         f"`ValueError`: <file>: {g_trunc}" + detected)
    def truncated(tmp_path):
        path = damaged_copy(tmp_path, fmt, text[: len(text) // 2])
        with raises(ValueError, f"{re.escape(str(path))}: {m_trunc}"):
            mcgeom.load_rig(path, format=fmt)
        with raises(ValueError, f"{re.escape(str(path))}: {m_trunc}.*detected from the content"):
            mcgeom.load_rig(path)

    @row(f"file-malformed-{slug}", f"a `{fmt}` calibration file with a syntax error",
         f"`ValueError`: <file>: {g_bad} (format= given; detecting the format may instead say "
         "it cannot tell the format, listing each format tried and why)")
    def malformed_(tmp_path):
        path = damaged_copy(tmp_path, fmt, malformed)
        with raises(ValueError, f"{re.escape(str(path))}: {m_bad}"):
            mcgeom.load_rig(path, format=fmt)
        with raises(ValueError, f"{re.escape(str(path))}: "):
            mcgeom.load_rig(path)

    @row(f"file-wrong-format-{slug}", f"a `{'kalibr' if fmt != 'kalibr' else 'mcgeom-json'}` "
         f"file loaded with `format='{fmt}'`", f"`ValueError`: <file>: {g_other}")
    def wrong_format():
        with raises(ValueError, f"{re.escape(str(other))}: {m_other}"):
            mcgeom.load_rig(other, format=fmt)

    for fn, kind in ((truncated, "truncated"), (malformed_, "malformed"),
                     (wrong_format, "wrong_format")):
        fn.__name__ = f"test_file_{kind}_{slug}"
        globals()[fn.__name__] = fn


for _fmt in FILES:
    file_rows(_fmt)


@row("file-unknown-format", "a file that is no calibration format (empty, binary, plain text)",
     "`ValueError`: <file>: cannot tell the calibration format. Tried mcgeom-json: ...; "
     "opencv-yaml: ...; kalibr: ...; colmap: .... Pass format= one of ...")
def test_file_unknown_format(tmp_path):
    for i, text in enumerate(("", "\x00\xff garbage", "focal length 800\n")):
        path = tmp_path / f"f{i}.txt"
        path.write_text(text, encoding="utf-8", errors="surrogateescape")
        with raises(ValueError, "cannot tell the calibration format. Tried mcgeom-json: .*; "
                                "opencv-yaml: .*; kalibr: .*; colmap: .*Pass format="):
            mcgeom.load_rig(path)
    with raises(FileNotFoundError, "No such file or directory: .*missing.json"):
        mcgeom.load_rig(tmp_path / "missing.json")


# ------------------------------------------------------------------ options named (issue 18)

@row("threshold-too-large", "`threshold` 1e20 or 1e300 px (an angle far above 1 rad), through "
     "the façade and `robust.ransac`",
     "`ValueError`: threshold 1e+300 px is an angular error of ... rad at the rig's ... px per "
     "radian: above 1 rad every correspondence is an inlier; it must be at most ... px")
def test_threshold_too_large():
    p1, p2, c1, c2, rig = pixels()
    for thr in (1e20, 1e200, 1e300):
        with raises(ValueError, re.escape(f"threshold {thr:g} px") + " is an angular error .* "
                                "above 1 rad"):
            cv.estimate(p1, p2, c1, c2, rig, threshold=thr)
    with raises(ValueError, "threshold 2 rad is an angular error of 2 rad: above 1 rad"):
        mcgeom.robust.ransac(rays(), "five_plus_one", threshold=2.0)
    cv.estimate(p1, p2, c1, c2, rig, threshold=800.0)   # below 1 rad: accepted


@row("threshold-too-small", "`threshold` 1e-300, 1e-12 or 1e-6 px on data with 0.3 px noise",
     "`DegenerateError`: threshold 1e-06 px is too small: the best of k hypotheses of "
     "five_plus_one explains 6 correspondences within ... px but fewer within the threshold "
     "(not 'degenerate data ... collinear')")
def test_threshold_too_small():
    p1, p2, c1, c2, rig = pixels()
    for thr in (1e-300, 1e-12, 1e-6):
        with pytest.raises(mcgeom.DegenerateError) as e:
            cv.estimate(p1, p2, c1, c2, rig, threshold=thr)
        assert f"threshold {thr:g} px is too small" in str(e.value)
        assert "collinear" not in str(e.value)


@row("sample-cap-reached", "`maxIters` too small for the outliers: 17-point RANSAC "
     "(`RIG_LINEAR17_RANSAC`) capped at 3 samples, or `ransac:six_point` at 1, on a 4-camera "
     "ring with half the correspondences outliers",
     "`DegenerateError`: linear17: no motion found ... after 3 samples (k hypotheses): the "
     "search reached its sample cap (maxIters of mcgeom.cv.estimate, ...). Either no sample "
     "was all inliers -- ... w^17: once in 430 draws at 30 % outliers ... -- then raise the "
     "cap ...; or the data are degenerate (not the data alone blamed)")
def test_sample_cap_reached():
    rng = np.random.default_rng(3)
    p = synth.make_problem(ring(), *MOTION, 120, rng, pixel_noise=0.3, outlier_fraction=0.5)
    for method, cap, m in ((cv.RIG_LINEAR17_RANSAC, 3, 17), ("ransac:six_point", 1, 6)):
        with pytest.raises(mcgeom.DegenerateError) as e:
            cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, p.rig, method=method,
                        maxIters=cap)
        msg = str(e.value)
        assert f"after {cap} sample" in msg and "reached its sample cap (maxIters" in msg, msg
        assert f"w^{m}: once in {1 / 0.7 ** m:,.0f} draws at 30 % outliers" in msg, msg
        assert "raise the cap" in msg and "or the data are degenerate" in msg, msg
    # the data are not degenerate: the default method finds the motion
    m = cv.estimate(p.pixels1, p.pixels2, p.cam1, p.cam2, p.rig)
    assert rot_err(m.R, MOTION[0]) < R_TOL


@row("five-camera-not-integer", "`five_camera` 1.5, NaN, '1', True or [1] (`five_plus_one`)",
     "`ValueError`: five_camera must be an integer camera id, got 1.5 (1.0 is camera 1, as "
     "for camera ids)")
def test_five_camera_not_integer():
    for bad in (1.5, np.nan, "1", True, [1]):
        with raises(ValueError, re.escape(f"five_camera must be an integer camera id, got "
                                          f"{bad!r}")):
            est(rays(), "five_plus_one", five_camera=bad)
    for ok in (np.int64(1), 1.0):
        assert est(rays(), "five_plus_one", five_camera=ok).info["five_camera"] == 1


@row("robust-threshold-e-socp", "`robust_threshold` 0, -1, NaN or '1' (`e_socp`)",
     "`ValueError`: robust_threshold must be None (least squares) or a finite angle > 0 "
     "(radians), got 0 (not accepted as the default, not reported as loss_scale)")
def test_robust_threshold_e_socp():
    for bad in (0, 0.0, -1, np.nan, "1", True):
        with raises(ValueError, "robust_threshold must be None .* got"):
            est(rays(), "e_socp", robust_threshold=bad)


@row("ransac-option-direct-method", "`threshold`, `prob`, `maxIters` or `seed` given to a "
     "method that runs without RANSAC (`direct:...`, `robust=False`, `RIG_LINEAR17`)",
     "`ValueError`: threshold=3.0 is a RANSAC option, but method 'linear17' runs without "
     "RANSAC (direct) and would ignore it (the defaults pass)")
def test_ransac_option_direct_method():
    p1, p2, c1, c2, rig = pixels()
    for method, kw in ((cv.RIG_LINEAR17, {"threshold": 3.0}),
                       (cv.RIG_5P1_DIRECT, {"prob": 0.5}),
                       ("e_socp", {"maxIters": 50}),
                       ("refine", {"seed": 3}),
                       ("bnb_lp", {"seed": None})):
        (key, value), = kw.items()
        name = method.split(":")[-1]
        with raises(ValueError, re.escape(f"{key}={value!r} is a RANSAC option, but method "
                                          f"'{name}' runs without RANSAC")):
            cv.estimate(p1, p2, c1, c2, rig, method=method, **kw)
    with raises(ValueError, "threshold=2.0 is a RANSAC option, but method 'five_plus_one'"):
        cv.estimate(p1, p2, c1, c2, rig, robust=False, threshold=2.0)
    cv.estimate(p1, p2, c1, c2, rig, method=cv.RIG_LINEAR17, threshold=1.0)  # the default


@row("seed-wrong", "`seed` -1, 1.5, 'a' or True (façade, `robust.ransac`)",
     "`ValueError`: seed must be None or a non-negative integer, got -1")
def test_seed_wrong():
    p1, p2, c1, c2, rig = pixels()
    for bad in (-1, 1.5, "a", True, [1, 2]):
        with raises(ValueError, "seed must be None or a non-negative integer, got"):
            cv.estimate(p1, p2, c1, c2, rig, seed=bad)
        with raises(ValueError, "seed must be None or a non-negative integer, got"):
            mcgeom.robust.ransac(rays(), "five_plus_one", seed=bad)
    cv.estimate(p1, p2, c1, c2, rig, seed=np.uint32(7))


@row("directions-tiny", "ray directions scaled by 1e-150 (finite, non-zero, below 1e-50)",
     "`ValueError`: rays.dirs1 contains a zero-length direction (row 0; |d| < 1e-50): one rule "
     "for every estimator (`mcgeom.validation.check_directions`), robust too")
def test_directions_tiny():
    r = rays()
    tiny = with_rays(dirs1=r.dirs1 * 1e-150, dirs2=r.dirs2 * 1e-150)
    every_estimator(tiny, ValueError, r"zero-length direction \(row 0; \|d\| < 1e-50\)")
    with raises(ValueError, "zero-length direction"):
        mcgeom.robust.ransac(tiny, "five_plus_one")
    # 1e-40 is above the bound: every estimator takes it (the same motion as unit rays)
    scaled = with_rays(dirs1=r.dirs1 * 1e-40, dirs2=r.dirs2 * 1e-40)
    for name in names():
        assert rot_err(est(scaled, name).R, MOTION[0]) < R_TOL, name


@row("origins-far", "a camera whose centre lies 1e151 m away (finite origins beyond 1e150)",
     "`ValueError`: rays.origins1 has a coordinate beyond 1e150 m in magnitude (row k): every "
     "estimator that checks rays in numpy, `robust.ransac` and the C search (which returned "
     "`MCG_OK` without the verdict's evidence); linear17 and refine normalise the rays and "
     "return a direction only (scale not observable)")
def test_origins_far():
    r = rays()
    cam0 = r.cam1 == 0
    assert cam0.any() and np.array_equal(r.cam1, r.cam2)
    o1, o2 = r.origins1.copy(), r.origins2.copy()
    o1[cam0] = o2[cam0] = [1e151, 0.0, 0.0]   # one centre per camera, as 5+1 asks
    far = with_rays(origins1=o1, origins2=o2)
    row = int(np.flatnonzero(cam0)[0])
    msg = rf"origins1 has a coordinate beyond 1e150 m in magnitude \(row {row}\)"
    for name in names():
        if name in ("linear17", "refine"):
            assert not est(far, name).scale.observable, name
        else:
            with raises(ValueError, "rays." + msg):
                est(far, name)
    with raises(ValueError, "robust_rig_motion: " + msg):
        mcgeom.robust.ransac(far, "five_plus_one", seed=1)
    # 1e150 itself is accepted by the C search (the bound is |x| <= 1e150)
    o1[cam0] = o2[cam0] = [1e150, 0.0, 0.0]
    mcgeom.robust.ransac(with_rays(origins1=o1, origins2=o2), "five_plus_one", seed=1)


@row("ids-integral-float", "camera ids as floats with whole values (1.0, 2.0: what `np.loadtxt` "
     "gives), to the façade, `Rig.ray_pairs` and `RayPairs`",
     "accepted everywhere: the same motion as integer ids (one rule, "
     "`mcgeom.validation.integral_camera_ids`); a fraction, NaN or inf is refused everywhere")
def test_ids_integral_float():
    p1, p2, c1, c2, rig = pixels()
    ref = cv.estimate(p1, p2, c1, c2, rig)
    m = cv.estimate(p1, p2, c1.astype(float), c2.astype(np.float32), rig)
    np.testing.assert_array_equal(m.R, ref.R)
    np.testing.assert_array_equal(m.t, ref.t)
    a = rig.ray_pairs(p1, p2, c1.astype(float), c2.astype(float))
    np.testing.assert_array_equal(a.cam1, c1)
    np.testing.assert_array_equal(with_rays(cam1=rays().cam1.astype(float)).cam1, rays().cam1)
    for bad in (c1 + 0.5, np.where(c1 == 0, np.nan, c1)):
        with raises(ValueError, "cameraIds1 must hold integer camera ids"):
            cv.estimate(p1, p2, bad, c2, rig)
        with raises(ValueError, "cam1 must hold integer camera ids"):
            rig.ray_pairs(p1, p2, bad, c2)
        with raises(ValueError, "cam1 must hold integer camera ids"):
            with_rays(cam1=bad)


@row("rig-frame-wrong", "`load_rig(frame=)` 'imu', 'camera:nosuch', a 3x3 or non-rigid "
     "matrix, or 'body' for a file without a body frame (COLMAP, Kalibr without T_cam_imu)",
     "`ValueError`: frame must be 'body' ... / <file>: frame='camera:nosuch': no camera named "
     "or numbered 'nosuch'; the rig's cameras are ... / <file>: frame='body': the file ... has "
     "no body/IMU frame")
def test_rig_frame_wrong():
    rig4 = CALIB / "mcgeom" / "rig4.json"
    for bad, msg in (("imu", "frame must be 'body'"), (np.eye(3), "frame: a transform must be"),
                     (2.0 * np.eye(4), "frame: the 4x4 transform is not rigid"),
                     ("camera:nosuch", "frame='camera:nosuch': no camera named or numbered")):
        with raises(ValueError, msg):
            mcgeom.load_rig(rig4, frame=bad)
    for path in (CALIB / "colmap" / "rig_config.json",
                 CALIB / "kalibr" / "camchain-equidistant.yaml"):
        with raises(ValueError, "frame='body': the file of format .* has no body/IMU frame"):
            mcgeom.load_rig(path, frame="body")


# ------------------------------------------------------------------ the table

BEGIN, END = "<!-- rows of tests/test_bad_input.py: begin -->", "<!-- rows: end -->"
#: set to 1 to rewrite the table of docs/bad_input.md from ROWS
WRITE_ENV = "MCGEOM_WRITE_BAD_INPUT_TABLE"


def markdown_table() -> str:
    """The table of docs/bad_input.md, one line per row (test ``test_<id>``)."""
    lines = ["| row (test) | input | what it gets |", "| --- | --- | --- |"]
    lines += [f"| `{rid}` | {given} | {gets} |" for rid, given, gets in ROWS]
    return "\n".join(lines)


def test_table_lists_exactly_the_rows():
    """docs/bad_input.md lists every row of this module, in order, as written here,
    and every row has its test function."""
    text = TABLE.read_text(encoding="utf-8")
    assert BEGIN in text and END in text, f"{TABLE} lost its row markers"
    if os.environ.get(WRITE_ENV) == "1":
        # regenerate the table of docs/bad_input.md from the rows (tests/ holds no
        # scripts, so the test itself writes it on request), then check as usual
        head, rest = text.split(BEGIN, 1)
        text = f"{head}{BEGIN}\n{markdown_table()}\n{END}{rest.split(END, 1)[1]}"
        TABLE.write_text(text, encoding="utf-8")
    table = text.split(BEGIN, 1)[1].split(END, 1)[0].strip()
    assert table == markdown_table(), (
        f"docs/bad_input.md is out of date: regenerate it with {WRITE_ENV}=1 "
        "pytest tests/test_bad_input.py -k test_table_lists_exactly_the_rows")
    tests = {getattr(f, "row_id", None) for f in globals().values() if callable(f)}
    missing = [rid for rid, _, _ in ROWS if rid not in tests]
    assert not missing, f"rows without a test: {missing}"
    for rid, _, _ in ROWS:
        assert f"test_{rid.replace('-', '_')}" in globals(), rid

