"""Clamped square plate vs Leissa (1969): λ = ω a² √(ρh/D), first six modes."""

import numpy as np
import pytest

from sarfe.fe import fixed_dofs, natural_frequencies, shell_matrices
from sarfe.fe.reference_meshes import (
    boundary_nodes,
    gmsh_rectangle_triangles,
    rectangle_triangles,
)

A, H, E, NU, RHO = 0.3, 2.5e-3, 2.2e9, 0.35, 1050.0
LEISSA = np.array([35.985, 73.394, 73.394, 108.22, 131.58, 132.20])


def clamped_plate_lambdas(cells, pattern="alternating", mesh=None):
    if mesh is None:
        mesh = rectangle_triangles(A, A, cells, cells, pattern=pattern)
    points, triangles = mesh
    k, m = shell_matrices(points, triangles, H, E, NU, RHO)
    omega = 2 * np.pi * natural_frequencies(k, m, 6, fixed_dofs(boundary_nodes(triangles)))
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


def test_unstructured_gmsh_plate_5mm_within_half_percent():
    points, triangles = gmsh_rectangle_triangles(A, A, 0.005)
    assert len(triangles) > 7000  # genuinely 5 mm, unstructured
    errors = clamped_plate_lambdas(None, mesh=(points, triangles)) / LEISSA - 1.0
    assert np.all(np.abs(errors) < 0.005)


@pytest.mark.slow
@pytest.mark.parametrize("pattern", ["alternating", "right"])
def test_clamped_plate_2p5mm_within_0p1_percent(pattern):
    assert np.all(np.abs(clamped_plate_lambdas(120, pattern) / LEISSA - 1.0) < 0.001)
