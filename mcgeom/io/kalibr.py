"""Kalibr camera chains (``camchain.yaml`` / ``camchain-imucam.yaml``): load.

Conventions, and where they were checked
----------------------------------------

Sources: https://github.com/ethz-asl/kalibr/wiki/yaml-formats and .../supported-models,
checked against ``kalibr_common/ConfigReader.py``.

Top-level ``cam0, cam1, ...`` each with ``camera_model`` (``pinhole`` only:
``omni``/``ds``/``eucm`` are not OpenCV models and are refused), ``intrinsics: [fu, fv, pu, pv]``, ``distortion_model`` (``radtan`` ``[k1, k2, r1,
r2]`` -> OpenCV pinhole ``k1 k2 p1 p2``; ``equidistant`` ``[k1..k4]`` -> ``cv2.fisheye``,
the same Kannala-Brandt polynomial; ``none`` -> no distortion; ``fov`` refused),
``resolution: [width, height]``, ``T_cn_cnm1`` ("takes cam n-1 to cam n coordinates":
``X_cn = T_cn_cnm1 X_cnm1``) and ``T_cam_imu`` ("from IMU to camera coordinates":
``X_cam = T_cam_imu X_imu``), both 4x4. The chain is composed as ``T_cn_c0 = T_cn_cnm1
T_cnm1_c0``. ``rig_frame="cam0"`` puts the rig frame on cam0 (a ``T_cn_cnm1`` on cam0,
which Kalibr never writes, is ignored); ``rig_frame="imu"`` on the IMU, with
``T_cam_imu`` as each camera's cam_from_rig; the default is ``"imu"`` when every camera
has ``T_cam_imu`` and ``"cam0"`` otherwise. When a file has both ``T_cn_cnm1`` and
``T_cam_imu`` (Kalibr's camchain-imucam computes one from the other) they must agree to
1e-6 (rotation entries and metres), else the file describes two rigs and is refused.
Pixel coordinates are OpenCV's (Kalibr's corner detection is OpenCV's; its intrinsics are
used unchanged with OpenCV by everyone), so no offset is applied.

Kalibr writes the file with PyYAML's ``yaml.dump``: older PyYAML writes leaf lists in
flow style (``- [0.99, 0.01, ...]``), PyYAML >= 5.1 in block style (``- - 0.99``), both
with PyYAML's *indentless* sequences (``T_cn_cnm1:`` followed by ``- ...`` at the key's
own indentation), and long flow lists wrap over several lines. PyYAML is not a
dependency of mcgeom, and ``cv2.FileStorage`` -- even with a ``%YAML:1.0`` header
prepended -- rejects indentless sequences ("Incorrect indentation"), so this module has
a small strict parser for the YAML subset Kalibr writes: block mappings and sequences
(indentless and compact ``- - x`` too), flow sequences (nested, multi-line), plain and
quoted scalars, comments, one document. Anchors, aliases, tags, flow mappings, block
scalars, duplicate keys and tabs in indentation are refused with the line number.
"""

from __future__ import annotations

import json
import math
import re
from typing import Any

import numpy as np

from mcgeom.io._common import (_IDENTITY_POSE, _integer, _make_camera, _make_rig, _read_text,
                               _rotation, _vector, _where)
from mcgeom.rig import Rig
from mcgeom.validation import numeric

__all__ = ["load_kalibr"]

_CHAIN_TOL = 1e-6           # Kalibr T_cn_cnm1 vs T_cam_imu agreement (entries, metres)
_BOTTOM_ROW_TOL = 1e-9      # last row of a 4x4 rigid transform must be [0, 0, 0, 1]


