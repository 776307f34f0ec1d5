"""Evaluation of the robust rig-motion pipeline on the real recordings in ../shared/data.

The data are read in place, never copied (root: ``--data``, else the environment
variable MCGEOM_REAL_DATA, else ../shared/data beside the working directory or
beside the source checkout)::

    mcgeom experiment real_data                 # every data set, every pair
    mcgeom experiment real_data --sets kitti_raw euroc --max-pairs 3

For every data set (``<data>/<dir>/load.py``, imported from its path) the
evaluation builds an :class:`mcgeom.rig.Rig` from the calibration, detects and matches
features with OpenCV (SIFT, else ORB; Lowe ratio test; mutual check) -- or takes the
tracked correspondences of the tracks-only set --, forms pixel correspondences between
consecutive frames

* intra-camera: camera i at frame k  <->  camera i at frame k+1,
* cross-camera: camera i at frame k  <->  camera j at frame k+1, for the camera pairs
  whose views overlap (found from the calibration, see :func:`overlapping_pairs`),

and runs :func:`mcgeom.cv.estimate` (default method) twice: on the intra-camera
correspondences only, and with the cross-camera ones added. The estimate is compared
with the ground truth.

Ground truth convention. The loaders give ``relative_pose(d, i, j)`` = pose of rig j in
rig i, ``X_rig_i = T X_rig_j``. mcgeom's motion is rig2_from_rig1, ``X_rig2 = R X_rig1 +
t`` (docs/architecture.md §3), i.e. ``inv(relative_pose(d, k, k+1))``. This is checked on
every pair by the Sampson error of the correspondences under the ground-truth motion,
computed here with an independent numpy implementation of the generalized epipolar
constraint (:func:`gec_sampson`), and compared with the error under the opposite
convention (which must be clearly larger on the moving sets).

Importable: :func:`load_sequences`, :func:`correspondences`, :func:`evaluate_pair`,
:func:`run` are used by the tests (tests/test_real_data.py).
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np

from mcgeom.sequence.features import FeatureDetector, match_descriptors
from mcgeom.sequence.frontend import overlapping_pairs

from .common import Progress, no_progress, positive_float, positive_int, write_line

try:
    import cv2
except ImportError:  # pragma: no cover - opencv is a runtime dependency of mcgeom
    cv2 = None

#: the environment variable that names the data root
DATA_ENV = "MCGEOM_REAL_DATA"

#: default inlier threshold of the robust pipeline, pixels
THRESHOLD_PX = 1.5
#: below this GT translation (metres) a pair is "static": the direction of t is noise
STATIC_T = 0.02


def data_available(root: Optional[Path] = None) -> bool:
    """True if the real data sets are present under ``root`` (default
    :data:`DATA_ROOT`): the tests skip cleanly otherwise."""
    return (Path(DATA_ROOT if root is None else root) / "README.md").is_file()


def default_data_root() -> Path:
    """The data root when ``--data`` is not given.

    $MCGEOM_REAL_DATA if set; else ../shared/data beside the working directory
    (a run from the root of a checkout); else ../shared/data beside the source
    checkout of this module, if it is there (from an install, ``__file__`` is in
    site-packages, so this guess only helps a source tree); else the first.
    """
    env = os.environ.get(DATA_ENV)
    if env:
        return Path(env)
    beside_cwd = Path.cwd().parent / "shared" / "data"
    # mcgeom/experiments/real_data.py: parents[2] is the checkout, [3] beside it
    beside_checkout = Path(__file__).resolve().parents[3] / "shared" / "data"
    for root in (beside_cwd, beside_checkout):
        if data_available(root):
            return root
    return beside_cwd


#: the data root of the tests and of the defaults below
DATA_ROOT = default_data_root()


def add_data_argument(ap: argparse.ArgumentParser) -> None:
    """The ``--data`` option of the experiments on the real recordings."""
    ap.add_argument("--data", type=Path, default=None,
                    help=f"root of the real recordings (default: ${DATA_ENV}, else "
                         f"../shared/data beside the working directory; now {DATA_ROOT})")


def data_root_or_none(args: argparse.Namespace, name: str) -> Optional[Path]:
    """The data root of the parsed options, or None after printing a one-line
    error that names the path and how to set it (the caller exits with 2)."""
    root = DATA_ROOT if args.data is None else args.data
    if data_available(root):
        return root
    print(f"mcgeom experiment {name}: error: no real recordings at {root} (no README.md "
          f"there); pass --data DIR or set {DATA_ENV}", file=sys.stderr)
    return None


# ------------------------------------------------------------------ geometry helpers

def rot_angle_deg(R: np.ndarray) -> float:
    """Rotation angle of R in degrees (robust near 0 and 180 deg)."""
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return float(np.degrees(np.arctan2(0.5 * np.linalg.norm(w), 0.5 * (np.trace(R) - 1.0))))


def angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle between two vectors, degrees (NaN if one is zero)."""
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    if not (na > 0 and nb > 0):
        return float("nan")
    return float(np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b)), float(a @ b))))


