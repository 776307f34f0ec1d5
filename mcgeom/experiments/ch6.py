"""Thesis ch. 6.5.1 (Figs. 6.3-6.6): 101 views on a circle of radius 100 in a
plane, known rotations, 1,000 uniform random points, each view sees the points
within a limited range (50 units), tracks of at most three views along the
image sequence (no track links the last view to the first: an open chain,
``--closed-loop`` to close it); angular noise sigma on the unit sphere. For
each variant (bilinear / trilinear x plain SVD / constrained) and sigma: the
RMS centre error after a similarity alignment (units of the scene, circle
radius 100), the spiral measure (largest angle between an estimated and the
true step, degrees), the number of reversed steps (> 90 deg: folds), where the
worst step is and how many tracks link it, medians over trials, and one PNG
per sigma with the four aligned trajectories (top view). Then, per relation
and sigma, how often the constrained variant beats the plain one in the same
trial (paired: same sequence, same noise) on RMS and on the spiral measure,
with the one-sided sign-test p-value of that count.

``--pairwise-reference`` also runs an estimator that is not one of the
thesis's variants, to show how far the bilinear data themselves go: each view
pair's baseline direction on its own (smallest eigenvector of the pair's
epipolar rows, eq. 6.13), then the centres that best fit those directions
(min sum |(I - d d^T)(c_j - c_i)|^2 subject to sum |c_j - c_i|^2 = 1).

    mcgeom experiment ch6 [--trials 10] [--out ch6_out] [--range 50] [--closed-loop]
                          [--tracks consecutive|any] [--noise-metric]
                          [--pairwise-reference]
"""

from __future__ import annotations

import argparse
import itertools
import math
from pathlib import Path

import numpy as np

from mcgeom import multiview
from mcgeom.synth_views import circle_sequence, similarity_align, spiral_measure

from .common import Progress, no_progress, non_negative_int, positive_float, positive_int

SIGMAS = (1e-7, 1.2e-5, 1e-4, 5e-4, 1e-3, 1e-2)
VARIANTS = [(r, s) for r in multiview.RELATIONS for s in multiview.SOLVERS]
COLOURS = {("bilinear", "svd"): (0, 140, 255), ("bilinear", "constrained"): (0, 160, 0),
           ("trilinear", "svd"): (200, 0, 200), ("trilinear", "constrained"): (200, 120, 0)}


def step_links(track: np.ndarray, view: np.ndarray, m: int) -> np.ndarray:
    """(m - 1,) number of tracks that observe both view i and view i + 1."""
    key = np.unique(np.c_[track, view], axis=0)          # sorted by track, then view
    same = (key[1:, 0] == key[:-1, 0]) & (key[1:, 1] == key[:-1, 1] + 1)
    return np.bincount(key[:-1, 1][same], minlength=m - 1)[:m - 1]


def step_angles(aligned: np.ndarray, true: np.ndarray) -> np.ndarray:
    """Angle (radians) between each estimated step c_{i+1} - c_i and the true one."""
    a, t = np.diff(aligned, axis=0), np.diff(true, axis=0)
    return np.arctan2(np.linalg.norm(np.cross(a, t), axis=1), np.einsum("ij,ij->i", a, t))


