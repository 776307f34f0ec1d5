"""The multi-view translation solver of thesis ch. 6 (mcgeom.multiview): the C
relation rows and Grams against numpy, the structured solver against the dense
numpy implementation of the same math, exact recovery of noise-free centres
(all four variants), invariance to permuting views and tracks, connectivity,
metric centres of rigs and the critical case, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from mcgeom import _core, multiview, synth
from mcgeom.experiments.bench.known_rotation_numpy import dense_rows, dense_solve
from mcgeom.synth_views import circle_sequence

VARIANTS = [(r, s) for r in multiview.RELATIONS for s in multiview.SOLVERS]
SETTINGS = settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
seeds = st.integers(min_value=0, max_value=2**31 - 1)


def random_views(seed, m=6, n_points=80, sigma=0.0, cameras=None):
    """m views with random centres and rotations, points seen in random runs
    of 2-3 views (tracks), as (track, view, bearings, rotations, centres, origins)."""
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(m, 3)) * 2.0
    rotations = np.array([synth.random_rotation(rng) for _ in range(m)])
    track, view, obs_pts = [], [], []
    points = rng.normal(size=(n_points, 3)) * 4.0 + np.array([0, 0, 8.0])
    for p in range(n_points):
        for tr in range(2):
            vs = np.sort(rng.choice(m, size=int(rng.integers(2, 4)), replace=False))
            track += [2 * p + tr] * len(vs)
            view += list(vs)
            obs_pts += [p] * len(vs)
    track, view, obs_pts = np.array(track), np.array(view), np.array(obs_pts)
    origins = None
    off = np.zeros((len(view), 3))
    if cameras is not None:
        origins = cameras[rng.integers(0, len(cameras), len(view))]
        off = np.einsum("kji,kj->ki", rotations[view], origins)
    b = np.einsum("kij,kj->ki", rotations[view], points[obs_pts] - centres[view] - off)
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    if sigma:
        b = synth.perturb_directions(b, sigma, rng)
    return track, view, b, rotations, centres, origins


def gauge(c, ref=0):
    """Centres with view ``ref`` at the origin and sum |c|^2 = 1."""
    c = c - c[ref]
    return c / np.sqrt(np.sum(c ** 2))


# ------------------------------------------------------------ C vs numpy

def test_bilinear_rows_match_numpy():
    rng = np.random.default_rng(0)
    x1, x2, w1, w2 = (rng.normal(size=(50, 3)) for _ in range(4))
    rows = _core.bilinear_rows(x1, x2, w1, w2)
    u = np.cross(x1, x2)
    np.testing.assert_allclose(rows[:, :3], -u, atol=1e-14)
    np.testing.assert_allclose(rows[:, 3:6], u, atol=1e-14)
    np.testing.assert_allclose(rows[:, 6], np.einsum("ij,ij->i", u, w2 - w1), atol=1e-13)
    np.testing.assert_allclose(_core.bilinear_rows(x1, x2)[:, 6], 0.0)


def test_trilinear_rows_match_numpy():
    """Each row is M_st(a, b) of eq. 6.11, evaluated by numpy at random a, b."""
    rng = np.random.default_rng(1)
    x1, x2, x3, w1, w2, w3 = (rng.normal(size=(40, 3)) for _ in range(6))
    a, b = rng.normal(size=3), rng.normal(size=3)
    rows = _core.trilinear_rows(x1, x2, x3, w1, w2, w3)
    A, B = a + w2 - w1, b + w3 - w1
    M = (np.einsum("ks,kt->kst", np.cross(x1, x2), np.cross(x3, B))
         - np.einsum("ks,kt->kst", np.cross(x2, A), np.cross(x1, x3))).reshape(-1, 9)
    got = rows[:, :, :3] @ a + rows[:, :, 3:6] @ b + rows[:, :, 6]
    np.testing.assert_allclose(got, M, atol=1e-12)


@pytest.mark.parametrize("q", [2, 3])
def test_grams_match_dense_rows(q):
    """Block Grams scattered = E^T E of the dense numpy rows (central views)."""
    track, view, b, rot, c, _ = random_views(3, m=5)
    x = np.einsum("kji,kj->ki", rot[view], b)
    idx = multiview.relations(track, view, q, "all", 1)
    keys, block = np.unique(view[idx], axis=0, return_inverse=True)
    block = block.reshape(-1)
    grams = _core.relation_grams(x[idx], None, block, len(keys))
    E, _ = dense_rows(x[idx], view[idx], 5)
    dense = np.zeros((15, 15))
    for kb, key in enumerate(keys):
        cols = (3 * key[:, None] + np.arange(3)).reshape(-1)
        dense[np.ix_(cols, cols)] += grams[kb, :3 * q, :3 * q]
    np.testing.assert_allclose(dense, E.T @ E, atol=1e-10 * np.abs(dense).max())


@pytest.mark.parametrize("relation,solver", VARIANTS)
def test_structured_solver_matches_dense_numpy(relation, solver):
    track, view, b, rot, c, _ = random_views(5, m=7, sigma=1e-3)
    r = multiview.translations_from_tracks(track, view, b, rot, relation=relation, solver=solver)
    x = np.einsum("kji,kj->ki", rot[view], b)
    idx = multiview.relations(track, view, 2 if relation == "bilinear" else 3, "all", 1)
    ref = dense_solve(x[idx], view[idx], 7, solver)
    ref *= np.sign(np.sum(ref * r.centres))
    assert r.converged
    np.testing.assert_allclose(r.centres, ref, atol=1e-8)


# ------------------------------------------------------------ properties

@pytest.mark.parametrize("relation,solver", VARIANTS)
@SETTINGS
@given(seed=seeds, m=st.integers(min_value=3, max_value=9))
def test_noise_free_recovers_centres(relation, solver, seed, m):
    track, view, b, rot, c, _ = random_views(seed, m=m)
    r = multiview.translations_from_tracks(track, view, b, rot, relation=relation, solver=solver)
    assert r.unconnected_views == () and r.connected.all()
    assert np.all(r.centres[0] == 0.0)
    assert abs(np.sum(r.centres ** 2) - 1.0) < 1e-12
    assert np.abs(r.centres - gauge(c)).max() < 1e-7   # sign from cheirality too
    assert not r.scale.observable


@pytest.mark.parametrize("relation,solver", VARIANTS)
@SETTINGS
@given(seed=seeds)
def test_permuting_views_and_tracks_changes_nothing(relation, solver, seed):
    """Constrained: any view permutation (re-gauged). Plain SVD: its gauge view
    matters under noise, so view 0 stays first there."""
    rng = np.random.default_rng(seed)
    m = 7
    track, view, b, rot, c, _ = random_views(seed, m=m, sigma=1e-3)
    sigma_v = rng.permutation(m)
    if solver == "svd":
        sigma_v = np.r_[0, 1 + rng.permutation(m - 1)]
    inv = np.argsort(sigma_v)
    order = rng.permutation(len(view))
    relabel = rng.permutation(track.max() + 1)
    a = multiview.translations_from_tracks(track, view, b, rot, relation=relation, solver=solver)
    bres = multiview.translations_from_tracks(relabel[track[order]], sigma_v[view[order]],
                                              b[order], rot[inv], relation=relation,
                                              solver=solver)
    back = bres.centres[sigma_v]          # back[i] = centre of old view i
    assert np.abs(gauge(back) - a.centres).max() < 1e-7


def test_unconnected_views_are_reported():
    track, view, b, rot, c, _ = random_views(11, m=5)
    rot = np.concatenate([rot, [np.eye(3)] * 3])     # views 5, 6, 7
    # views 6 and 7 see one track together: a component of their own
    track = np.r_[track, 10**6, 10**6]
    view = np.r_[view, 6, 7]
    b = np.vstack([b, [[0, 0, 1.0], [0, 0.1, 1.0]]])
    r = multiview.translations_from_tracks(track, view, b, rot)
    assert r.unconnected_views == (5, 6, 7)
    assert np.isnan(r.centres[5:]).all() and np.isfinite(r.centres[:5]).all()
    assert r.components[0] == (0, 1, 2, 3, 4) and (6, 7) in r.components and (5,) in r.components
    assert np.abs(r.centres[:5] - gauge(c)).max() < 1e-7


def test_window_uses_only_near_views():
    seq = circle_sequence(n_views=30, n_points=600, rng=2)
    full = multiview.translations_from_tracks(seq.track, seq.view, seq.bearings, seq.rotations,
                                              relation="bilinear")
    win = multiview.translations_from_tracks(seq.track, seq.view, seq.bearings, seq.rotations,
                                             relation="bilinear", pairs="window", window=1)
    assert win.n_relations < full.n_relations
    true = gauge(seq.centres)
    assert np.abs(full.centres - true).max() < 1e-6
    # consecutive pairs alone leave the relative scales of the steps free
    assert win.rigidity < 1e-8 * full.rigidity or win.eigen_ratio > 0.5 or \
        np.abs(win.centres - true).max() > 1e-3


@SETTINGS
@given(seed=seeds, relation=st.sampled_from(multiview.RELATIONS))
def test_rig_views_give_metric_centres(seed, relation):
    cams = np.array([[0.3, 0, 0], [-0.3, 0, 0], [0, 0.3, 0.1]])
    track, view, b, rot, c, org = random_views(seed, m=5, cameras=cams)
    r = multiview.translations_from_tracks(track, view, b, rot, origins=org, relation=relation)
    assert r.scale.observable
    assert np.abs(r.centres - (c - c[0])).max() < 1e-7 * np.abs(c).max()


def test_rig_pure_translation_intra_camera_is_critical():
    """Same rotation everywhere and each track in one camera: the offsets cancel
    (ch. 7.3.2), only the unit-normalised centres come back."""
    rng = np.random.default_rng(4)
    cams = np.array([[0.3, 0, 0], [-0.3, 0, 0]])
    m, Rc = 5, synth.random_rotation(rng)
    centres = np.cumsum(rng.normal(size=(m, 3)), axis=0)
    track, view, bear, org = [], [], [], []
    for p in range(150):
        X = rng.normal(size=3) * 4 + [0, 0, 8]
        k = p % 2
        for v in np.sort(rng.choice(m, 3, replace=False)):
            track.append(p)
            view.append(v)
            org.append(cams[k])
            bear.append(Rc @ (X - centres[v]) - cams[k])
    r = multiview.translations_from_tracks(np.array(track), np.array(view), np.array(bear),
                                           np.array([Rc] * m), origins=np.array(org))
    assert not r.scale.observable and "critical" in r.scale.reason
    assert np.abs(r.centres - gauge(centres)).max() < 1e-7


@pytest.mark.parametrize("kwargs,match", [
    ({"relation": "quadrilinear"}, "relation"), ({"solver": "qr"}, "solver"),
    ({"pairs": "some"}, "pairs"), ({"relation": "trilinear", "pairs": "window", "window": 1},
                                   "window"),
    ({"rotation_std": -1e-4}, "rotation_std"), ({"rotation_std": float("nan")}, "rotation_std"),
    ({"rotation_std": 1e-4, "refine": False}, "rotation_std needs the bundle adjustment"),
])
def test_bad_options(kwargs, match):
    track, view, b, rot, c, _ = random_views(0, m=4)
    with pytest.raises(ValueError, match=match):
        multiview.translations_from_tracks(track, view, b, rot, **kwargs)


def test_bad_input_is_named():
    track, view, b, rot, c, _ = random_views(0, m=4)
    bad = b.copy()
    bad[3] = np.nan
    with pytest.raises(ValueError, match="bearings"):
        multiview.translations_from_tracks(track, view, bad, rot)
    with pytest.raises(ValueError, match="view ids"):
        multiview.translations_from_tracks(track, view + 10, b, rot)
    r2 = rot.copy()
    r2[1] *= 2
    with pytest.raises(ValueError, match=r"rotations\[1\]"):
        multiview.translations_from_tracks(track, view, b, r2)
    with pytest.raises(ValueError, match="no bilinear relation"):
        multiview.translations_from_tracks(np.arange(len(view)), view, b, rot)


def test_long_tracks_are_refused_not_enumerated(monkeypatch):
    monkeypatch.setattr(multiview, "MAX_RELATIONS", 1000)
    m = 30
    rot = np.array([np.eye(3)] * m)
    b = np.random.default_rng(0).normal(size=(m, 3))
    with pytest.raises(ValueError, match="combinations"):
        multiview.translations_from_tracks(np.zeros(m, int), np.arange(m), b, rot,
                                           relation="trilinear")


def test_relation_grams_rejects_bad_block_indices():
    x = np.random.default_rng(0).normal(size=(4, 2, 3))
    with pytest.raises(ValueError, match="block"):
        _core.relation_grams(x, None, np.array([0, 1, 2, 3.0]), 4)
    with pytest.raises(ValueError, match="block"):
        _core.relation_grams(x, None, np.array([0, 1, 2, 4]), 4)


@pytest.mark.parametrize("q", [2, 3])
def test_relation_grams_in_chunks_equal_one_call(q, monkeypatch):
    """More relations than the kernel takes in a call (2^20: a real sequence
    with long tracks gives more trilinear ones) are added up chunk by chunk."""
    rng = np.random.default_rng(q)
    x = rng.normal(size=(50, q, 3))
    w = rng.normal(size=(50, q, 3))
    block = rng.integers(0, 6, size=50)
    whole = _core.relation_grams(x, w, block, 6)
    monkeypatch.setattr(_core, "RELATION_CHUNK", 7)
    chunked = _core.relation_grams(x, w, block, 6)
    assert np.allclose(chunked, whole, rtol=1e-13, atol=1e-13 * np.abs(whole).max())


@pytest.mark.parametrize("q", [2, 3])
def test_grams_with_offsets_are_sums_of_explicit_row_outer_products(q):
    """Each block Gram, constant column included, against sum r r^T of the
    explicit rows of mcg_bilinear_rows / mcg_trilinear_rows (themselves checked
    against numpy above): the trilinear Gram is summed in closed form, not
    from the 27 rows, so this pins the closed form down."""
    rng = np.random.default_rng(10 + q)
    n, nb = 40, 5
    x = rng.normal(size=(n, q, 3))
    w = rng.normal(size=(n, q, 3))
    block = rng.integers(0, nb, size=n)
    grams = _core.relation_grams(x, w, block, nb)
    d = 3 * q + 1
    ref = np.zeros((nb, d, d))
    if q == 2:
        rows = _core.bilinear_rows(x[:, 0], x[:, 1], w[:, 0], w[:, 1])
        np.add.at(ref, block, rows[:, :, None] * rows[:, None, :])
    else:
        for r0 in range(3):
            o1, o2 = (r0 + 1) % 3, (r0 + 2) % 3
            r9 = _core.trilinear_rows(x[:, r0], x[:, o1], x[:, o2],
                                      w[:, r0], w[:, o1], w[:, o2])     # (n, 9, 7)
            full = np.zeros((n, 9, 10))
            full[:, :, 3 * r0:3 * r0 + 3] = -(r9[:, :, 0:3] + r9[:, :, 3:6])
            full[:, :, 3 * o1:3 * o1 + 3] = r9[:, :, 0:3]
            full[:, :, 3 * o2:3 * o2 + 3] = r9[:, :, 3:6]
            full[:, :, 9] = r9[:, :, 6]
            np.add.at(ref, block, np.einsum("kea,keb->kab", full, full))
    np.testing.assert_allclose(grams, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())
    assert np.array_equal(grams, np.transpose(grams, (0, 2, 1)))


@pytest.mark.parametrize("q", [2, 3])
def test_blocks_coded_sort_equals_unique_rows(q):
    """The 1-D coded sort of the view tuples gives np.unique's rows and inverse,
    also on the record-sort fallback for view counts whose code would overflow."""
    rng = np.random.default_rng(q)
    for m in (7, 3_000_000):
        v = np.sort(rng.choice(m, size=(500, q)), axis=1)
        keys, block = multiview._blocks(v, m)
        ref, inv = np.unique(v, axis=0, return_inverse=True)
        assert np.array_equal(keys, ref)
        assert np.array_equal(block, inv.reshape(-1))
        assert np.array_equal(keys[block], v)
