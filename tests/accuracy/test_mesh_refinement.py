"""The mesh term's Richardson formula (sarfe.accuracy.mesh_refinement, (1)) against closed forms:
a level converging as L(h) = L* + C h^p."""
import math

import pytest

from sarfe.accuracy.mesh_refinement import (MESH_GCI_RATIO, MESH_ORDER, MESH_RATIO, SAFETY_FACTOR,
                                           SAFETY_FACTOR_OSCILLATING, mesh_gci, mesh_richardson)


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


@pytest.mark.parametrize("p_true", [1.05, 1.5, 1.95])
@pytest.mark.parametrize("C", [5.0, -3.0])
def test_gci_of_three_meshes_finds_the_order_and_covers_the_error(p_true, C):
    """(2) on L(h) = L* + C h^p with 1 ≤ p ≤ 2: the observed order is p and the estimate is
    Fs = 1.25 times the true error (Richardson with the right order is exact)."""
    level = (lambda size: 90.0 + C * size ** p_true)  # noqa: E731
    h = 0.6
    gci = mesh_gci([level(h), level(MESH_GCI_RATIO * h), level(MESH_GCI_RATIO ** 2 * h)])
    assert gci["convergence"] == "monotone" and gci["order"] == pytest.approx(p_true, rel=1e-9)
    assert gci["mesh_db"] == pytest.approx(SAFETY_FACTOR * abs(level(h) - 90.0), rel=1e-9)


def test_gci_outside_the_asymptotic_range_uses_the_levels_range():
    """p = 3 (the finer levels agree better than order 2 allows) and p = 0.5: 1.25 × ΔM (which
    covers p = 3's true error; a true order below 1 is not expected of a consistent element and
    is under-reported: the stated limit); levels that oscillate: 3 × ΔM; equal levels: 0; p = 1
    joins (2) continuously; a level that is not finite: NaN."""
    for p_true in (3.0, 0.5):
        level = (lambda size: 30.0 + 2.0 * size ** p_true)  # noqa: E731
        gci = mesh_gci([level(1.0), level(MESH_GCI_RATIO), level(2.0)])
        assert gci["convergence"] == "pre-asymptotic"
        assert gci["order"] == pytest.approx(p_true)
        assert gci["mesh_db"] == pytest.approx(SAFETY_FACTOR * (level(2.0) - level(1.0)))
    assert mesh_gci([32.0, 30.0 + 2.0 * MESH_GCI_RATIO ** 3, 46.0])["mesh_db"] >= 2.0
    oscillating = mesh_gci([30.13, 30.64, 30.15])       # the squeak rig at 10 / 14.1 / 20 mm
    assert oscillating["convergence"] == "oscillatory"
    assert oscillating["mesh_db"] == pytest.approx(SAFETY_FACTOR_OSCILLATING * 0.51)
    assert mesh_gci([40.0, 40.0, 40.0])["mesh_db"] == 0.0
    below, above = (mesh_gci([1.0, MESH_GCI_RATIO, 2.0 + d]) for d in (-1e-9, 1e-9))  # p ≈ 1
    assert {below["convergence"], above["convergence"]} == {"monotone", "pre-asymptotic"}
    assert below["mesh_db"] == pytest.approx(above["mesh_db"], rel=1e-6)
    assert math.isnan(mesh_gci([float("-inf"), 30.0, 31.0])["mesh_db"])
