"""Image sequences of a rig on disk: which image of which camera belongs to which frame.

I/O only: this module finds files, reads time stamps and decodes images; it does
no geometry. :func:`find_image_sequence` recognises three layouts of a folder
``DIR`` (tried in this order):

``euroc``
    EuRoC / ASL: ``DIR/camN/data.csv`` (``#timestamp [ns],filename``) and the images
    in ``DIR/camN/data/``; ``DIR`` may also be the folder above ``mav0``. Cameras are
    the folders named as the rig's cameras, else ``cam0``, ``cam1``, ... in rig
    order. Frame times come from the first camera's ``data.csv`` (seconds).
``kitti``
    KITTI raw: ``DIR/image_0X/data/*.png`` (``image_02`` / ``image_03`` colour,
    ``image_00`` / ``image_01`` grey), with ``image_0X/timestamps.txt`` when present
    (``YYYY-MM-DD hh:mm:ss.fffffffff``, turned into POSIX seconds, read as UTC).
    Folders named as the rig's cameras win; else a 2-camera rig takes the colour
    pair if both folders are there (the grey pair otherwise), and a 4-camera rig
    takes ``image_00`` .. ``image_03``.
``folders``
    One sub-folder per camera, named as in the rig or ``cam0``, ``cam1``, ... in rig
    order, each holding the same number of image files; the sorted file names give
    the frame order. No time stamps (``None``).

Every problem is a ``ValueError`` naming the folder and what is wrong (expected and
found camera folders, image counts per camera, a file that is not an image, fewer
than 2 frames after slicing); :func:`read_image` names the file it cannot decode.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np

from mcgeom.io._common import describe_path, read_text
from mcgeom.rig import Rig
from mcgeom.validation import check_int

__all__ = ["ImageSequence", "find_image_sequence", "read_image", "IMAGE_EXTENSIONS"]

#: file name endings (lower case) taken as images; others in a camera folder are an error
IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm",
                    ".pnm", ".pbm", ".webp", ".jp2")

_KITTI_COLOUR = ("image_02", "image_03")
_KITTI_GREY = ("image_00", "image_01")
_KITTI_ALL = ("image_00", "image_01", "image_02", "image_03")
#: EuRoC cameras are hardware-triggered: time stamps of one frame agree to well under
#: a frame period (20 Hz); more than this (seconds) means the rows are not one frame
_SYNC_TOLERANCE_S = 1e-3


@dataclass(frozen=True)
class ImageSequence:
    """The image files of a rig's sequence.

    Attributes:
        root: the folder the layout was found in.
        layout: ``"folders"``, ``"euroc"`` or ``"kitti"``.
        folders: the camera folders used, in rig order (``folders[i]`` holds the
            images of ``rig.cameras[i]``).
        paths: ``paths[k][i]`` is the image of camera ``i`` in frame ``k`` (after
            slicing), as a string path.
        timestamps: (n_frames,) float64 seconds when the layout gives them, else None.
        indices: (n_frames,) int64: the frame numbers in the full, unsliced sequence.
    """

    root: Path
    layout: str
    folders: tuple[str, ...]
    paths: tuple[tuple[str, ...], ...]
    timestamps: Optional[np.ndarray]
    indices: np.ndarray

    def __len__(self) -> int:
        return len(self.paths)

    @property
    def n_frames(self) -> int:
        """Number of frames (after slicing)."""
        return len(self.paths)

    @property
    def n_cameras(self) -> int:
        """Number of cameras (images per frame)."""
        return len(self.folders)

    def read(self, frame: int, camera: int, grey: bool = True) -> np.ndarray:
        """The image of ``camera`` in ``frame``: see :func:`read_image`."""
        if not 0 <= frame < self.n_frames:
            raise ValueError(f"{describe_path(self.root)}: frame {frame} out of range "
                             f"0..{self.n_frames - 1}")
        if not 0 <= camera < self.n_cameras:
            raise ValueError(f"{describe_path(self.root)}: camera {camera} out of range "
                             f"0..{self.n_cameras - 1}")
        return read_image(self.paths[frame][camera], grey=grey)


def read_image(path: Any, grey: bool = True) -> np.ndarray:
    """Decode one image file with OpenCV.

    Args:
        path: the file.
        grey: decode to one 8-bit channel (``cv2.IMREAD_GRAYSCALE``), else BGR.

    Returns:
        (H, W) uint8 (grey) or (H, W, 3) uint8 (BGR) array.

    Raises:
        ValueError: the file is missing, unreadable or not a decodable image
            (``cv2.imread`` returned None); the message names the file.
    """
    import cv2

    name = describe_path(path)
    if not os.path.isfile(name):
        raise ValueError(f"{name}: image file not found")
    img = cv2.imread(name, cv2.IMREAD_GRAYSCALE if grey else cv2.IMREAD_COLOR)
    if img is None:
        raise ValueError(f"{name}: cannot read the image (unreadable, corrupt or not an "
                         f"image format OpenCV decodes)")
    return img


# ----------------------------------------------------------------------------- helpers

def _subdirs(d: Path) -> list[str]:
    return sorted(p.name for p in d.iterdir() if p.is_dir() and not p.name.startswith("."))


def _image_files(folder: Path, where: str) -> list[str]:
    """Sorted image file names of a folder; ValueError for a file that is not an image
    (hidden files and sub-folders are skipped)."""
    names = []
    for p in sorted(folder.iterdir()):
        if p.name.startswith(".") or p.is_dir():
            continue
        if p.suffix.lower() not in IMAGE_EXTENSIONS:
            raise ValueError(f"{where}: {describe_path(p)} is not an image file (expected "
                             f"one of {', '.join(IMAGE_EXTENSIONS)})")
        names.append(p.name)
    return names


def _holds_images(folder: Path) -> bool:
    return any(p.suffix.lower() in IMAGE_EXTENSIONS for p in folder.iterdir()
               if p.is_file() and not p.name.startswith("."))


def _indexed_names(n: int) -> tuple[str, ...]:
    return tuple(f"cam{i}" for i in range(n))


def _camera_folders(root: Path, rig: Rig, candidates: list[str], what: str) -> tuple[str, ...]:
    """The camera folders in rig order: the rig's names if all are there, else
    cam0..camM-1; ValueError naming the expected and the found folders, and the
    camera count mismatch, otherwise."""
    names, indexed = tuple(rig.names), _indexed_names(len(rig))
    have = set(candidates)
    for choice in (names, indexed):
        if have.issuperset(choice):
            extra = sorted(have - set(choice))
            if extra:
                raise ValueError(
                    f"{describe_path(root)}: the rig has {len(rig)} cameras ({', '.join(choice)}) "
                    f"but the folder holds {len(candidates)} {what} ({', '.join(candidates)}); "
                    f"extra: {', '.join(extra)}")
            return choice
    raise ValueError(
        f"{describe_path(root)}: no {what} for the rig's {len(rig)} cameras: expected "
        f"{', '.join(names)} (the rig's camera names) or {', '.join(indexed)} (rig order); "
        f"found {', '.join(candidates) if candidates else 'none'}"
        + (f"; missing {', '.join(sorted(set(names) - have))}" if have & set(names) else ""))


def _check_counts(root: Path, folders: Sequence[str], counts: Sequence[int]) -> None:
    if len(set(counts)) > 1:
        per = ", ".join(f"{f}: {c}" for f, c in zip(folders, counts))
        raise ValueError(f"{describe_path(root)}: the cameras have different numbers of "
                         f"images ({per}); every camera needs one image per frame")


def _slice(root: Path, n: int, start: Any, end: Any, step: Any) -> range:
    """The frame indices ``start:end:step`` of n frames, validated."""
    where = describe_path(root)
    s = check_int("start", start)
    st = check_int("step", step)
    e = n if end is None else check_int("end", end)
    if st < 1:
        raise ValueError(f"{where}: step must be >= 1, got {st}")
    if not 0 <= s < n:
        raise ValueError(f"{where}: start {s} out of range: the sequence has {n} frames "
                         f"(0..{n - 1})")
    if not s < e <= n:
        raise ValueError(f"{where}: end {e} out of range: need start ({s}) < end <= {n} "
                         f"(the number of frames; end is exclusive)")
    r = range(s, e, st)
    if len(r) < 2:
        raise ValueError(f"{where}: {len(r)} frame(s) after slicing start={s}, end={e}, "
                         f"step={st} (of {n}); a sequence needs at least 2 frames")
    return r


# ----------------------------------------------------------------------------- layouts

def _euroc_root(root: Path) -> Optional[Path]:
    for d in (root, root / "mav0"):
        if d.is_dir() and any((d / s / "data.csv").is_file() for s in _subdirs(d)):
            return d
    return None


def _read_euroc_csv(csv: Path) -> tuple[np.ndarray, list[str]]:
    """Time stamps (ns, int64) and file names of an ASL ``data.csv``."""
    stamps, files = [], []
    for lineno, line in enumerate(read_text(csv).splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        parts = [p.strip() for p in line.split(",")]
        if len(parts) != 2 or not parts[0].isdigit() or not parts[1]:
            raise ValueError(f"{describe_path(csv)}: line {lineno}: expected "
                             f"'timestamp_ns,filename', got {line!r}")
        stamps.append(int(parts[0]))
        files.append(parts[1])
    return np.array(stamps, dtype=np.int64), files


def _euroc(root: Path, rig: Rig) -> tuple[str, tuple[str, ...], list[list[str]], np.ndarray]:
    base = _euroc_root(root)
    assert base is not None
    cands = [s for s in _subdirs(base) if (base / s / "data.csv").is_file()]
    folders = _camera_folders(base, rig, cands, "camera folders with a data.csv")
    stamps, columns = [], []
    for f in folders:
        ns, files = _read_euroc_csv(base / f / "data.csv")
        data = base / f / "data"
        for name in files:
            if Path(name).suffix.lower() not in IMAGE_EXTENSIONS:
                raise ValueError(f"{describe_path(base / f / 'data.csv')}: {name} is not an "
                                 f"image file")
        missing = [n for n in files if not (data / n).is_file()]
        if missing:
            raise ValueError(f"{describe_path(data)}: {len(missing)} image(s) listed in "
                             f"data.csv are missing, e.g. {missing[0]}")
        stamps.append(ns)
        columns.append([str(data / n) for n in files])
    _check_counts(base, folders, [len(c) for c in columns])
    for f, ns in zip(folders[1:], stamps[1:]):
        gap = np.abs(ns - stamps[0]) * 1e-9
        if gap.size and gap.max() > _SYNC_TOLERANCE_S:
            k = int(np.argmax(gap))
            raise ValueError(f"{describe_path(base)}: {f} is not synchronised with "
                             f"{folders[0]}: row {k} differs by {gap[k]:.4f} s")
    return str(base), folders, columns, stamps[0] * 1e-9


def _kitti_stamps(path: Path) -> np.ndarray:
    out = []
    for lineno, line in enumerate(read_text(path).splitlines(), 1):
        line = line.strip()
        if not line:
            continue
        # KITTI writes nanoseconds; datetime keeps microseconds, so the fraction is
        # added separately to keep the full resolution
        head, _, frac = line.partition(".")
        try:
            whole = datetime.strptime(head, "%Y-%m-%d %H:%M:%S").replace(tzinfo=timezone.utc)
            sub = float("0." + frac) if frac else 0.0
            if frac and not frac.isdigit():
                raise ValueError(frac)
        except ValueError:
            raise ValueError(f"{describe_path(path)}: line {lineno}: expected "
                             f"'YYYY-MM-DD hh:mm:ss.fffffffff', got {line!r}") from None
        out.append(whole.timestamp() + sub)
    return np.array(out, dtype=np.float64)


def _kitti(root: Path, rig: Rig) -> tuple[str, tuple[str, ...], list[list[str]], Optional[np.ndarray]]:
    cands = [s for s in _subdirs(root) if s.startswith("image_") and (root / s / "data").is_dir()]
    names = tuple(rig.names)
    if set(names) <= set(cands):
        folders = names
    elif len(rig) == 2 and set(_KITTI_COLOUR) <= set(cands):
        folders = _KITTI_COLOUR
    elif len(rig) == 2 and set(_KITTI_GREY) <= set(cands):
        folders = _KITTI_GREY
    elif len(rig) == 4 and set(_KITTI_ALL) <= set(cands):
        folders = _KITTI_ALL
    else:
        raise ValueError(
            f"{describe_path(root)}: KITTI raw layout with folders {', '.join(cands)}, but the "
            f"rig has {len(rig)} cameras ({', '.join(names)}): expected folders named as the "
            f"rig's cameras, or a 2-camera rig (image_02 + image_03, or image_00 + image_01), "
            f"or a 4-camera rig (image_00 .. image_03)")
    columns = [[str(root / f / "data" / n) for n in
                _image_files(root / f / "data", describe_path(root / f / "data"))]
               for f in folders]
    _check_counts(root, folders, [len(c) for c in columns])
    stamps = None
    ts = root / folders[0] / "timestamps.txt"
    if ts.is_file():
        stamps = _kitti_stamps(ts)
        # KITTI names an image by its frame number (0000000005.png is line 5 of
        # timestamps.txt): a folder may hold a part of the drive
        stems = [Path(c).stem for c in columns[0]]
        if all(s.isdigit() for s in stems) and stems and max(map(int, stems)) < stamps.size:
            stamps = stamps[[int(s) for s in stems]]
        elif stamps.size != len(stems):
            raise ValueError(f"{describe_path(ts)}: {stamps.size} time stamps for "
                             f"{len(stems)} images whose names are not frame numbers")
    return str(root), folders, columns, stamps


def _folders(root: Path, rig: Rig) -> tuple[str, tuple[str, ...], list[list[str]], None]:
    cands = [s for s in _subdirs(root) if _holds_images(root / s)]
    folders = _camera_folders(root, rig, cands, "camera folders with images")
    columns = [[str(root / f / n) for n in _image_files(root / f, describe_path(root / f))]
               for f in folders]
    _check_counts(root, folders, [len(c) for c in columns])
    return str(root), folders, columns, None


def find_image_sequence(directory: Any, rig: Rig, *, start: int = 0, end: Optional[int] = None,
                        step: int = 1) -> ImageSequence:
    """Find the frames of ``rig``'s image sequence in ``directory``.

    Args:
        directory: a folder in one of the layouts of this module's docstring
            (``euroc``, ``kitti``, ``folders``, recognised in that order).
        rig: the calibrated rig; its camera names (or ``cam0``.. in rig order) name
            the camera folders, and it fixes the number of cameras.
        start, end, step: frame slicing ``start:end:step`` of the full sequence
            (``end`` exclusive, default all frames; ``step >= 1``).

    Returns:
        An :class:`ImageSequence`: per frame one path per rig camera, in rig order;
        time stamps in seconds for the EuRoC and KITTI layouts.

    Raises:
        ValueError: the folder is missing or in no known layout; camera folders
            missing or not matching the rig (the message lists the expected and the
            found folders); cameras with different numbers of images (each count is
            named); a non-image file in a camera folder; bad slicing or fewer than 2
            frames after it.
    """
    if not isinstance(rig, Rig):
        raise ValueError(f"rig must be a mcgeom.rig.Rig, got {type(rig).__name__}")
    root = Path(os.fspath(directory))
    if not root.is_dir():
        raise ValueError(f"{describe_path(root)}: not a folder")
    if _euroc_root(root) is not None:
        layout, found = "euroc", _euroc(root, rig)
    elif any(s.startswith("image_") and (root / s / "data").is_dir() for s in _subdirs(root)):
        layout, found = "kitti", _kitti(root, rig)
    else:
        layout, found = "folders", _folders(root, rig)
    base, folders, columns, stamps = found
    n = len(columns[0])
    if n == 0:
        raise ValueError(f"{describe_path(base)}: the camera folders hold no images")
    r = _slice(Path(base), n, start, end, step)
    idx = np.array(r, dtype=np.int64)
    paths = tuple(tuple(col[k] for col in columns) for k in r)
    return ImageSequence(root=Path(base), layout=layout, folders=tuple(folders), paths=paths,
                         timestamps=None if stamps is None else np.ascontiguousarray(stamps[idx]),
                         indices=idx)