def run(trials: int = 10, sigmas=SIGMAS, n_views: int = 101, n_points: int = 1000,
        seed: int = 0, visible_range: float = 50.0, closed_loop: bool = False,
        track_views: str = "consecutive", progress: Progress = no_progress) -> dict:
    """{(relation, solver, sigma): dict(rms=[...], spiral=[...], folds=[...],
    worst=[...], worst_links=[...], links=[...], seconds=[...], rigidity=[...])}
    plus the aligned trajectories of the first trial under key "paths".
    rms: centre error after a similarity (units of the scene, circle radius
    100); spiral: radians; seconds: solver time. ``progress`` wraps the loop
    over (sigma, trial)."""
    out, paths = {}, {}
    # one flat loop (same order as sigma-major nested loops) so that one bar covers it
    for sigma, trial in progress(itertools.product(sigmas, range(trials)),
                                 total=len(sigmas) * trials, desc="ch6"):
        seq = circle_sequence(n_views=n_views, n_points=n_points, sigma=sigma,
                              rng=seed + 1000 * trial, visible_range=visible_range,
                              closed_loop=closed_loop, track_views=track_views)
        links = step_links(seq.track, seq.view, n_views)
        for rel, sol in VARIANTS:
            r = multiview.translations_from_tracks(seq.track, seq.view, seq.bearings,
                                                   seq.rotations, relation=rel, solver=sol)
            ok = r.connected
            aligned, rms = similarity_align(r.centres[ok], seq.centres[ok])
            ang = step_angles(aligned, seq.centres[ok])
            worst = int(np.flatnonzero(ok)[np.argmax(ang)])
            rec = out.setdefault((rel, sol, sigma), {k: [] for k in (
                "rms", "spiral", "folds", "worst", "worst_links", "links", "seconds",
                "rigidity")})
            rec["rms"].append(rms)
            rec["spiral"].append(spiral_measure(aligned, seq.centres[ok]))
            rec["folds"].append(int(np.count_nonzero(ang > np.pi / 2)))
            rec["worst"].append(worst)
            rec["worst_links"].append(int(links[min(worst, n_views - 2)]))
            rec["links"].append(float(np.median(links)))
            rec["seconds"].append(r.timing["total"])
            rec["rigidity"].append(r.rigidity)
            if trial == 0:
                paths[(rel, sol, sigma)] = aligned
                paths[("truth", sigma)] = seq.centres[ok]
    out["paths"] = paths
    return out


def paired_wins(res: dict, relation: str, sigma: float, metric: str) -> tuple[int, int, float]:
    """(wins, trials, p): in how many trials the constrained variant's
    ``metric`` ("rms" or "spiral") is below the plain SVD's on the same data,
    and the one-sided sign-test p-value of at least that many wins if neither
    variant were better (a tie is no win: conservative)."""
    con = np.asarray(res[(relation, "constrained", sigma)][metric])
    svd = np.asarray(res[(relation, "svd", sigma)][metric])
    n = len(con)
    wins = int(np.count_nonzero(con < svd))
    p = sum(math.comb(n, k) for k in range(wins, n + 1)) / 2.0 ** n
    return wins, n, float(p)


def pairwise_direction_centres(seq) -> np.ndarray:
    """(m, 3) centres (view 0 at the origin, sum |c_j - c_i|^2 = 1 over the
    linked pairs) from each view pair's baseline direction estimated on its
    own: not a thesis variant, a reference for what the bilinear data of the
    sequence fix. Dense (3m unknowns): for experiments only."""
    m = len(seq.rotations)
    x = np.einsum("kji,kj->ki", seq.rotations[seq.view], seq.bearings)
    idx = multiview.relations(seq.track, seq.view, 2, "all", 1)
    keys, block = np.unique(seq.view[idx], axis=0, return_inverse=True)
    rows = np.cross(x[idx[:, 0]], x[idx[:, 1]])       # eq. 6.5 rows in c_j - c_i
    gram = np.zeros((len(keys), 3, 3))
    np.add.at(gram, block.reshape(-1), rows[:, :, None] * rows[:, None, :])
    d = np.linalg.eigh(gram)[1][:, :, 0]              # each pair's baseline direction
    H, B = np.zeros((3 * m, 3 * m)), np.zeros((3 * m, 3 * m))
    for (i, j), dd in zip(keys, d):
        P = np.eye(3) - np.outer(dd, dd)
        for a, b, sgn in ((i, i, 1.0), (j, j, 1.0), (i, j, -1.0), (j, i, -1.0)):
            H[3 * a:3 * a + 3, 3 * b:3 * b + 3] += sgn * P
            B[3 * a:3 * a + 3, 3 * b:3 * b + 3] += sgn * np.eye(3)
    Ci = np.linalg.inv(np.linalg.cholesky(B[3:, 3:]))  # gauge c_0 = 0
    vec = np.linalg.eigh(Ci @ H[3:, 3:] @ Ci.T)[1][:, 0]
    return np.r_[np.zeros(3), Ci.T @ vec].reshape(-1, 3)