def gec_sampson(o1: np.ndarray, d1: np.ndarray, o2: np.ndarray, d2: np.ndarray,
                R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """First-order (Sampson) angular error, radians, of the generalized epipolar constraint.

    Own numpy implementation (independent of the C kernels) of docs/architecture.md §3:
    ``e = d2^T [t]x R d1 + d2^T R m1 + m2^T R d1`` with ``m = c x d``, divided by the
    norm of its gradient with respect to tangent perturbations of the unit bearings
    ``d1`` and ``d2`` (camera centres fixed). For one pinhole camera this is the usual
    Sampson distance in normalized units; times the focal length it is in pixels.
    """
    d1 = d1 / np.linalg.norm(d1, axis=1, keepdims=True)
    d2 = d2 / np.linalg.norm(d2, axis=1, keepdims=True)
    Rd1 = d1 @ R.T
    m1 = np.cross(o1, d1)
    m2 = np.cross(o2, d2)
    e = (np.einsum("ij,ij->i", d2, np.cross(t, Rd1)) + np.einsum("ij,ij->i", d2, m1 @ R.T)
         + np.einsum("ij,ij->i", m2, Rd1))
    # de/dd1 = R^T (d2 x t) + (R^T d2) x c1 + R^T (c2 x d2)
    Rtd2 = d2 @ R
    g1 = np.cross(d2, t) @ R + np.cross(Rtd2, o1) + m2 @ R
    # de/dd2 = t x R d1 + R m1 + (R d1) x c2
    g2 = np.cross(t, Rd1) + m1 @ R.T + np.cross(Rd1, o2)
    g1 -= np.einsum("ij,ij->i", g1, d1)[:, None] * d1
    g2 -= np.einsum("ij,ij->i", g2, d2)[:, None] * d2
    den = np.sqrt(np.einsum("ij,ij->i", g1, g1) + np.einsum("ij,ij->i", g2, g2))
    return np.abs(e) / np.maximum(den, 1e-300)


def front_fraction(o1: np.ndarray, d1: np.ndarray, o2: np.ndarray, d2: np.ndarray,
                   R: np.ndarray, t: np.ndarray, min_parallax: float = 1e-4) -> float:
    """Cheirality: fraction of correspondences triangulated in front of both cameras.

    The midpoint triangulation ``a R d1 - b d2 = o2 - R o1 - t`` (rig frames, metres)
    must have ``a, b > 0``. Pairs with parallax below ``min_parallax`` (radians; points
    at infinity, where the sign is noise) are left out; NaN if none is left. A motion
    whose translation has the wrong sign -- which the epipolar residual alone cannot see
    when the rotation is small -- puts most points behind the cameras.
    """
    d1 = d1 / np.linalg.norm(d1, axis=1, keepdims=True)
    d2 = d2 / np.linalg.norm(d2, axis=1, keepdims=True)
    A = d1 @ R.T
    rhs = o2 - (o1 @ R.T + t)
    c = np.einsum("ij,ij->i", A, d2)
    det = 1.0 - c * c
    ok = det > min_parallax ** 2
    if not ok.any():
        return float("nan")
    p = np.einsum("ij,ij->i", A, rhs)[ok]
    q = -np.einsum("ij,ij->i", d2, rhs)[ok]
    b = (q + c[ok] * p) / det[ok]
    a = p + c[ok] * b
    return float(np.mean((a > 0) & (b > 0)))


# ------------------------------------------------------------------ data sets

def import_loader(dirname: str, root: Path):
    """Import ``<root>/<dirname>/load.py`` under a private module name."""
    path = root / dirname / "load.py"
    spec = importlib.util.spec_from_file_location(f"_mcgeom_realdata_{dirname}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def rig_from_calib(d: dict):
    """mcgeom Rig (camera id = index in ``d['cameras']``) from a loader's calibration.

    The loaders give cam_from_rig ``X_cam = R_cam_rig X_rig + t_cam_rig`` -- mcgeom's own
    convention -- and distortion in OpenCV order (pinhole model).
    """
    from mcgeom.rig import Camera, Rig
    cams = []
    for name in d["cameras"]:
        c = d["calib"][name]
        cams.append(Camera(name=name, K=c["K"], dist=np.asarray(c["dist"], float).ravel(),
                           model="pinhole", R=c["R_cam_rig"], t=c["t_cam_rig"],
                           width=int(c["width"]), height=int(c["height"])))
    return Rig(tuple(cams))


@dataclass
class Sequence:
    """One evaluated recording: loaded data, rig, ground truth and the pairs to evaluate."""

    key: str                 # short name used on the command line
    name: str                # printed name
    d: dict                  # what the data set's load() returned
    mod: Any                 # its load module
    rig: Any                 # mcgeom Rig
    pairs: list              # [(k, k+1), ...] frame pairs to evaluate
    kind: str = "images"     # "images" or "tracks"
    static: bool = False     # the GT motion is ~0 (direction of t meaningless)
    cross_pairs: list = field(default_factory=list)   # [(i, j, overlap)]
    nfeatures: int = 3000
    note: str = ""
    alt_gt: Optional[Callable] = None   # (i, j) -> 4x4 second GT (relative_pose convention)
    alt_gt_name: str = ""
    #: k -> the vertical (gravity, pointing down) in the rig frame of frame k,
    #: from the recording's own inertial sensor; None: the recording gives none
    vertical: Optional[Callable[[int], np.ndarray]] = None
    vertical_name: str = ""

    def gt_motion(self, i: int, j: int, alt: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Ground truth rig2_from_rig1 (R, t): inv(relative_pose(d, i, j))."""
        T = self.alt_gt(i, j) if alt else self.mod.relative_pose(self.d, i, j)
        Tinv = np.linalg.inv(T)
        return Tinv[:3, :3].copy(), Tinv[:3, 3].copy()

    def gt_relative_pose(self, i: int, j: int) -> tuple[np.ndarray, np.ndarray]:
        """The loader's relative_pose as (R, t) -- the *opposite* convention, for the check."""
        T = self.mod.relative_pose(self.d, i, j)
        return T[:3, :3].copy(), T[:3, 3].copy()


SET_KEYS = ("dgp_scene_02", "dgp_scene_01", "kitti_raw", "euroc", "kitti00_tracks")


def load_sequences(keys=SET_KEYS, root: Optional[Path] = None, max_pairs: Optional[int] = None,
                   pairs: Optional[dict] = None) -> list[Sequence]:
    """Load the requested data sets (keys of :data:`SET_KEYS`) from ``root``
    (default :data:`DATA_ROOT`).

    ``pairs`` may map a key to an explicit list of frame pairs; ``max_pairs`` keeps the
    first pairs of each set.
    """
    root = DATA_ROOT if root is None else Path(root)
    seqs = []
    for key in keys:
        if key not in SET_KEYS:
            raise ValueError(f"unknown data set {key!r}; known: {', '.join(SET_KEYS)}")
        seqs.append(_load_one(key, root))
    for s in seqs:
        if pairs and s.key in pairs:
            s.pairs = list(pairs[s.key])
        if max_pairs is not None:
            s.pairs = s.pairs[:max_pairs]
    return seqs


def oxts_gravity(oxts: np.ndarray) -> np.ndarray:
    """Gravity (unit, pointing down) in the OXTS frame (x forward, y left, z
    up: KITTI raw's rig frame) from an OXTS packet's roll and pitch (fields 3
    and 4, radians; the devkit's world_from_imu = Rz(yaw) Ry(pitch) Rx(roll),
    world z up): Rx(roll)^T Ry(pitch)^T (0, 0, -1), the yaw drops out. What
    an inertial unit gives a car; the vertical prior of the upright sampler."""
    roll, pitch = float(oxts[3]), float(oxts[4])
    cr, sr, cp, sp = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch)
    # Ry(pitch)^T (0, 0, -1) = (sp, 0, -cp); then Rx(roll)^T
    return np.array([sp, -sr * cp, -cr * cp])


def _consecutive(frames: list) -> list[tuple[int, int]]:
    have = [k for k, f in enumerate(frames) if f.get("T_world_rig") is not None]
    return [(a, b) for a, b in zip(have, have[1:]) if b == a + 1]


def _load_one(key: str, root: Path) -> Sequence:
    if key.startswith("dgp_"):
        mod = import_loader("dgp_ddad_testscene", root)
        scene = key[4:]
        d = mod.load(scene)
        s = Sequence(key, d["name"], d, mod, rig_from_calib(d), _consecutive(d["frames"]),
                     nfeatures=4000, static=(scene == "scene_01"))
        s.note = ("parked car: GT motion 0, translation direction meaningless"
                  if s.static else "6-camera surround rig, 1.27 m / 0.1 deg per pair")
    elif key == "kitti_raw":
        mod = import_loader("kitti_raw_0023_tiny", root)
        d = mod.load()
        s = Sequence(key, d["name"], d, mod, rig_from_calib(d), _consecutive(d["frames"]),
                     nfeatures=3000)
        s.alt_gt = lambda i, j, m=mod, dd=d: m.relative_pose_ins(dd, i, j)
        s.alt_gt_name = "OXTS velocity integral"
        s.vertical = lambda k, dd=d: oxts_gravity(dd["frames"][k]["oxts_raw"])
        s.vertical_name = "OXTS roll and pitch"
        s.note = ("GT = OXTS poses, ~5 cm per-step position jitter (~5 % of |t|); the scale "
                  "error against the integrated INS velocity is given too")
    elif key == "euroc":
        mod = import_loader("euroc_v101_kimera", root)
        d = mod.load("micro")
        s = Sequence(key, d["name"], d, mod, rig_from_calib(d), _consecutive(d["frames"]),
                     nfeatures=2000, static=True)
        s.note = ("MAV standing still (GT |t| ~1 mm per pair): translation direction and "
                  "scale error are meaningless here; what matters is the verdict / |t|")
    elif key == "kitti00_tracks":
        mod = import_loader("kitti00_gtsam_stereo_tracks", root)
        d = mod.load()
        # the KITTI GT of frames 0..12 disagrees with the images (data README): skip them
        allp = _consecutive(d["frames"])
        s = Sequence(key, d["name"], d, mod, rig_from_calib(d), [p for p in allp if p[0] >= 13],
                     kind="tracks")
        s.note = ("GTSAM tracked stereo correspondences (no images); frames 0-12 skipped "
                  "(suspect GT)")
    else:  # pragma: no cover
        raise ValueError(key)
    s.cross_pairs = overlapping_pairs(s.rig)
    return s


# ------------------------------------------------------------------ features

class Features:
    """Keypoints + descriptors per image path, computed once (SIFT, else ORB) with
    :class:`mcgeom.sequence.features.FeatureDetector`; the cache keeps every image's
    features (a few frames per data set here)."""

    def __init__(self, nfeatures: int = 3000, detector: str = "auto"):
        if cv2 is None:
            raise RuntimeError("OpenCV (cv2) is needed for the image data sets")
        use_sift = detector == "sift" or (detector == "auto" and hasattr(cv2, "SIFT_create"))
        self.name = "SIFT" if use_sift else "ORB"
        self.nfeatures = nfeatures
        self._det = FeatureDetector("sift" if use_sift else "orb", nfeatures)
        self.norm = self._det.norm
        self._cache: dict = {}
        self.seconds = 0.0

    @property
    def n_images(self) -> int:
        """Number of distinct images detected so far (each is detected once)."""
        return len(self._cache)

    def __call__(self, path: str) -> tuple[np.ndarray, np.ndarray]:
        if path not in self._cache:
            t0 = time.perf_counter()
            img = cv2.imread(path, cv2.IMREAD_GRAYSCALE)
            if img is None:
                raise OSError(f"cannot read image {path}")
            kp = self._det.detect(img, what=path)
            self._cache[path] = (kp.pixels, kp.descriptors)
            self.seconds += time.perf_counter() - t0
        return self._cache[path]


# ------------------------------------------------------------------ correspondences

@dataclass
class Corr:
    """Pixel correspondences between frames k (1) and k+1 (2)."""

    p1: np.ndarray
    p2: np.ndarray
    c1: np.ndarray
    c2: np.ndarray
    seconds: float = 0.0

    @property
    def intra(self) -> np.ndarray:
        return self.c1 == self.c2

    def subset(self, mask: np.ndarray) -> "Corr":
        return Corr(self.p1[mask], self.p2[mask], self.c1[mask], self.c2[mask], self.seconds)


def _empty_corr() -> Corr:
    return Corr(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, np.int64), np.zeros(0, np.int64))


def _concat(parts: list) -> Corr:
    if not parts:
        return _empty_corr()
    return Corr(np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]),
                np.concatenate([np.full(len(p[0]), p[2], np.int64) for p in parts]),
                np.concatenate([np.full(len(p[0]), p[3], np.int64) for p in parts]))


