"""radarnode.dsp.subspace's fast paths (issue 11 item 7) against the computations they replaced: the fused
covariance against sample covariance → smoothing → FB, the cached trigonometric tables against the steering
vectors' quadratic form, LAPACK's partial eigenvectors against numpy's ``eigh``, root-MUSIC's real Cayley
polynomial against ``np.roots`` and TLS-ESPRIT's Gram-matrix eigenvectors against the SVD."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radarnode.dsp import subspace as ss

pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")


def snapshots(rng, u, snr_db, k, n=12, d=0.5):
    u = np.atleast_1d(np.asarray(u, dtype=float))
    a = ss.steering(n, u, d)
    s = (rng.standard_normal((u.size, k)) + 1j * rng.standard_normal((u.size, k))) / math.sqrt(2.0)
    w = (rng.standard_normal((n, k)) + 1j * rng.standard_normal((n, k))) / math.sqrt(2.0)
    return a @ (10.0 ** (snr_db / 20.0) * s) + w


def random_cases(seed, count, n_choices=(12, 8, 11, 5)):
    """(covariance, n_sources, d): random arrays, sources (some near end-fire), SNR, snapshots, smoothing, FB;
    only well-posed ones (a gap between the M-th and (M+1)-th eigenvalue, M < Q − 1 with FB)."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        n = int(rng.choice(n_choices))
        d = float(rng.choice([0.5, 0.5, 0.4]))
        m_true = int(rng.integers(1, 4))
        u = rng.uniform(-1.0, 1.0, m_true)
        x = snapshots(rng, u, rng.uniform(-5.0, 40.0), int(rng.choice([1, 4, 16, 64])), n=n, d=d)
        q = int(rng.choice([n, ss.default_subarray(n)]))
        fb = bool(rng.integers(2))
        r = ss._covariance(x, q, fb)
        m = int(rng.integers(1, min(4, q)))
        lam = np.linalg.eigvalsh(r)[::-1]
        if (lam[m - 1] - lam[m]) < 1e-6 * lam[0] or (fb and m == q - 1):
            continue
        out.append((r, m, d))
    return out


def reference_subspace(r, m):
    _, v = np.linalg.eigh(0.5 * (r + np.conj(r.T)))
    return v[:, r.shape[0] - m:]


def reference_root_music(r, m, d):
    """The former root-MUSIC: np.roots of the diagonal sums of En·Enᴴ, the m roots inside closest to the circle."""
    n = r.shape[0]
    _, v = np.linalg.eigh(0.5 * (r + np.conj(r.T)))
    en = v[:, : n - m]
    c = en @ np.conj(en.T)
    coef = np.array([np.trace(c, offset=o) for o in range(-(n - 1), n)])
    roots = np.roots(coef[::-1])
    inside = roots[np.abs(roots) <= 1.0]
    cand = inside if inside.size >= m else roots
    z = cand[np.argsort(np.abs(1.0 - np.abs(cand)))[:m]]
    return np.sort(ss._wrap(np.angle(z) / (2.0 * np.pi * d), d))


def reference_esprit(r, m, d):
    """The former TLS-ESPRIT: SVD of [Es₁ Es₂], Ψ = −V₁₂ V₂₂⁺."""
    es = reference_subspace(r, m)
    _, _, vh = np.linalg.svd(np.concatenate((es[:-1], es[1:]), axis=1), full_matrices=True)
    vv = np.conj(vh.T)
    psi = -vv[:m, m:] @ np.linalg.pinv(vv[m:, m:])
    return np.sort(ss._wrap(np.angle(np.linalg.eigvals(psi)) / (2.0 * np.pi * d), d))


def circular_distance(a, b, d):
    diff = np.abs(a - b)
    return np.minimum(diff, np.abs(diff - 2.0)) if ss._periodic(d) else diff


@pytest.mark.parametrize("n, k, q, fb", [(12, 1, 8, True), (12, 16, 12, False), (12, 16, 12, True),
                                         (12, 5, 8, False), (7, 3, 5, True), (2, 1, 2, True)])
def test_fused_covariance_equals_the_three_steps(n, k, q, fb):
    rng = np.random.default_rng(n * 100 + k)
    x = rng.standard_normal((n, k)) + 1j * rng.standard_normal((n, k))
    want = ss.spatial_smoothing(ss.sample_covariance(x), q)
    if fb:
        want = ss.forward_backward(want)
    got = ss._covariance(x, q, fb)
    assert got.shape == (q, q)
    assert np.max(np.abs(got - want)) < 1e-13 * np.max(np.abs(want))


