import numpy as np
import pytest

from pkmkit.exceptions import InputError
from pkmkit.solve.least_squares import (
    BlockPattern,
    _BlockNormal,
    normal_matrix,
    solve_least_squares,
    solve_spd,
    solve_spd_many,
)
from pkmkit.status import Status


def linear_problem(a: np.ndarray, b: np.ndarray):
    """r = A u − b for a batch: a (N, m, n), b (N, m); engine layout is batch-last."""
    a_t = a.transpose(1, 2, 0)
    b_t = b.T

    def evaluate(u, rows):
        return np.einsum("mnk,nk->mk", a_t[:, :, rows], u) - b_t[:, rows], a_t[:, :, rows]

    return evaluate


def test_linear_least_squares_matches_lstsq():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(40, 7, 3))
    b = rng.normal(size=(40, 7))
    res = solve_least_squares(linear_problem(a, b), np.zeros((40, 3)), residual_tol=np.inf)
    expected = np.array([np.linalg.lstsq(a[k], b[k], rcond=None)[0] for k in range(40)])
    np.testing.assert_allclose(res.u, expected, atol=1e-10)
    assert (res.status == Status.OK).all() and (res.rank == 3).all()


def test_rosenbrock_rows_converge_independently():
    def evaluate(u, rows):
        x, y = u
        r = np.stack([10 * (y - x**2), 1 - x])
        jac = np.zeros((2, 2, u.shape[1]))
        jac[0, 0], jac[0, 1], jac[1, 0] = -20 * x, 10.0, -1.0
        return r, jac

    starts = np.array([[-1.2, 1.0], [0.0, 0.0], [2.0, 2.0], [np.nan, 0.0]])
    res = solve_least_squares(evaluate, starts)
    np.testing.assert_allclose(res.u[:3], 1.0, atol=1e-10)
    assert res.status.tolist() == [Status.OK] * 3 + [Status.INVALID_INPUT]
    assert len(set(res.iterations[:3].tolist())) > 1  # per-row stopping


def test_inconsistent_and_rank_deficient_rows():
    # u0 + u1 = 1 and u0 + u1 = 3: rank 1 and no exact solution
    a = np.tile(np.array([[1.0, 1.0], [1.0, 1.0]]), (2, 1, 1))
    b = np.array([[1.0, 3.0], [2.0, 2.0]])
    res = solve_least_squares(linear_problem(a, b), np.zeros((2, 2)))
    assert res.status.tolist() == [Status.INCONSISTENT, Status.OK]
    assert res.rank.tolist() == [1, 1]
    np.testing.assert_allclose(res.u.sum(axis=1), [2.0, 2.0], atol=1e-10)
    # the step never moves along the null space (1, -1): minimum-norm solution from 0
    np.testing.assert_allclose(res.u[:, 0] - res.u[:, 1], 0.0, atol=1e-10)


def test_iteration_limit_flag():
    def evaluate(u, rows):
        return np.exp(u) + 1.0, np.exp(u)[:, None, :]  # no zero: drifts to -inf

    res = solve_least_squares(evaluate, np.zeros((1, 1)), max_iter=3)
    assert res.status[0] == Status.NOT_CONVERGED and res.iterations[0] == 3


def test_default_iteration_limit_is_60():
    """r = u³ from 1e10: Gauss–Newton steps u → 2u/3 make steady progress (no stall), and
    reaching |r| < residual_tol would take about 80 of them."""
    def evaluate(u, rows):
        return u**3, (3 * u**2)[:, None, :]

    res = solve_least_squares(evaluate, np.full((1, 1), 1e10))
    assert res.status[0] == Status.NOT_CONVERGED and res.iterations[0] == 60


def test_rows_without_a_finite_start_are_flagged_and_left_alone():
    calls = []

    def evaluate(u, rows):
        calls.append(rows)
        return u - 1.0, np.ones((1, 1, u.shape[1]))

    res = solve_least_squares(evaluate, np.full((3, 1), np.nan))
    assert res.status.tolist() == [Status.INVALID_INPUT] * 3 and calls == []
    assert res.iterations.tolist() == [0, 0, 0] and np.isnan(res.residual).all()
    mixed = solve_least_squares(evaluate, np.array([[np.nan], [0.0], [np.inf]]))
    assert mixed.status.tolist() == [Status.INVALID_INPUT, Status.OK, Status.INVALID_INPUT]
    assert mixed.iterations[0] == mixed.iterations[2] == 0
    assert mixed.u[1, 0] == pytest.approx(1.0, abs=1e-12)