def pairwise_reference(trials: int = 10, sigmas=SIGMAS, seed: int = 0,
                       visible_range: float = 50.0, closed_loop: bool = False,
                       track_views: str = "consecutive",
                       progress: Progress = no_progress) -> dict:
    """{sigma: dict(rms=[...], spiral=[...])} of ``pairwise_direction_centres``
    on the sequences of ``run`` (same seeds)."""
    out = {}
    for sigma, trial in progress(itertools.product(sigmas, range(trials)),
                                 total=len(sigmas) * trials, desc="pairwise reference"):
        rec = out.setdefault(sigma, {"rms": [], "spiral": []})
        seq = circle_sequence(sigma=sigma, rng=seed + 1000 * trial,
                              visible_range=visible_range, closed_loop=closed_loop,
                              track_views=track_views)
        aligned, rms = similarity_align(pairwise_direction_centres(seq), seq.centres)
        rec["rms"].append(rms)
        rec["spiral"].append(spiral_measure(aligned, seq.centres))
    return out


def noise_metric_spread(relation: str, sigma: float = 1e-3, draws: int = 20, seed: int = 0,
                        visible_range: float = 50.0) -> dict:
    """How well each solver's normalisation matches the noise: the expected
    noise part D = E[dE^T dE] of E^T E (dense rows, ``draws`` noise draws on
    one noise-free sequence, gauge c_0 = 0) against L = G^T G (constrained)
    and I (plain). Returns the spread max/min of the generalized eigenvalues
    of (D, L) and of (D, I): 1 would mean the noise adds the same cost to
    every configuration of unit norm, i.e. no bias."""
    from mcgeom import synth
    from .bench.known_rotation_numpy import dense_rows
    seq = circle_sequence(sigma=0.0, rng=seed, visible_range=visible_range)
    q = 2 if relation == "bilinear" else 3
    idx = multiview.relations(seq.track, seq.view, q, "all", 1)
    m = len(seq.rotations)

    def rows(b):
        x = np.einsum("kji,kj->ki", seq.rotations[seq.view], b)
        return dense_rows(x[idx], seq.view[idx], m)

    E0, L = rows(seq.bearings)
    D = np.zeros_like(L)
    for k in range(draws):
        dE = rows(synth.perturb_directions(seq.bearings, sigma, seed + 1 + k))[0] - E0
        D += dE.T @ dE / draws
    D, L = D[3:, 3:], L[3:, 3:]
    Ci = np.linalg.inv(np.linalg.cholesky(L))
    wl, wi = np.linalg.eigvalsh(Ci @ D @ Ci.T), np.linalg.eigvalsh(D)
    return {"constrained": float(wl[-1] / wl[0]), "svd": float(wi[-1] / wi[0])}


def _poses(c):
    T = np.tile(np.eye(4), (len(c), 1, 1))
    T[:, :3, 3] = c
    return list(T)


def write_pngs(res: dict, outdir: Path, sigmas=SIGMAS) -> list:
    from mcgeom.report import plot_trajectories_png
    outdir.mkdir(parents=True, exist_ok=True)
    files = []
    for sigma in sigmas:
        curves = {"truth": (_poses(res["paths"][("truth", sigma)]), (0, 0, 0))}
        for rel, sol in VARIANTS:
            curves[f"{rel} + {sol}"] = (_poses(res["paths"][(rel, sol, sigma)]), COLOURS[(rel, sol)])
        f = outdir / f"ch6_sigma_{sigma:.1e}.png"
        plot_trajectories_png(f, curves, title=f"sigma = {sigma:.1e} rad, aligned (similarity)")
        files.append(f)
    return files


def add_arguments(ap: argparse.ArgumentParser) -> None:
    """The options of ``mcgeom experiment ch6``."""
    ap.add_argument("--trials", type=positive_int, default=10, help="trials per noise level")
    ap.add_argument("--out", default="ch6_out", help="directory of the PNGs")
    ap.add_argument("--seed", type=non_negative_int, default=0, help="random seed")
    ap.add_argument("--range", type=positive_float, default=50.0,
                    help="visible range of a view (units of the scene, circle radius 100)")
    ap.add_argument("--closed-loop", action="store_true",
                    help="tracks also link the last view to the first (a ring)")
    ap.add_argument("--tracks", choices=("consecutive", "any"), default="consecutive",
                    help="a track's <= 3 views: consecutive along the sequence, or "
                         "drawn among all views that see the point (wide triangles: rigid, "
                         "no spirals for either solver)")
    ap.add_argument("--noise-metric", action="store_true",
                    help="also print how far the noise part of E^T E is from each "
                         "solver's normalisation (dense, a few seconds)")
    ap.add_argument("--pairwise-reference", action="store_true",
                    help="also run pairwise directions + centres, a reference for how far "
                         "the bilinear data go (dense, about a second per trial)")