@pytest.mark.parametrize("n, d, n_grid", [(12, 0.5, 256), (8, 0.5, 256), (5, 0.4, 300), (12, 0.5, 64)])
def test_cached_grid_tables_equal_the_steering_quadratic_form(n, d, n_grid):
    rng = np.random.default_rng(n)
    h = rng.standard_normal((n, n)) + 1j * rng.standard_normal((n, n))
    h = h @ np.conj(h.T)                                          # Hermitian, like es·esᴴ, R or R⁻¹
    s = ss._diag_sums(h)
    grid = ss._grid(n, d, n_grid)

    def quad(u):                                                  # a(u)ᴴ H a(u) from fresh steering vectors
        a = ss.steering(n, u, d).reshape(n, -1)
        return np.einsum("ij,ik,kj->j", np.conj(a), h, a).real.reshape(np.shape(u))

    scale = np.abs(h).sum()
    u = grid.u if not ss._periodic(d) else grid.u[np.arange(-1, n_grid + 1) % n_grid]
    assert np.max(np.abs(grid.coarse @ s - quad(u))) < 1e-13 * scale
    offs = np.linspace(-(grid.u[1] - grid.u[0]), grid.u[1] - grid.u[0], 2 * ss.REFINE_HALF + 1)
    assert np.max(np.abs(grid.fine @ s - quad(grid.u[:, None] + offs))) < 1e-13 * scale
    assert np.array_equal(grid.first, grid.u + offs[0]) and grid.fine_step == offs[1] - offs[0]
    # the null spectrum N − ‖Esᴴa‖² from the noise projector's sums
    es = reference_subspace(h, 2)
    a = ss.steering(n, grid.u, d)
    want = n - np.sum(np.abs(np.conj(es.T) @ a) ** 2, axis=0)
    got = (grid.coarse @ ss._null_sums(es))[1:-1] if ss._periodic(d) else grid.coarse @ ss._null_sums(es)
    assert np.max(np.abs(got - want)) < 1e-12 * n


def test_partial_eigenvectors_span_numpy_eigh_subspace():
    for r, m, _ in random_cases(1, 200):
        n = r.shape[0]
        got = ss._signal_subspace(r, m)
        want = reference_subspace(r, m)
        assert got.shape == (n, m)
        assert np.allclose(np.conj(got.T) @ got, np.eye(m), atol=1e-12)
        assert np.max(np.abs(got @ np.conj(got.T) - want @ np.conj(want.T))) < 1e-8
    real = np.real(r) + np.real(r).T                              # the real symmetric path (unitary MUSIC)
    lam, v = np.linalg.eigh(real)
    got = ss._eigvecs(real, 1, 3)
    assert np.max(np.abs(got @ got.T - v[:, :3] @ v[:, :3].T)) < 1e-10


def test_cayley_roots_are_np_roots():
    worst = 0.0
    for r, m, _ in random_cases(2, 300):
        n = r.shape[0]
        c = ss._null_sums(ss._signal_subspace(r, m))
        tr, ti, w = ss._polynomial_roots(c, n)
        assert w is not None and tr.size == 2 * n - 2
        t = tr + 1j * ti
        z = w * (t - 1j) / (t + 1j)
        want = np.roots(ss._root_music_coef(c, n)[::-1])
        assert want.size == z.size
        # match each reference root with the nearest new one (relative to max(1, |z|))
        err = np.abs(want[:, None] - z[None, :]).min(axis=1) / np.maximum(1.0, np.abs(want))
        worst = max(worst, float(err.max()))
        # |z| ≤ 1 ⟺ Im t ≥ 0
        assert np.all((np.abs(z) <= 1.0 + 1e-12) == (ti >= 0.0))
    assert worst < 1e-9, worst


@pytest.mark.parametrize("name, seed", [("root_music", 3), ("esprit", 5)])
def test_root_music_and_esprit_equal_their_np_roots_and_svd_references(name, seed):
    fast, reference = {"root_music": (ss.root_music, reference_root_music),
                       "esprit": (ss.esprit, reference_esprit)}[name]
    worst = 0.0
    for r, m, d in random_cases(seed, 300):
        got = fast(r, m, d)[0]
        worst = max(worst, float(np.max(circular_distance(got, reference(r, m, d), d))))
    assert worst < 1e-9, worst


def test_root_music_double_roots_agree_to_their_sensitivity():
    # FB with M = Q − 1: one noise eigenvector, conjugate-symmetric, so P = |f|²·… has only double roots (on the
    # circle, or pairs z, 1/z* each twice); rounding splits a double root √eps apart in either solver, so the two
    # agree to about 1e-7 here, not 1e-9 (seen: 2e-7), and both keep one root per double root on the circle
    rng = np.random.default_rng(4)
    worst = 0.0
    for _ in range(50):
        x = snapshots(rng, rng.uniform(-0.9, 0.9, 2), 20.0, 16, n=5)
        r = ss._covariance(x, 4, True)
        got = ss.root_music(r, 3, 0.5)[0]
        worst = max(worst, float(np.max(circular_distance(got, reference_root_music(r, 3, 0.5), 0.5))))
    assert worst < 1e-6, worst