def test_warm_start_needs_fewer_iterations():
    def evaluate(u, rows):
        return np.stack([u[0] ** 3 - 2.0]), 3 * u[None] ** 2

    cold = solve_least_squares(evaluate, np.full((1, 1), 5.0))
    warm = solve_least_squares(evaluate, cold.u + 1e-6)
    assert warm.iterations[0] < cold.iterations[0]
    np.testing.assert_allclose(cold.u, 2 ** (1 / 3), rtol=1e-14)


@pytest.mark.parametrize("n", [1, 3, 6, 12])
def test_solve_spd_matches_numpy(n):
    rng = np.random.default_rng(n)
    jac = rng.normal(size=(n + 4, n, 30))
    h = normal_matrix(jac) + 1e-3 * np.eye(n)[:, :, None]
    b = rng.normal(size=(n, 30))
    expected = np.linalg.solve(h.transpose(2, 0, 1), b.T[:, :, None])[:, :, 0].T
    np.testing.assert_allclose(solve_spd(h, b), expected, rtol=1e-9, atol=1e-12)


def block_problem(rng, n_rows: int, shared: int, groups: list[int]):
    """A nonlinear problem with bordered block-diagonal normal equations: shared unknowns s
    in every row group, private unknowns p_g in group g's six rows only:
    r_g = A_g s + B_g p_g + 0.02 sin(p_g)·c_g − b_g, and two extra rows on s alone."""
    blocks = []
    col = shared
    for size in groups:
        blocks.append((rng.normal(size=(6, shared, n_rows)), rng.normal(size=(6, size, n_rows)),
                       rng.normal(size=(6, size, n_rows)), rng.normal(size=(6, n_rows)),
                       slice(col, col + size)))
        col += size
    extra = (rng.normal(size=(2, shared, n_rows)), rng.normal(size=(2, n_rows)))

    def evaluate(u, rows):
        res, jac = [], []
        for a, b, c, rhs, cols in blocks:
            p = u[cols]
            res.append(np.einsum("mnk,nk->mk", a[:, :, rows], u[:shared])
                       + np.einsum("mnk,nk->mk", b[:, :, rows], p)
                       + 0.02 * np.einsum("mnk,nk->mk", c[:, :, rows], np.sin(p)) - rhs[:, rows])
            j = np.zeros((6, u.shape[0], u.shape[1]))
            j[:, :shared] = a[:, :, rows]
            j[:, cols] = b[:, :, rows] + 0.02 * c[:, :, rows] * np.cos(p)[None]
            jac.append(j)
        res.append(np.einsum("mnk,nk->mk", extra[0][:, :, rows], u[:shared]) - extra[1][:, rows])
        j = np.zeros((2, u.shape[0], u.shape[1]))
        j[:, :shared] = extra[0][:, :, rows]
        jac.append(j)
        return np.concatenate(res), np.concatenate(jac)

    pattern = BlockPattern(
        shared=tuple(range(shared)),
        groups=tuple((tuple(range(6 * g, 6 * g + 6)), tuple(range(b[4].start, b[4].stop)))
                     for g, b in enumerate(blocks)))
    return evaluate, pattern, col


def test_block_pattern_gives_the_dense_solution():
    """The Schur-complement path takes the same steps as the dense one: same solutions, same
    iteration counts, on a nonlinear least-squares problem with an inconsistent residual."""
    rng = np.random.default_rng(7)
    evaluate, pattern, n = block_problem(rng, 64, 6, [3, 4, 3])
    u0 = rng.normal(scale=0.1, size=(64, n))
    dense = solve_least_squares(evaluate, u0, residual_tol=np.inf)
    block = solve_least_squares(evaluate, u0, residual_tol=np.inf, pattern=pattern)
    assert (dense.status == Status.OK).sum() >= 60
    assert np.array_equal(block.status, dense.status)
    np.testing.assert_allclose(block.u, dense.u, atol=1e-10)
    assert np.array_equal(block.iterations, dense.iterations)
    assert np.array_equal(block.rank, dense.rank)