# Rigid transforms as (R, t) with X_a = R X_b + t ("a_from_b").
def _compose(a_from_b: tuple[np.ndarray, np.ndarray],
             b_from_c: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    (R1, t1), (R2, t2) = a_from_b, b_from_c
    return R1 @ R2, R1 @ t2 + t1


def _inverse(a_from_b: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    R, t = a_from_b
    return R.T, -R.T @ t


def _matrix(where: str, what: str, value: Any, shape: tuple[int, int]) -> np.ndarray:
    """A finite float matrix of the given shape."""
    try:
        arr = numeric(what, value)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    if arr.shape != shape:
        raise ValueError(f"{where}: {what} must have shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{where}: {what} has non-finite entries")
    return arr


# --------------------------------------------------------------------------- YAML subset

class _YamlError(ValueError):
    pass


_FLOAT_RE = re.compile(r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?$")
_INT_RE = re.compile(r"[-+]?[0-9]+$")
_SPECIAL_FLOATS = {".inf": math.inf, "+.inf": math.inf, "-.inf": -math.inf, ".nan": math.nan,
                   ".Inf": math.inf, "+.Inf": math.inf, "-.Inf": -math.inf, ".NaN": math.nan,
                   ".INF": math.inf, "+.INF": math.inf, "-.INF": -math.inf, ".NAN": math.nan}
_UNSUPPORTED = {"&": "anchors", "*": "aliases", "!": "tags", "|": "block scalars",
                ">": "block scalars", "{": "flow mappings", "?": "complex keys",
                "@": "reserved indicators", "`": "reserved indicators"}


def _strip_comment(s: str) -> str:
    """``s`` without a trailing ``# comment`` (a '#' after whitespace, outside quotes)."""
    i, n, quote = 0, len(s), None
    while i < n:
        ch = s[i]
        if quote == '"':
            if ch == "\\":
                i += 1
            elif ch == '"':
                quote = None
        elif quote == "'":
            if ch == "'" and i + 1 < n and s[i + 1] == "'":
                i += 1  # '' is an escaped quote
            elif ch == "'":
                quote = None
        elif ch in "'\"" and (i == 0 or s[i - 1] in " \t[,:-"):
            quote = ch
        elif ch == "#" and (i == 0 or s[i - 1] in " \t"):
            return s[:i]
        i += 1
    return s


class _YamlSubset:
    """Strict parser for the YAML subset Kalibr (PyYAML ``yaml.dump``) writes."""

    MAX_DEPTH = 64  # nesting limit: a Kalibr file nests 3 deep; no RecursionError on junk

    def __init__(self, text: str, where: str):
        self.where = where
        self.depth = 0
        self.lines: list[list] = []  # [lineno, indent, content]
        started = ended = False
        for lineno, raw in enumerate(text.splitlines(), 1):
            body = _strip_comment(raw).rstrip()
            if not body.strip():
                continue
            stripped = body.lstrip(" ")
            if stripped.startswith("\t") or "\t" in body[: len(body) - len(stripped)]:
                self.fail(lineno, "tab in indentation (YAML allows spaces only)")
            indent = len(body) - len(stripped)
            if ended:
                self.fail(lineno, "content after the end-of-document marker '...'")
            if indent == 0 and re.match(r"---(\s|$)", stripped):
                if started:
                    self.fail(lineno, "a second YAML document ('---'): one document expected")
                started = True
                stripped = stripped[3:].strip()
                if not stripped:
                    continue
            elif indent == 0 and stripped.startswith("%"):
                if started or self.lines:
                    self.fail(lineno, "directive after the start of the document")
                continue
            elif indent == 0 and re.match(r"\.\.\.(\s|$)", stripped):
                ended = True
                continue
            started = True
            self.lines.append([lineno, indent, stripped])

    def fail(self, lineno: int, msg: str) -> None:
        raise _YamlError(f"{self.where}: line {lineno}: {msg}")

    def parse(self) -> Any:
        if not self.lines:
            raise _YamlError(f"{self.where}: empty YAML document")
        value, i = self.block(0, self.lines[0][1])
        if i < len(self.lines):
            lineno, indent, _ = self.lines[i]
            self.fail(lineno, f"content that does not fit the document's top-level "
                              f"{'sequence' if isinstance(value, list) else 'structure'} "
                              f"(indentation {indent})")
        return value

    # -- block structure
    @staticmethod
    def is_item(content: str) -> bool:
        return content == "-" or content.startswith("- ")

    def split_key(self, lineno: int, content: str) -> tuple[str, str] | None:
        """``(key, rest)`` if ``content`` is ``key: rest`` / ``key:``, else None."""
        if content[0] in "\"'":
            close = content.find(content[0], 1)
            if close < 0:
                self.fail(lineno, "unterminated quoted key")
            key = self.scalar(lineno, content[: close + 1])
            after = content[close + 1:]
            if not (after == ":" or after.startswith(": ")):
                return None
            return str(key), after[1:].strip()
        m = re.search(r":(\s|$)", content)
        if m is None:
            return None
        key = content[: m.start()].rstrip()
        if not key or key[0] in "[]{},#" or key.startswith("- "):
            return None
        return key, content[m.end():].strip()

    def nest(self, lineno: int) -> None:
        self.depth += 1
        if self.depth > self.MAX_DEPTH:
            self.fail(lineno, f"nesting deeper than {self.MAX_DEPTH} levels")

    def block(self, i: int, indent: int) -> tuple[Any, int]:
        self.nest(self.lines[i][0])
        try:
            return self._block(i, indent)
        finally:
            self.depth -= 1

    def _block(self, i: int, indent: int) -> tuple[Any, int]:
        lineno, ind, content = self.lines[i]
        if ind != indent:
            self.fail(lineno, f"bad indentation ({ind} spaces, expected {indent})")
        if self.is_item(content):
            return self.sequence(i, indent)
        if content[0] in _UNSUPPORTED:
            self.fail(lineno, f"unsupported YAML feature ({_UNSUPPORTED[content[0]]})")
        if self.split_key(lineno, content) is not None:
            return self.mapping(i, indent)
        value, i = self.inline(i, content, indent)
        return value, i

    def sequence(self, i: int, indent: int) -> tuple[list, int]:
        items = []
        n = len(self.lines)
        while i < n and self.lines[i][1] == indent and self.is_item(self.lines[i][2]):
            lineno, _, content = self.lines[i]
            rest = content[1:].lstrip(" ")
            if not rest:  # "-" alone: the item is the following, more indented block
                if i + 1 >= n or self.lines[i + 1][1] <= indent:
                    items.append(None)
                    i += 1
                    continue
                value, i = self.block(i + 1, self.lines[i + 1][1])
            elif self.is_item(rest) or (rest[0] not in "[\"'" and self.split_key(lineno, rest)):
                # compact nested sequence "- - x" or mapping "- key: v": re-read the rest of
                # the line as a block starting at its own column
                column = indent + len(content) - len(rest)
                self.lines[i] = [lineno, column, rest]
                value, i = self.block(i, column)
            else:
                value, i = self.inline(i, rest, indent)
            items.append(value)
        if i < n and self.lines[i][1] > indent:
            self.fail(self.lines[i][0], "unexpected indentation inside a sequence")
        return items, i

    def mapping(self, i: int, indent: int) -> tuple[dict, int]:
        out: dict = {}
        n = len(self.lines)
        while i < n and self.lines[i][1] == indent:
            lineno, _, content = self.lines[i]
            if self.is_item(content):
                self.fail(lineno, "a sequence item where a 'key: value' was expected")
            kv = self.split_key(lineno, content)
            if kv is None:
                self.fail(lineno, f"expected 'key: value', got {content[:40]!r}")
            key, rest = kv
            if key in out:
                self.fail(lineno, f"duplicate key {key!r}")
            if rest:
                out[key], i = self.inline(i, rest, indent)
            elif i + 1 < n and self.lines[i + 1][1] > indent:
                out[key], i = self.block(i + 1, self.lines[i + 1][1])
            elif i + 1 < n and self.lines[i + 1][1] == indent and self.is_item(self.lines[i + 1][2]):
                out[key], i = self.sequence(i + 1, indent)  # PyYAML's indentless sequence
            else:
                out[key], i = None, i + 1
        if i < n and self.lines[i][1] > indent:
            self.fail(self.lines[i][0], "unexpected indentation (multi-line plain scalars are "
                                        "not supported)")
        return out, i

    # -- inline values: scalars and (possibly multi-line) flow sequences
    def inline(self, i: int, text: str, parent_indent: int) -> tuple[Any, int]:
        lineno = self.lines[i][0]
        if text[0] in _UNSUPPORTED:
            self.fail(lineno, f"unsupported YAML feature ({_UNSUPPORTED[text[0]]})")
        if text[0] != "[":
            if re.search(r":(\s|$)", text) and text[0] not in "\"'":
                self.fail(lineno, f"unexpected ': ' in a plain value {text[:40]!r} (quote it)")
            return self.scalar(lineno, text), i + 1
        j = i + 1
        while not self.flow_closed(text):
            if j >= len(self.lines) or self.lines[j][1] <= parent_indent:
                self.fail(lineno, "unterminated flow sequence '[' (truncated file?)")
            text += " " + self.lines[j][2]
            j += 1
        value, pos = self.flow(lineno, text, 0)
        if text[pos:].strip():
            self.fail(lineno, f"unexpected text after a flow sequence: {text[pos:].strip()[:40]!r}")
        return value, j

    @staticmethod
    def flow_closed(text: str) -> bool:
        depth, quote = 0, None
        k = 0
        while k < len(text):
            ch = text[k]
            if quote == '"':
                if ch == "\\":
                    k += 1
                elif ch == '"':
                    quote = None
            elif quote == "'":
                if ch == "'" and k + 1 < len(text) and text[k + 1] == "'":
                    k += 1
                elif ch == "'":
                    quote = None
            elif ch in "'\"" and text[:k].rstrip()[-1:] in ("[", ","):
                quote = ch  # quotes open a scalar only at the start of an item
            elif ch == "[":
                depth += 1
            elif ch == "]":
                depth -= 1
                if depth == 0:
                    return True
            k += 1
        return False

    def flow(self, lineno: int, text: str, pos: int) -> tuple[list, int]:
        """Parse the flow sequence starting at ``text[pos] == '['``; return (list, end)."""
        self.nest(lineno)
        try:
            return self._flow(lineno, text, pos)
        finally:
            self.depth -= 1

    def _flow(self, lineno: int, text: str, pos: int) -> tuple[list, int]:
        assert text[pos] == "["
        pos += 1
        items: list = []
        expect_item = True
        while True:
            while pos < len(text) and text[pos] == " ":
                pos += 1
            if pos >= len(text):
                self.fail(lineno, "unterminated flow sequence '['")
            ch = text[pos]
            if ch == "]":
                if expect_item and items:
                    self.fail(lineno, "empty item in a flow sequence (',]')")
                return items, pos + 1
            if not expect_item:
                if ch != ",":
                    self.fail(lineno, f"expected ',' or ']' in a flow sequence, got {text[pos:pos + 20]!r}")
                pos += 1
                expect_item = True
                continue
            if ch == ",":
                self.fail(lineno, "empty item in a flow sequence (',,')")
            if ch == "[":
                value, pos = self.flow(lineno, text, pos)
            elif ch in "\"'":
                end = pos + 1
                while True:
                    end = text.find(ch, end)
                    if end < 0:
                        self.fail(lineno, "unterminated quoted string")
                    if ch == '"' and text[end - 1] == "\\" and text[end - 2] != "\\":
                        end += 1
                        continue
                    if ch == "'" and end + 1 < len(text) and text[end + 1] == "'":
                        end += 2
                        continue
                    break
                value, pos = self.scalar(lineno, text[pos:end + 1]), end + 1
            else:
                m = re.compile(r"[^,\[\]]*").match(text, pos)
                token = m.group(0).strip()
                if token and token[0] in _UNSUPPORTED:
                    self.fail(lineno, f"unsupported YAML feature ({_UNSUPPORTED[token[0]]})")
                if re.search(r":(\s|$)", token):
                    self.fail(lineno, "flow mappings inside sequences are not supported")
                value, pos = self.scalar(lineno, token), m.end()
            items.append(value)
            expect_item = False

    def scalar(self, lineno: int, tok: str) -> Any:
        if tok[0] == '"':
            if len(tok) < 2 or tok[-1] != '"':
                self.fail(lineno, f"unterminated quoted string {tok[:40]!r}")
            try:
                return json.loads(tok)
            except json.JSONDecodeError:
                self.fail(lineno, f"unsupported escape in {tok[:40]!r}")
        if tok[0] == "'":
            if len(tok) < 2 or tok[-1] != "'":
                self.fail(lineno, f"unterminated quoted string {tok[:40]!r}")
            return tok[1:-1].replace("''", "'")
        if tok[0] in _UNSUPPORTED:
            self.fail(lineno, f"unsupported YAML feature ({_UNSUPPORTED[tok[0]]})")
        if tok in ("null", "Null", "NULL", "~"):
            return None
        if tok in ("true", "True", "TRUE"):
            return True
        if tok in ("false", "False", "FALSE"):
            return False
        if _INT_RE.match(tok):
            return int(tok)
        if _FLOAT_RE.match(tok):
            return float(tok)
        if tok in _SPECIAL_FLOATS:
            return _SPECIAL_FLOATS[tok]
        return tok


def _parse_yaml_subset(text: str, where: str) -> Any:
    return _YamlSubset(text, where).parse()


# --------------------------------------------------------------------------- Kalibr

_KALIBR_OTHER_MODELS = {"omni": "omnidirectional (Mei)", "ds": "double sphere",
                        "eucm": "extended unified"}
_KALIBR_DIST = {"radtan": ("pinhole", 4), "equidistant": ("fisheye", 4), "none": ("pinhole", 0)}


def _kalibr_numbers(where: str, entry: str, cam: dict, key: str, n: int | None) -> np.ndarray:
    if key not in cam:
        raise ValueError(f"{where}: {entry}: missing key {key!r}")
    value = cam[key]
    if not isinstance(value, list):
        raise ValueError(f"{where}: {entry}: {key} must be a list, got {value!r}")
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise ValueError(f"{where}: {entry}: {key} must hold numbers, got {v!r}")
    return _vector(where, f"{entry}: {key}", value if value else np.zeros(0), n)


def _kalibr_transform(where: str, entry: str, key: str, value: Any) -> tuple[np.ndarray, np.ndarray]:
    """A Kalibr 4x4 homogeneous rigid transform as (R, t)."""
    what = f"{entry}: {key}"
    if not isinstance(value, list) or any(not isinstance(r, list) for r in value):
        raise ValueError(f"{where}: {what} must be a 4x4 matrix (a list of 4 rows), got {value!r}"[:300])
    T = _matrix(where, what, value, (4, 4))
    if np.max(np.abs(T[3] - [0, 0, 0, 1])) > _BOTTOM_ROW_TOL:
        raise ValueError(f"{where}: {what} is not a rigid transform: last row is {T[3].tolist()}, "
                         f"expected [0, 0, 0, 1]")
    return _rotation(where, what, T[:3, :3]), T[:3, 3].copy()


def _kalibr_camera(where: str, key: str, cam: Any) -> dict:
    if not isinstance(cam, dict):
        raise ValueError(f"{where}: {key} must be a mapping, got {cam!r}"[:300])
    cm = cam.get("camera_model")
    if cm is None:
        raise ValueError(f"{where}: {key}: missing key 'camera_model'")
    if cm in _KALIBR_OTHER_MODELS:
        raise ValueError(f"{where}: {key}: camera_model {cm!r} ({_KALIBR_OTHER_MODELS[cm]}) is not "
                         f"supported: mcgeom handles OpenCV pinhole and fisheye lenses only")
    if cm != "pinhole":
        raise ValueError(f"{where}: {key}: unknown camera_model {cm!r} (expected 'pinhole')")
    fu, fv, pu, pv = _kalibr_numbers(where, key, cam, "intrinsics", 4)
    dm = cam.get("distortion_model")
    if dm is None:
        raise ValueError(f"{where}: {key}: missing key 'distortion_model'")
    if dm not in _KALIBR_DIST:
        extra = " (the FOV model has no OpenCV equivalent)" if dm == "fov" else ""
        raise ValueError(f"{where}: {key}: distortion_model {dm!r} is not supported{extra}; "
                         f"expected one of {sorted(_KALIBR_DIST)}")
    model, n_coeffs = _KALIBR_DIST[dm]
    if "distortion_coeffs" not in cam and dm == "none":
        dist = np.zeros(0)
    else:
        dist = _kalibr_numbers(where, key, cam, "distortion_coeffs", n_coeffs)
    res = cam.get("resolution")
    if res is None:
        raise ValueError(f"{where}: {key}: missing key 'resolution'")
    if not isinstance(res, list) or len(res) != 2:
        raise ValueError(f"{where}: {key}: resolution must be [width, height], got {res!r}")
    width = _integer(where, f"{key}: resolution width", res[0])
    height = _integer(where, f"{key}: resolution height", res[1])
    K = np.array([[fu, 0.0, pu], [0.0, fv, pv], [0.0, 0.0, 1.0]])
    out = {"name": key, "K": K, "dist": dist, "model": model, "width": width, "height": height}
    for tkey in ("T_cn_cnm1", "T_cam_imu"):
        if tkey in cam:
            out[tkey] = _kalibr_transform(where, key, tkey, cam[tkey])
    return out


def load_kalibr(path: Any, *, rig_frame: str | None = None) -> Rig:
    """Read a Kalibr ``camchain.yaml`` / ``camchain-imucam.yaml``.

    Args:
        path: the camchain file.
        rig_frame: ``"cam0"`` (rig frame = cam0's frame) or ``"imu"`` (the IMU frame; every
            camera needs ``T_cam_imu``). Default: ``"imu"`` if every camera has
            ``T_cam_imu``, else ``"cam0"``.

    Cameras are named ``cam0, cam1, ...`` as in the file. Conventions: module docstring.
    """
    where = _where(path)
    if rig_frame not in (None, "cam0", "imu"):
        raise ValueError(f"rig_frame must be 'cam0' or 'imu', got {rig_frame!r}")
    doc = _parse_yaml_subset(_read_text(path), where)
    if not isinstance(doc, dict):
        raise ValueError(f"{where}: not a Kalibr camchain: the top level must be a mapping "
                         f"cam0, cam1, ..., got {type(doc).__name__}")
    indices = sorted(int(m.group(1)) for k in doc if isinstance(k, str)
                     for m in [re.fullmatch(r"cam(0|[1-9][0-9]*)", k)] if m)
    if not indices or indices[0] != 0:
        raise ValueError(f"{where}: not a Kalibr camchain: no top-level 'cam0' "
                         f"(top-level keys: {', '.join(map(str, list(doc)[:8]))})")
    gaps = [i for i in range(indices[-1] + 1) if i not in indices]
    if gaps:
        raise ValueError(f"{where}: cam{gaps[0]} is missing but cam{indices[-1]} is present")
    cams = [_kalibr_camera(where, f"cam{i}", doc[f"cam{i}"]) for i in indices]

    all_imu = all("T_cam_imu" in c for c in cams)
    frame = rig_frame or ("imu" if all_imu else "cam0")
    if frame == "imu" and not all_imu:
        lacking = next(c["name"] for c in cams if "T_cam_imu" not in c)
        raise ValueError(f"{where}: {lacking}: missing key 'T_cam_imu', needed for rig_frame='imu'")

    # Kalibr's two descriptions of one rig must agree (camchain-imucam derives one from
    # the other): T_cn_cnm1 == T_cn_imu T_cnm1_imu^-1.
    for n in range(1, len(cams)):
        cn, cp = cams[n], cams[n - 1]
        if "T_cn_cnm1" in cn and "T_cam_imu" in cn and "T_cam_imu" in cp:
            R_p, t_p = _compose(cn["T_cam_imu"], _inverse(cp["T_cam_imu"]))
            R_g, t_g = cn["T_cn_cnm1"]
            gap = max(float(np.max(np.abs(R_p - R_g))), float(np.max(np.abs(t_p - t_g))))
            if gap > _CHAIN_TOL:
                raise ValueError(f"{where}: cam{n}: T_cn_cnm1 disagrees with T_cam_imu of cam{n} "
                                 f"and cam{n - 1} (max difference {gap:.3g}): the file describes "
                                 f"two different rigs")

    poses: list[tuple[np.ndarray, np.ndarray]] = []
    for n, c in enumerate(cams):
        if frame == "imu":
            poses.append(c["T_cam_imu"])                  # X_cam = T_cam_imu X_imu
        elif n == 0:
            poses.append(_IDENTITY_POSE)                  # rig frame = cam0
        else:
            if "T_cn_cnm1" in c:
                step = c["T_cn_cnm1"]                     # X_cn = T_cn_cnm1 X_cnm1
            elif "T_cam_imu" in c and "T_cam_imu" in cams[n - 1]:
                step = _compose(c["T_cam_imu"], _inverse(cams[n - 1]["T_cam_imu"]))
            else:
                raise ValueError(f"{where}: cam{n}: missing key 'T_cn_cnm1' (pose of cam{n} "
                                 f"relative to cam{n - 1})")
            poses.append(_compose(step, poses[n - 1]))    # T_cn_c0 = T_cn_cnm1 T_cnm1_c0
    out = []
    for c, (R, t) in zip(cams, poses):
        out.append(_make_camera(where, c["name"], name=c["name"], K=c["K"], dist=c["dist"],
                                model=c["model"], R=R, t=t, width=c["width"], height=c["height"]))
    return _make_rig(where, out)