def correspondences(seq: Sequence, k1: int, k2: int, feats: Optional[Features] = None) -> Corr:
    """Intra-camera and (for overlapping cameras) cross-camera correspondences k1 -> k2."""
    t0 = time.perf_counter()
    if seq.kind == "tracks":
        out = _track_correspondences(seq, k1, k2)
    else:
        feats = feats or Features(seq.nfeatures)
        f1, f2 = seq.d["frames"][k1], seq.d["frames"][k2]
        names = seq.d["cameras"]
        combos = [(i, i) for i in range(len(names))]
        for i, j, _ in seq.cross_pairs:
            combos += [(i, j), (j, i)]
        parts = []
        for i, j in combos:
            pts1, de1 = feats(f1["images"][names[i]])
            pts2, de2 = feats(f2["images"][names[j]])
            a, b, _ = match_descriptors(de1, de2, feats.norm)
            parts.append((pts1[a], pts2[b], i, j))
        out = _concat(parts)
    out.seconds = time.perf_counter() - t0
    return out


def _track_correspondences(seq: Sequence, k1: int, k2: int) -> Corr:
    o1, o2 = seq.d["frames"][k1]["obs"], seq.d["frames"][k2]["obs"]
    common = sorted(set(o1) & set(o2))
    names = seq.d["cameras"]
    parts = []
    combos = [(i, i) for i in range(len(names))]
    for i, j, _ in seq.cross_pairs:
        combos += [(i, j), (j, i)]
    for i, j in combos:
        a = np.array([o1[l][names[i]] for l in common], float).reshape(-1, 2)
        b = np.array([o2[l][names[j]] for l in common], float).reshape(-1, 2)
        parts.append((a, b, i, j))
    return _concat(parts)


