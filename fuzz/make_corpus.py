#!/usr/bin/env python3
"""Write the seed corpora of the fuzzing harnesses into fuzz/build/seeds/<harness>/.

    python fuzz/make_corpus.py [harness ...]

Seeds are generated, never committed: deterministic (fixed RNG seed) byte
strings in the input format the harness decodes.

- C harnesses (fuzz/c/fuzz_input.h): the first byte selects the routine
  (each harness declares how many with ``#define FUZZ_MODES N``, read here:
  a new harness needs no edit of this script), the rest is a stream the
  decoder reads as sizes and doubles; each seed is encoded with the
  decoder's "nice" double format (selector byte < 224, then a 16-bit integer
  / 4096), a few with special values (NaN, inf, denormals, 1e150, DBL_MAX).
- fuzz_calibration: byte 0 picks the calibration file of tests/data/calibration
  (and with it the loader), byte 1 the file or a sibling it reads, the rest is
  the text; the seeds are the hand-written files themselves, whole and
  truncated.
- fuzz_estimate, fuzz_estimators: byte strings decoded by
  atheris.FuzzedDataProvider (sizes, seeds, flags, floats).
"""
from __future__ import annotations

import math
import random
import re
import struct
import sys
from pathlib import Path

FUZZ = Path(__file__).resolve().parent
ROOT = FUZZ.parent
SEEDS = FUZZ / "build" / "seeds"



def c_modes() -> dict[str, int]:
    """Routines selected by the first byte of each C harness's input: its
    ``#define FUZZ_MODES N`` (every fuzz/c/fuzz_*.c must declare it)."""
    modes = {}
    for src in sorted((FUZZ / "c").glob("fuzz_*.c")):
        m = re.search(r"^#define FUZZ_MODES (\d+)\b", src.read_text(), re.M)
        if m is None:
            sys.exit(f"make_corpus: {src.relative_to(ROOT)} declares no '#define FUZZ_MODES N'")
        modes[src.stem] = int(m.group(1))
    return modes


MODES = c_modes()

# the calibration files, in the order fuzz/python/fuzz_calibration.py indexes
# them, with the sibling files its byte 1 can select instead (byte 1 % 4 >= 2:
# sibling number byte 1 % len(siblings))
CALIBRATION_FILES = [
    ("mcgeom/rig4.json", []),
    ("opencv/rig4.yml", []),
    ("opencv/stereo_calib.yml", ["opencv/stereo_calib/intrinsics.yml",
                                 "opencv/stereo_calib/extrinsics.yml"]),
    ("kalibr/camchain-equidistant.yaml", []),
    ("kalibr/camchain-imucam-radtan.yaml", []),
    ("colmap/rig_config.json", ["colmap/cameras.txt", "colmap/images.txt"]),
    ("colmap/rig_config_legacy.json", ["colmap/cameras.txt", "colmap/images.txt"]),
]


def nice(x: float) -> bytes:
    """A double in the decoder's nice format (exact for multiples of 1/4096)."""
    v = max(-32768, min(32767, round(x * 4096)))
    return bytes([0]) + struct.pack("<h", v)


def special(k: int) -> bytes:
    """A special value: index into fz_special's table (k = 28 NaN, 29 inf)."""
    return bytes([230, k])


def raw(x: float) -> bytes:
    return bytes([250]) + struct.pack("<d", x)


def c_seeds(name: str, rng: random.Random) -> list[bytes]:
    out = []
    for mode in range(MODES[name]):
        for length in (16, 64, 256, 1024, 3000):
            body = bytearray()
            while len(body) < length:
                r = rng.random()
                if r < 0.15:
                    # a size-like 16-bit value (decoders take it modulo the range)
                    body += bytes([rng.randrange(15)]) + struct.pack("<H", rng.randrange(65536))
                elif r < 0.9:
                    body += nice(rng.uniform(-4.0, 4.0))
                elif r < 0.97:
                    body += bytes([rng.randrange(256)])
                else:
                    body += special(rng.randrange(31)) if rng.random() < 0.7 else \
                        raw(rng.choice([5e-324, 1e150, -1e-300, 1.7976931348623157e308]))
            out.append(bytes([mode]) + bytes(body))
    return out


