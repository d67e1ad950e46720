"""Clamped square plate vs Leissa (1969): λ = ω a² √(ρh/D), first six modes."""

import numpy as np
import pytest
import scipy.sparse.linalg as sla

from sarfe.fe import fixed_dofs, free_dofs, shell_matrices
from sarfe.fe.reference_meshes import boundary_nodes, rectangle_triangles

A, H, E, NU, RHO = 0.3, 2.5e-3, 2.2e9, 0.35, 1050.0
LEISSA = np.array([35.985, 73.394, 73.394, 108.22, 131.58, 132.20])


def clamped_plate_lambdas(cells, pattern="alternating"):
    points, triangles = rectangle_triangles(A, A, cells, cells, pattern=pattern)
    k, m = shell_matrices(points, triangles, H, E, NU, RHO)
    free = free_dofs(k.shape[0], fixed_dofs(boundary_nodes(triangles)))
    k, m = k[free][:, free], m[free][:, free]
    eigenvalues = sla.eigsh(k.tocsc(), 6, m.tocsc(), sigma=0.0, which="LM")[0]
    omega = np.sqrt(np.sort(eigenvalues))
    rigidity = E * H**3 / (12 * (1 - NU**2))
    return omega * A**2 * np.sqrt(RHO * H / rigidity)


@pytest.fixture(scope="module")
def errors():
    return {cells: clamped_plate_lambdas(cells) / LEISSA - 1.0 for cells in (15, 30, 60)}


def test_clamped_plate_5mm_within_half_percent_of_leissa(errors):
    assert np.all(np.abs(errors[60]) < 0.005)


def test_clamped_plate_converges_under_refinement(errors):
    e20, e10, e5 = (np.abs(errors[c]) for c in (15, 30, 60))
    assert np.all(e10 < e20) and np.all(e5 < e10)
    # DKT is second order in h: halving h cuts the error by ~4 (allow ≥ 2.5)
    assert np.all(e10 / e5 > 2.5)


@pytest.mark.slow
@pytest.mark.parametrize("pattern", ["alternating", "right"])
def test_clamped_plate_2p5mm_within_0p1_percent(pattern):
    assert np.all(np.abs(clamped_plate_lambdas(120, pattern) / LEISSA - 1.0) < 0.001)