def test_block_solve_matches_lapack():
    rng = np.random.default_rng(8)
    evaluate, pattern, n = block_problem(rng, 20, 7, [2, 5, 1])
    u = rng.normal(size=(n, 20))
    _, jac = evaluate(u, np.arange(20))
    normal = _BlockNormal.of(jac, pattern)
    dense = normal_matrix(jac)
    np.testing.assert_allclose(normal.diagonal(), dense[np.arange(n), np.arange(n)], rtol=1e-13)
    lam = rng.uniform(0.1, 1.0, (n, 20))
    normal.add_diagonal(lam)
    dense[np.arange(n), np.arange(n)] += lam
    rhs = rng.normal(size=(n, 20))
    expected = np.linalg.solve(dense.transpose(2, 0, 1), rhs.T[:, :, None])[:, :, 0].T
    np.testing.assert_allclose(normal.solve(rhs), expected, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(solve_spd_many(dense, rhs[:, None]), expected[:, None],
                               rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(("pattern", "message"), [
    (BlockPattern(shared=(0,), groups=(((0, 1), (2,)),)), "do not partition"),
    (BlockPattern(shared=(0,), groups=(((0, 1), (1,)), ((1, 2), (2,)))), "disjoint rows"),
])
def test_block_pattern_is_checked(pattern, message):
    def evaluate(u, rows):
        return np.zeros((3, u.shape[1])), np.zeros((3, 3, u.shape[1]))

    with pytest.raises(InputError, match=message):
        solve_least_squares(evaluate, np.zeros((2, 3)), pattern=pattern)


def test_stationarity_stop_is_the_documented_cosine():
    """Inconsistent rows (no zero residual) stop when every Jacobian column is orthogonal to
    the residual within gtol: at the returned u, |J_iᵀ r| ≤ gtol ‖J_i‖ ‖r‖ for each column i,
    checked here from the problem itself on 300 random rows."""
    rng = np.random.default_rng(9)
    a, b, c = rng.uniform(0.5, 2.0, (3, 300))

    def residual(u):
        return np.stack([u[0] - a, u[1] - b, 3.0 * (u[0] * u[1] - c * a * b)])

    def evaluate(u, rows):
        x, y = u
        r = np.stack([x - a[rows], y - b[rows], 3.0 * (x * y - c[rows] * a[rows] * b[rows])])
        jac = np.zeros((3, 2, u.shape[1]))
        jac[0, 0], jac[1, 1], jac[2, 0], jac[2, 1] = 1.0, 1.0, 3.0 * y, 3.0 * x
        return r, jac

    gtol = 1e-3
    res = solve_least_squares(evaluate, np.stack([a, b], axis=1), gtol=gtol, residual_tol=0.0)
    assert (res.status == Status.INCONSISTENT).all()
    u = res.u.T
    r = residual(u)
    jac = np.stack([np.stack([np.ones(300), np.zeros(300), 3.0 * u[1]]),
                    np.stack([np.zeros(300), np.ones(300), 3.0 * u[0]])])  # (column, m, N)
    cosine = np.abs(np.einsum("imk,mk->ik", jac, r)) / (
        np.linalg.norm(jac, axis=1) * np.linalg.norm(r, axis=0))
    assert cosine.max() <= gtol * (1 + 1e-9)
    assert cosine.max() > 0.3 * gtol  # and stops there, not at rounding level


def test_steps_that_raise_the_cost_are_refused():
    """r = arctan(u) from u = 1.5: the plain Gauss–Newton step overshoots to ever larger |u|
    (each step raising the cost by 10–20 %); refusing those steps and damping instead
    converges to u = 0."""
    def evaluate(u, rows):
        return np.arctan(u), (1.0 / (1.0 + u**2))[:, None, :]

    res = solve_least_squares(evaluate, np.full((1, 1), 1.5))
    assert res.status[0] == Status.OK and abs(res.u[0, 0]) < 1e-9


def test_normal_matrix_of_few_large_problems_is_the_entrywise_one():
    """Few problems with many unknowns take matrix products (one per problem); many small ones
    the entry-by-entry passes over the batch: the same JᵀJ."""
    rng = np.random.default_rng(0)
    for n, k in ((20, 3), (53, 1), (6, 500), (20, 40)):
        jac = rng.normal(size=(30, n, k))
        expected = np.einsum("mik,mjk->ijk", jac, jac)
        np.testing.assert_allclose(normal_matrix(jac), expected, rtol=1e-12, atol=1e-12)
