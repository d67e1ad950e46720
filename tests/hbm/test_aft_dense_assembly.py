"""∂λ̃/∂r̃ assembled dense (the condensed Newton's path) equals the definition: entry (h·n_rows +
row_a, g·n_rows + row_b) of the global matrix is the sum of the block entries (h·m + a, g·m + b)
over the blocks that hold rows a, b (absent rows −1 skipped) — written out with explicit loops."""
import numpy as np

from sarfe.hbm.aft import jacobian_matrix


def by_definition(blocks, n_rows, H):
    P = 2 * H + 1
    out = np.zeros((P * n_rows, P * n_rows))
    for rows, block in blocks:
        m = rows.shape[1]
        for c in range(rows.shape[0]):
            for h in range(P):
                for a in range(m):
                    for g in range(P):
                        for b in range(m):
                            if rows[c, a] >= 0 and rows[c, b] >= 0:
                                out[h * n_rows + rows[c, a], g * n_rows + rows[c, b]] += \
                                    block[c, h * m + a, g * m + b]
    return out


def test_dense_assembly_equals_the_definition():
    rng = np.random.default_rng(3)
    H, n_rows = 2, 7
    P = 2 * H + 1
    distinct = [(np.array([[0, 2, -1], [1, 3, 4]]), rng.normal(size=(2, 3 * P, 3 * P))),
                (np.array([[5], [6]]), rng.normal(size=(2, P, P)))]
    dense = jacobian_matrix(distinct, n_rows, H, dense=True)
    assert np.allclose(dense, by_definition(distinct, n_rows, H), rtol=0, atol=1e-14)
    assert np.allclose(dense, jacobian_matrix(distinct, n_rows, H).toarray(), rtol=0, atol=1e-14)
    shared = distinct + [(np.array([[0]]), rng.normal(size=(1, P, P)))]   # row 0 in two blocks
    assert np.allclose(jacobian_matrix(shared, n_rows, H, dense=True),
                       by_definition(shared, n_rows, H), rtol=0, atol=1e-14)