def test_esprit_falls_back_to_the_pseudo_inverse_on_a_singular_block():
    # a subspace whose shifted halves make V₂₂ singular: the pinv path, finite angles
    es = np.zeros((6, 1), dtype=complex)
    es[0, 0] = 1.0                                                # e₂ = 0: [E₁ E₂] = [e₀ 0]
    r = es @ np.conj(es.T) + 1e-3 * np.eye(6)
    u, ok = ss.esprit(r, 1)
    assert np.all(np.isfinite(u)) and u.shape == (1,)


class _FailingLapack:
    """scipy's LAPACK wrappers, with the named ones reporting failure (info = 1), as they never have here."""

    def __init__(self, real, failing):
        self._real, self._failing = real, failing

    def __getattr__(self, name):
        fn = getattr(self._real, name)
        if name not in self._failing:
            return fn

        def failed(*args, **kwargs):
            out = list(fn(*args, **kwargs))
            out[-1] = 1
            return tuple(out)

        return failed


@pytest.mark.parametrize("method", ["music", "unitary_music", "root_music", "esprit"])
def test_lapack_failures_fall_back_to_the_reference_routines(method, monkeypatch):
    cases = random_cases(6, 40, n_choices=(12, 8, 5))
    want = [ss.ESTIMATORS[method](r, m, d) for r, m, d in cases]
    failing = {"zheevr", "dsyevr", "zheev", "dsyev", "dgeev", "zgeev"}
    monkeypatch.setattr(ss, "_lapack", _FailingLapack(ss._lapack, failing))
    for (r, m, d), (u, ok) in zip(cases, want):
        u2, ok2 = ss.ESTIMATORS[method](r, m, d)
        assert np.array_equal(ok, ok2)
        assert np.max(circular_distance(u, u2, d)) < 1e-9


def test_root_music_without_enough_cayley_roots_inside_falls_back_to_the_complex_roots(monkeypatch):
    # _nearest_inside (the Python-float selection of the roots closest to the circle) declines when fewer than
    # n_sources roots lie inside (never seen: finite roots give N − 1 inside); the complex-root path then selects
    cases = random_cases(7, 60, n_choices=(12, 8, 5))
    want = [ss.root_music(r, m, d) for r, m, d in cases]
    monkeypatch.setattr(ss, "_nearest_inside", lambda *args: None)
    for (r, m, d), (u, ok) in zip(cases, want):
        u2, ok2 = ss.root_music(r, m, d)
        assert np.array_equal(ok, ok2)
        assert np.max(circular_distance(u, u2, d)) < 1e-9


def test_root_music_null_sums_read_column_major_equal_the_row_major_ones():
    # root-MUSIC reads zgemm's Es·Esᴴ in place (column-major) with the Im rows' signs flipped: the same sums as
    # _null_sums' row-major copy up to the order of summation
    for r, m, _ in random_cases(8, 100):
        es = ss._signal_subspace(r, m)
        want = ss._null_sums(es)
        got = ss._null_sums_columns(es)
        assert np.max(np.abs(got - want)) <= 4 * np.finfo(float).eps * r.shape[0]
        got = ss._null_sums_columns(np.ascontiguousarray(es))           # any layout: ravel("F") copies then
        assert np.max(np.abs(got - want)) <= 4 * np.finfo(float).eps * r.shape[0]


def test_lapack_calls_by_position_equal_the_calls_by_keyword(monkeypatch):
    # zgemm (covariances, Gram matrices), _eigvecs and root-MUSIC's dgeev pass f2py's optional arguments by position
    # when the installed scipy documents their order (cheaper to parse); the keyword calls give the same numbers
    assert not ss._takes_in_order(object(), "w")
    if not ss._POSITIONAL:
        pytest.skip("this scipy's wrappers document another argument order: the keyword calls are the only path")
    cases = random_cases(9, 60, n_choices=(12, 8, 5))
    want = {method: [ss.ESTIMATORS[method](r, m, d) for r, m, d in cases]
            for method in ("capon", "music", "unitary_music", "root_music", "esprit")}
    rng = np.random.default_rng(9)
    xs = [snapshots(rng, [-0.3, 0.2], 20.0, k) for k in (1, 16)]
    covs = [ss._covariance(x, q, fb) for x in xs for q, fb in ((12, False), (8, True))]
    monkeypatch.setattr(ss, "_POSITIONAL", False)
    for method, results in want.items():
        for (r, m, d), (u, ok) in zip(cases, results):
            u2, ok2 = ss.ESTIMATORS[method](r, m, d)
            assert np.array_equal(u, u2) and np.array_equal(ok, ok2)
    assert all(np.array_equal(r, ss._covariance(x, q, fb))
               for r, (x, (q, fb)) in zip(covs, [(x, qf) for x in xs for qf in ((12, False), (8, True))]))