def run_cli(args: argparse.Namespace, progress: Progress = no_progress) -> int:
    """Run the experiment with parsed options; print the tables, write the PNGs."""
    res = run(args.trials, seed=args.seed, visible_range=args.range,
              closed_loop=args.closed_loop, track_views=args.tracks, progress=progress)
    print(f"thesis ch. 6.5.1: 101 views, circle radius 100, 1000 points, range {args.range:g}, "
          f"tracks <= 3 {args.tracks} views, {'closed loop' if args.closed_loop else 'open sequence'}; "
          f"medians over {args.trials} trials; folds = steps reversed by > 90 deg; worst = "
          "view of the worst step (tracks linking it / median per step); rigidity = second "
          "smallest relative eigenvalue of the solver's pencil (near 0: scales of parts free)")
    print(f"{'sigma':>8} {'variant':>24} {'rms err':>10} {'spiral[deg]':>12} {'folds':>6} "
          f"{'worst (links)':>15} {'rigidity':>9} {'ms':>6}")
    for sigma in SIGMAS:
        for rel, sol in VARIANTS:
            r = res[(rel, sol, sigma)]
            where = (f"{int(np.median(r['worst'])):3d} ({np.median(r['worst_links']):2.0f}/"
                     f"{np.median(r['links']):2.0f})")
            print(f"{sigma:8.1e} {rel + ' + ' + sol:>24} {np.median(r['rms']):10.4g} "
                  f"{np.degrees(np.median(r['spiral'])):12.4g} {np.median(r['folds']):6.0f} "
                  f"{where:>15} {np.median(r['rigidity']):9.2e} "
                  f"{1000 * np.median(r['seconds']):6.1f}")
    print("constrained / plain SVD, median RMS error (< 1 = constrained better):")
    for sigma in SIGMAS:
        ratios = [np.median(res[(rel, 'constrained', sigma)]["rms"]) /
                  np.median(res[(rel, 'svd', sigma)]["rms"]) for rel in multiview.RELATIONS]
        print(f"{sigma:8.1e}  bilinear {ratios[0]:7.3f}  trilinear {ratios[1]:7.3f}")
    print("paired: trials in which constrained beats plain SVD on the same data "
          "(one-sided sign-test p):")
    for rel in multiview.RELATIONS:
        for sigma in SIGMAS:
            cells = []
            for metric in ("rms", "spiral"):
                w, n, p = paired_wins(res, rel, sigma, metric)
                cells.append(f"{metric} {w:3d}/{n:<3d} p {p:8.2g}")
            print(f"  {rel:9s} {sigma:8.1e}  " + "   ".join(cells))
    if args.pairwise_reference:
        ref = pairwise_reference(args.trials, seed=args.seed, visible_range=args.range,
                                 closed_loop=args.closed_loop, track_views=args.tracks,
                                 progress=progress)
        print("reference, not a thesis variant: pairwise baseline directions, then centres "
              "(median RMS / spiral[deg]):")
        for sigma in SIGMAS:
            print(f"  {sigma:8.1e}  {np.median(ref[sigma]['rms']):10.4g} "
                  f"{np.degrees(np.median(ref[sigma]['spiral'])):10.4g}")
    if args.noise_metric:
        print("spread max/min of the expected noise part of E^T E against each solver's "
              "normalisation (sigma 1e-3; 1 = unbiased):")
        for rel in multiview.RELATIONS:
            sp = noise_metric_spread(rel, visible_range=args.range)
            print(f"  {rel:9s} constrained (|Gc|^2) {sp['constrained']:8.3g}   "
                  f"plain (|c|^2) {sp['svd']:8.3g}")
    files = write_pngs(res, Path(args.out))
    print("wrote " + ", ".join(str(f) for f in files))
    return 0