def calibration_seeds() -> list[bytes]:
    """Each file (byte 1 = 0: the file itself), whole and truncated, and each
    sibling (byte 1 = 2 or 3 selects sibling 0 or 1 of two)."""
    base = ROOT / "tests" / "data" / "calibration"
    out = []
    for i, (rel, siblings) in enumerate(CALIBRATION_FILES):
        text = (base / rel).read_bytes()
        out += [bytes([i, 0]) + text, bytes([i, 0]) + text[: len(text) // 2]]
        for sel in (2, 3)[: len(siblings)]:
            out.append(bytes([i, sel]) + (base / siblings[sel % len(siblings)]).read_bytes())
    return out


def random_seeds(rng: random.Random, n: int = 24) -> list[bytes]:
    return [bytes(rng.randrange(256) for _ in range(rng.choice([32, 128, 512, 2048])))
            for _ in range(n)]


def _u16_in(x: float, lo: float, hi: float) -> bytes:
    """The fz_range(in, lo, hi) encoding of x (a little-endian 16-bit fraction)."""
    return struct.pack("<H", max(0, min(65535, round((x - lo) / (hi - lo) * 65535))))


def _rodrigues(w: list) -> list:
    """The rotation (3 x 3 nested lists) of the angle-axis vector w."""
    th = math.sqrt(sum(v * v for v in w)) or 1e-300
    k = [v / th for v in w]
    c, s_, v_ = math.cos(th), math.sin(th), 1.0 - math.cos(th)
    R = [[k[i] * k[j] * v_ + (c if i == j else 0.0) for j in range(3)] for i in range(3)]
    R[0][1] -= k[2] * s_; R[0][2] += k[1] * s_; R[1][0] += k[2] * s_
    R[1][2] -= k[0] * s_; R[2][0] -= k[1] * s_; R[2][1] += k[0] * s_
    return R


def essential5_seeds(rng: random.Random) -> list[bytes]:
    """fuzz_essential5: well-posed 5-point problems as the harness decodes them
    (mode 0: rotation angles, translation, five points, no replaced entry;
    mode 2: each degenerate kind of the same; mode 1: the bearings of such a
    problem as nice doubles, i.e. rounded to 1/4096 like a noisy sample)."""
    out = []
    for _ in range(8):
        w = [rng.uniform(-0.5, 0.5) for _ in range(3)]
        t = [rng.uniform(-2.0, 2.0) for _ in range(3)]
        pts = [(rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(2.0, 8.0)) for _ in range(5)]
        body = b"".join(_u16_in(v, -1.5, 1.5) for v in w)
        body += b"".join(_u16_in(v, -2.0, 2.0) for v in t)
        for x, y, z in pts:
            body += _u16_in(x, -4.0, 4.0) + _u16_in(y, -4.0, 4.0) + _u16_in(z, 0.5, 8.0)
        out.append(bytes([0]) + body + bytes([1]))
        out += [bytes([2, kind]) + body for kind in range(5)]
        # the same problem's bearings (rotation by Rodrigues' formula)
        R = _rodrigues(w)
        d1, d2 = [], []
        for X in pts:
            X2 = [sum(R[i][j] * X[j] for j in range(3)) + t[i] for i in range(3)]
            for P, d in ((X, d1), (X2, d2)):
                n = math.sqrt(sum(v * v for v in P))
                d += [4.0 * v / n for v in P]
        out.append(bytes([1]) + b"".join(nice(v) for v in d1 + d2))
    return out


def sixpt_seeds(rng: random.Random) -> list[bytes]:
    """fuzz_sixpt mode 1: the rays of well-posed 6-point problems (6 cameras
    within 1 m, every other pair cross-camera, points 2..8 m away, rotations
    up to ~30 degrees) as nice doubles, i.e. rounded to 1/4096 like a noisy
    sample; each of the four arrays with fz_matrix layout 0 (as decoded)."""
    out = []
    for _ in range(6):
        w = [rng.uniform(-0.3, 0.3) for _ in range(3)]
        t = [rng.uniform(-2.0, 2.0) for _ in range(3)]
        R = _rodrigues(w)
        cams = [[rng.uniform(-1, 1) for _ in range(3)] for _ in range(6)]
        o1, d1, o2, d2 = [], [], [], []
        for i in range(6):
            c1, c2 = cams[i], cams[(i + (i & 1)) % 6]
            X = [c1[j] + rng.uniform(2.0, 8.0) * rng.choice((-1, 1)) * (j == i % 3)
                 + rng.uniform(-1, 1) for j in range(3)]
            X2 = [sum(R[a][b] * X[b] for b in range(3)) + t[a] for a in range(3)]
            o1 += c1
            d1 += [X[j] - c1[j] for j in range(3)]
            o2 += c2
            d2 += [X2[j] - c2[j] for j in range(3)]
        out.append(bytes([1]) + b"".join(bytes([0]) + b"".join(nice(v) for v in a)
                                         for a in (o1, d1, o2, d2)))
    return out


def seeds_for(name: str) -> list[bytes]:
    rng = random.Random(f"mcgeom-{name}")
    if name == "fuzz_essential5":
        return c_seeds(name, rng) + essential5_seeds(rng)
    if name == "fuzz_sixpt":
        return c_seeds(name, rng) + sixpt_seeds(rng)
    if name in MODES:
        return c_seeds(name, rng)
    if name == "fuzz_calibration":
        return calibration_seeds()
    return random_seeds(rng)


def main(argv: list[str]) -> int:
    known = set(MODES) | {p.stem for p in (FUZZ / "python").glob("fuzz_*.py")}
    for name in argv or sorted(known):
        if name not in known:
            print(f"make_corpus: no seeds defined for {name}", file=sys.stderr)
            return 2
        d = SEEDS / name
        d.mkdir(parents=True, exist_ok=True)
        for old in d.iterdir():
            old.unlink()
        for k, s in enumerate(seeds_for(name)):
            (d / f"seed-{k:03d}").write_bytes(s)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
