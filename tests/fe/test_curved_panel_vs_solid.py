"""Clamped cylindrical panel: facet shell vs an independent scikit-fem quadratic solid."""

import numpy as np
import pytest

from sarfe.fe import fixed_dofs, natural_frequencies, shell_matrices
from sarfe.fe.reference_meshes import (
    boundary_nodes,
    cylindrical_panel_solid,
    cylindrical_panel_triangles,
)
from sarfe.fe.solid import solid_matrices

# ABS-like panel, 0.2 m arc × 0.15 m, R = 0.5 m, 2.5 mm; all four edges clamped
RADIUS, ARC, LENGTH, H = 0.5, 0.2, 0.15, 2.5e-3
E, NU, RHO = 2.2e9, 0.35, 1050.0
ANGLE = ARC / RADIUS


def lowest_six_hz(stiffness, mass, fixed):
    return natural_frequencies(stiffness, mass, 6, fixed)


def shell_frequencies(n_arc, n_axial):
    points, triangles = cylindrical_panel_triangles(RADIUS, ANGLE, LENGTH, n_arc, n_axial)
    k, m = shell_matrices(points, triangles, H, E, NU, RHO)
    return lowest_six_hz(k, m, fixed_dofs(boundary_nodes(triangles)))


def solid_frequencies(n_arc, n_axial, layers, kind="hex2"):
    mesh = cylindrical_panel_solid(RADIUS, ANGLE, LENGTH, H, n_arc, n_axial, layers, kind)
    k, m, basis = solid_matrices(mesh, E, NU, RHO)
    x, y, z = basis.doflocs
    theta = np.arctan2(x, z + RADIUS)
    edge = np.flatnonzero(np.isclose(np.abs(theta), ANGLE / 2, rtol=0, atol=1e-9)
                          | np.isclose(y, 0.0, atol=1e-9) | np.isclose(y, LENGTH, atol=1e-9))
    fixed = (3 * edge[:, None] + np.arange(3)).ravel()  # whole edge faces clamped
    return lowest_six_hz(k, m, fixed)


def test_curved_panel_shell_matches_hex2_solid_within_1_percent():
    """Shell 3.3 mm vs one-layer Hex2 solid 6.7 mm (27-node, exact cylinder geometry)."""
    shell = shell_frequencies(60, 45)
    solid = solid_frequencies(30, 22, 1)
    assert 400 < shell[0] < 500  # sanity: a stiff, curved panel (≈ 446 Hz converged)
    assert np.all(np.abs(shell / solid - 1) < 0.01)


@pytest.mark.slow
def test_curved_panel_fine_shell_matches_two_layer_hex2_within_half_percent():
    shell = shell_frequencies(120, 90)
    solid = solid_frequencies(40, 30, 2)
    assert np.all(np.abs(shell / solid - 1) < 0.005)


@pytest.mark.slow
def test_curved_panel_shell_converges_under_refinement():
    reference = shell_frequencies(160, 120)
    errors = [np.abs(shell_frequencies(n, 3 * n // 4) / reference - 1) for n in (20, 40, 80)]
    assert np.all(errors[1] < errors[0] / 3) and np.all(errors[2] < errors[1] / 3)
    assert np.all(errors[2] < 0.002)