# ------------------------------------------------------------------ GT check

def _focal(rig, c1: np.ndarray, c2: np.ndarray) -> np.ndarray:
    f = np.array([0.5 * (c.K[0, 0] + c.K[1, 1]) for c in rig.cameras])
    return 0.5 * (f[c1] + f[c2])


def sampson_px(seq: Sequence, corr: Corr, R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Sampson error (pixels) of every correspondence under the motion (R, t)."""
    if len(corr.p1) == 0:
        return np.zeros(0)
    rays = seq.rig.ray_pairs(corr.p1, corr.p2, corr.c1, corr.c2)
    r = gec_sampson(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2, R, t)
    return r * _focal(seq.rig, corr.c1, corr.c2)


def rotation_transfer_px(seq: Sequence, corr: Corr, R: np.ndarray) -> np.ndarray:
    """Angle (pixels) between d2 and R d1 -- the check for static pairs, where the
    epipolar constraint of one camera is undefined (no translation)."""
    if len(corr.p1) == 0:
        return np.zeros(0)
    rays = seq.rig.ray_pairs(corr.p1, corr.p2, corr.c1, corr.c2)
    a = rays.dirs1 @ R.T
    b = rays.dirs2
    ang = np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))
    return ang * _focal(seq.rig, corr.c1, corr.c2)


def gt_check(seq: Sequence, corr: Corr, k1: int, k2: int) -> dict:
    """Errors of the correspondences under the GT motion (and the opposite convention)."""
    R, t = seq.gt_motion(k1, k2)
    Rw, tw = seq.gt_relative_pose(k1, k2)
    intra = corr.intra
    out: dict = {}
    s = sampson_px(seq, corr, R, t)
    sw = sampson_px(seq, corr, Rw, tw)
    for tag, m in (("intra", intra), ("cross", ~intra)):
        if m.any():
            out[f"{tag}_med"] = float(np.median(s[m]))
            out[f"{tag}_lt2"] = float(np.mean(s[m] < 2.0))
            out[f"{tag}_med_wrong"] = float(np.median(sw[m]))
    if seq.static and intra.any():
        tr = rotation_transfer_px(seq, corr.subset(intra), R)
        out["intra_rot_transfer_med"] = float(np.median(tr))
        out["intra_rot_transfer_lt2"] = float(np.mean(tr < 2.0))
    return out


def format_gt_check(g: dict, static: bool) -> str:
    parts = []
    if static and "intra_rot_transfer_med" in g:
        parts.append("intra rotation-transfer median %.2f px (%.0f%% < 2 px)" % (
            g["intra_rot_transfer_med"], 100 * g["intra_rot_transfer_lt2"]))
    elif "intra_med" in g:
        parts.append("intra Sampson median %.2f px (%.0f%% < 2 px; opposite convention %.2f px)"
                     % (g["intra_med"], 100 * g["intra_lt2"], g["intra_med_wrong"]))
    if "cross_med" in g:
        parts.append("cross Sampson median %.2f px (%.0f%% < 2 px; opposite convention %.2f px)"
                     % (g["cross_med"], 100 * g["cross_lt2"], g["cross_med_wrong"]))
    return "; ".join(parts) if parts else "no correspondences"


# ------------------------------------------------------------------ evaluation

MODES = ("intra", "intra+cross")


def metric_t(m) -> np.ndarray:
    """The metric translation of an estimate, whatever the verdict: ``t`` when
    the scale is observable, zero when no translation was detected (the
    answer is the static rig: the free refinement's ``t_metric`` there is a
    slide along a flat cost, printed as hundreds of metres for the parked DDAD
    scene), else ``info["t_metric"]``, what |t| the data gave (the scale error
    of an unobservable answer)."""
    if m.scale.observable or m.info.get("translation_detected") is False:
        return np.asarray(m.t, float).ravel()
    return np.asarray(m.info.get("t_free", m.info.get("t_metric", m.t)), float).ravel()


def evaluate_pair(seq: Sequence, corr: Corr, k1: int, k2: int, mode: str,
                  threshold: float = THRESHOLD_PX, **options: Any) -> dict:
    """Run mcgeom.cv.estimate on one pair and mode; errors against the GT."""
    from mcgeom.cv import estimate
    use = corr if mode == "intra+cross" else corr.subset(corr.intra)
    R_gt, t_gt = seq.gt_motion(k1, k2)
    res = {"set": seq.name, "key": seq.key, "pair": (k1, k2), "mode": mode,
           "n_intra": int(use.intra.sum()), "n_cross": int((~use.intra).sum()),
           "t_gt": float(np.linalg.norm(t_gt)), "static": seq.static}
    t0 = time.perf_counter()
    try:
        m = estimate(use.p1, use.p2, use.c1, use.c2, seq.rig, threshold=threshold, **options)
    except Exception as exc:  # report, do not hide: the row says FAILED
        res.update(ok=False, error=f"{type(exc).__name__}: {exc}", time=time.perf_counter() - t0)
        return res
    res["time"] = time.perf_counter() - t0
    tm = metric_t(m)
    res.update(
        ok=True, motion=m, inliers=int(np.count_nonzero(m.inliers)),
        inliers_cross=int(np.count_nonzero(m.inliers & ~use.intra)),
        rot_err=rot_angle_deg(m.R @ R_gt.T), tdir_err=angle_deg(np.asarray(m.t).ravel(), t_gt),
        t_est=float(np.linalg.norm(tm)),
        scale_err=abs(np.linalg.norm(tm) / np.linalg.norm(t_gt) - 1.0)
        if np.linalg.norm(t_gt) >= STATIC_T else float("nan"),
        observable=bool(m.scale.observable), reason=m.scale.reason,
        rel_std=float(m.scale.rel_std),
        rel_std_calibration=float(m.info.get("scale_rel_std_calibration", float("nan"))),
        crit=float(np.degrees(m.scale.critical_angle)),
        gt_rot=rot_angle_deg(R_gt), sampler=str(m.info.get("sampler", "-")),
    )
    if seq.alt_gt is not None:
        _, t_alt = seq.gt_motion(k1, k2, alt=True)
        res["scale_err_alt"] = abs(np.linalg.norm(tm) / np.linalg.norm(t_alt) - 1.0)
    # cheirality of the returned motion on its inliers: direction of m.t, metric length
    # (the length the inliers were fitted with)
    t_dir = np.asarray(m.t, float).ravel()
    t_info = np.asarray(m.info.get("t_metric", t_dir), float).ravel()
    res["info_t_opposite"] = bool(t_info @ t_dir < 0)   # info's metric t vs returned t
    inl = use.subset(m.inliers)
    if len(inl.p1) and not seq.static and np.linalg.norm(t_dir) > 0:
        rays = seq.rig.ray_pairs(inl.p1, inl.p2, inl.c1, inl.c2)
        t_fit = t_dir * (np.linalg.norm(t_info) / np.linalg.norm(t_dir))
        res["front"] = front_fraction(rays.origins1, rays.dirs1, rays.origins2, rays.dirs2,
                                      np.asarray(m.R), t_fit)
    else:
        res["front"] = float("nan")   # static: no parallax, the sign is noise
    return res


HEADER = ("%-6s %-11s %6s %6s %6s %6s %8s %8s %8s %7s %7s %5s %-5s %8s %7s %-7s  %s" % (
    "pair", "mode", "#intra", "#cross", "#inl", "#inlX", "rot(deg)", "tdir(deg)", "scale_err",
    "|t_gt|", "|t_est|", "front", "verd", "crit(deg)", "time(s)", "sampler", "reason"))
#: the sampler column's short names (info["sampler"] of the C search)
SAMPLER_SHORT = {"five_plus_one": "5+1", "six_point": "6-pt", "upright_four_point": "upright"}


def format_row(r: dict) -> str:
    pair = "%d-%d" % r["pair"]
    if not r["ok"]:
        return "%-6s %-11s %6d %6d %6s %6s  FAILED after %.2f s: %s" % (
            pair, r["mode"], r["n_intra"], r["n_cross"], "-", "-", r["time"], r["error"])
    tdir = "%8.2f" % r["tdir_err"] if not r["static"] else "%8s" % "n/a*"
    if np.isfinite(r["scale_err"]):
        scale = "%8.3f" % r["scale_err"]
        if "scale_err_alt" in r:
            scale += " (%.3f)" % r["scale_err_alt"]
    else:
        scale = "%8s" % "n/a*"
    front = "%4.0f%%" % (100 * r["front"]) if np.isfinite(r["front"]) else "%5s" % "n/a"
    sampler = r.get("sampler", "-")
    return "%-6s %-11s %6d %6d %6d %6d %8.3f %8s %8s %7.4f %7.4f %5s %-5s %8.3f %7.2f %-7s  %s" % (
        pair, r["mode"], r["n_intra"], r["n_cross"], r["inliers"], r["inliers_cross"],
        r["rot_err"], tdir, scale, r["t_gt"], r["t_est"], front,
        "OBS" if r["observable"] else "unobs", r["crit"], r["time"],
        SAMPLER_SHORT.get(sampler, sampler), r["reason"]) + (
        "  [info['t_metric'] points opposite to t]" if r["info_t_opposite"] else "")


def summarize(seq: Sequence, results: list, out=print) -> list[dict]:
    rows = []
    for mode in MODES:
        rs = [r for r in results if r["mode"] == mode]
        ok = [r for r in rs if r["ok"]]
        row = {"set": seq.name, "key": seq.key, "mode": mode, "pairs": len(rs),
               "failed": len(rs) - len(ok)}
        if ok:
            def med(k, sel=ok):
                v = [r[k] for r in sel if np.isfinite(r[k])]
                return float(np.median(v)) if v else float("nan")
            obs = [r for r in ok if r["observable"]]
            # issue 18: |scale - 1| <= 3 rel_std on the moving pairs reported observable
            cov = [r["scale_err"] <= 3.0 * r["rel_std"] for r in obs
                   if np.isfinite(r["scale_err"])]
            row.update(covered=int(sum(cov)), covered_of=len(cov),
                       rel_std=med("rel_std", obs) if obs else float("nan"))
            row.update(rot=med("rot_err"), tdir=med("tdir_err"), scale=med("scale_err"),
                       scale_obs=med("scale_err", obs) if obs else float("nan"),
                       t_est=med("t_est"), obs_frac=len(obs) / len(ok), time=med("time"),
                       inl=med("inliers"), crit=med("crit"))
            if any("scale_err_alt" in r for r in ok):
                row["scale_alt"] = med("scale_err_alt")
        rows.append(row)
        if not ok:
            out("  %-11s %d pairs, all FAILED" % (mode, len(rs)))
            continue
        if seq.static:
            kinds: dict = {}
            for r in ok:
                k = "observable" if r["observable"] else r["reason"].split(":")[0].split(";")[0]
                kinds[k] = kinds.get(k, 0) + 1
            t_obs = [r["t_est"] for r in ok if r["observable"]]
            desc = ("median rot err %.3f deg | tdir n/a (static) | median |t_est| %.4f m, max "
                    "%s over observable verdicts (GT ~0) | observable %d/%d | verdicts: %s" % (
                        row["rot"], row["t_est"], "%.4f m" % max(t_obs) if t_obs else "-",
                        round(row["obs_frac"] * len(ok)), len(ok),
                        ", ".join("%d x %s" % (v, k) for k, v in sorted(kinds.items()))))
        else:
            alt = (" (vs %s %.3f)" % (seq.alt_gt_name, row["scale_alt"])
                   if "scale_alt" in row else "")
            desc = ("median rot err %.3f deg | tdir %.2f deg | scale err %.3f%s, over observable "
                    "verdicts %s | observable %d/%d | |scale-1| <= 3 rel_std on %d/%d observable "
                    "(median rel_std %s)" % (
                        row["rot"], row["tdir"], row["scale"], alt,
                        "%.3f" % row["scale_obs"] if np.isfinite(row["scale_obs"]) else "-",
                        round(row["obs_frac"] * len(ok)), len(ok), row["covered"],
                        row["covered_of"],
                        "%.4f" % row["rel_std"] if np.isfinite(row["rel_std"]) else "-"))
        out("  %-11s %2d pairs%s: %s | median crit %.3f deg | median inliers %.0f | "
            "median time %.2f s" % (mode, len(rs), (", %d FAILED" % row["failed"]) if row["failed"]
                                    else "", desc, row["crit"], row["inl"], row["time"]))
    return rows


def run(seqs: list[Sequence], threshold: float = THRESHOLD_PX, out=print,
        detector: str = "auto", nfeatures: Optional[int] = None,
        progress: Progress = no_progress, vertical: bool = False, **options: Any) -> dict:
    """Evaluate every pair of every sequence in both modes; print rows and summaries
    with ``out``; ``progress`` wraps the loop over the pairs of each sequence.
    ``vertical``: give the façade the recording's vertical (``gravity1``,
    ``gravity2`` from :attr:`Sequence.vertical`) where it has one, so that it
    runs the upright sampler; the others run as without it (said in their
    header)."""
    all_results: dict = {}
    summary = []
    for seq in seqs:
        feats = None
        if seq.kind == "images":
            feats = Features(nfeatures or seq.nfeatures, detector)
        out("")
        out("=" * 100)
        cams = ", ".join("%d=%s" % (i, n) for i, n in enumerate(seq.rig.names))
        out("%s  [%s]  cameras: %s" % (seq.name, seq.key, cams))
        out("  %s" % seq.note)
        if vertical:
            out("  vertical: " + (f"{seq.vertical_name} (upright sampler)" if seq.vertical
                                  else "none recorded: the default sampler"))
        if seq.cross_pairs:
            out("  cross-camera pairs (overlap from calibration): " + ", ".join(
                "%s-%s %.0f%%" % (seq.rig.names[i], seq.rig.names[j], 100 * f)
                for i, j, f in seq.cross_pairs))
        else:
            out("  no overlapping cameras: the intra+cross mode equals intra")
        if feats is not None:
            out("  features: %s, %d per image, ratio 0.8 + mutual check; threshold %.2f px"
                % (feats.name, feats.nfeatures, threshold))
        else:
            out("  correspondences: tracked landmarks; threshold %.2f px" % threshold)
        out(HEADER)
        results = []
        for k1, k2 in progress(seq.pairs, total=len(seq.pairs), desc=seq.key):
            corr = correspondences(seq, k1, k2, feats)
            g = gt_check(seq, corr, k1, k2)
            R_gt, t_gt = seq.gt_motion(k1, k2)
            out("%-6s GT |t| %.3f m, rot %.3f deg; GT check: %s" % (
                "%d-%d" % (k1, k2), np.linalg.norm(t_gt), rot_angle_deg(R_gt),
                format_gt_check(g, seq.static)))
            pair_opts = dict(options)
            if vertical and seq.vertical is not None:
                pair_opts.update(gravity1=seq.vertical(k1), gravity2=seq.vertical(k2))
            for mode in MODES:
                r = evaluate_pair(seq, corr, k1, k2, mode, threshold, **pair_opts)
                r["gt_check"] = g
                results.append(r)
                out(format_row(r))
        if feats is not None:
            out("  feature detection %.1f s in total (%d images)" % (feats.seconds,
                                                                     feats.n_images))
        out("-- summary %s" % seq.name)
        summary += summarize(seq, results, out)
        all_results[seq.key] = results
    out("")
    out("(*) n/a: the GT motion is ~0 (static rig), so the translation direction and the "
        "relative scale error are meaningless; judge the verdict and |t_est| instead.")
    out("scale_err = | |t_est| / |t_gt| - 1 |, with t_est the metric estimate (info['t_free'] / "
        "info['t_metric'] when the verdict is unobservable, 0 when no translation was "
        "detected); in brackets for KITTI raw: against the OXTS velocity integral.")
    all_results["_summary"] = summary
    return all_results


def print_summary_table(summary: list, out=print) -> None:
    out("")
    out("=" * 100)
    out("SUMMARY (medians over pairs)")
    out("%-16s %-11s %5s %8s %9s %9s %8s %6s %8s %9s" % (
        "data set", "mode", "pairs", "rot(deg)", "tdir(deg)", "scale_err", "|t_est|", "obs",
        "time(s)", "in 3sig"))
    for r in summary:
        if "rot" not in r:
            out("%-16s %-11s %5d  all FAILED" % (r["key"], r["mode"], r["pairs"]))
            continue
        static = r["key"] in ("euroc", "dgp_scene_01")
        out("%-16s %-11s %5d %8.3f %9s %9s %8.4f %6s %8.2f %9s%s" % (
            r["key"], r["mode"], r["pairs"], r["rot"],
            "n/a*" if static else "%.2f" % r["tdir"],
            "n/a*" if static else "%.3f" % r["scale"], r["t_est"],
            "%d%%" % round(100 * r["obs_frac"]), r["time"],
            "-" if static or not r["covered_of"] else "%d/%d" % (r["covered"], r["covered_of"]),
            ("  (%d failed)" % r["failed"]) if r["failed"] else ""))


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment real_data``."""
    ap.add_argument("--sets", nargs="*", default=list(SET_KEYS), choices=SET_KEYS,
                    metavar="SET", help="data sets to evaluate, of " + ", ".join(SET_KEYS))
    ap.add_argument("--max-pairs", type=positive_int, default=None,
                    help="evaluate only the first pairs of each set (default: all)")
    ap.add_argument("--threshold", type=positive_float, default=THRESHOLD_PX,
                    help="inlier threshold, pixels")
    ap.add_argument("--detector", choices=("auto", "sift", "orb"), default="auto",
                    help="feature detector (auto: SIFT if OpenCV has it, else ORB)")
    ap.add_argument("--nfeatures", type=positive_int, default=None,
                    help="features per image (default: per data set, 2000-4000)")
    ap.add_argument("--vertical", action="store_true",
                    help="give the façade each recording's own vertical where it has one "
                         "(KITTI raw: the OXTS roll and pitch): the upright sampler "
                         "(default: off, the 5+1 / 6-point choice)")
    add_data_argument(ap)


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Evaluate, print the rows and the summary table; 2 if the data are missing."""
    out = write_line   # rows are printed while the bar runs
    root = data_root_or_none(args, "real_data")
    if root is None:
        return 2
    if cv2 is not None:
        cv2.setNumThreads(2)
    import mcgeom
    out("mcgeom %s from %s; OpenCV %s; data %s" % (
        mcgeom.__version__, os.path.dirname(mcgeom.__file__),
        getattr(cv2, "__version__", "-"), root))
    t0 = time.perf_counter()
    seqs = load_sequences(args.sets, root, args.max_pairs)
    res = run(seqs, args.threshold, out=out, detector=args.detector,
              nfeatures=args.nfeatures, progress=progress, vertical=args.vertical)
    print_summary_table(res["_summary"], out)
    out("total %.1f s" % (time.perf_counter() - t0))
    return 0
