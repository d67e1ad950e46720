"""The mesh term's Richardson formula (sarfe.accuracy.mesh_refinement, (1)) against closed forms:
a level converging as L(h) = L* + C h^p."""
import math

import pytest

from sarfe.accuracy.mesh_refinement import MESH_ORDER, MESH_RATIO, mesh_richardson


@pytest.mark.parametrize("p_true", [1.0, 1.5, 2.0, 3.0])
@pytest.mark.parametrize("C", [5.0, -3.0])
def test_richardson_covers_a_level_converging_at_order_one_or_faster(p_true, C):
    """With p = 1 stated the estimate is exact for p_true = 1 and over-reports by
    (2^p_true − 1) for faster convergence: it never under-reports an asymptotic ladder."""
    h, L_star = 0.01, 90.0
    level = (lambda size: L_star + C * (size / 0.01) ** p_true)  # noqa: E731
    estimate = mesh_richardson(level(h), level(MESH_RATIO * h))
    true_error = abs(level(h) - L_star)
    assert estimate >= true_error * (1 - 1e-12)
    assert estimate == pytest.approx(true_error * (MESH_RATIO ** p_true - 1)
                                     / (MESH_RATIO ** MESH_ORDER - 1), rel=1e-12)


def test_richardson_with_the_true_order_is_exact_and_nan_without_a_level():
    level = (lambda size: 40.0 + 2.0 * size ** 2)  # noqa: E731
    assert mesh_richardson(level(1.0), level(1.5), order=2.0, ratio=1.5) == \
        pytest.approx(2.0, rel=1e-12)
    assert math.isnan(mesh_richardson(float("-inf"), 30.0))
