"""ERP against the Rayleigh integral: a baffled circular piston, σ = 1 − J1(2ka)/(ka)."""
import numpy as np
import pytest
from scipy.spatial import Delaunay
from scipy.special import j1

from sarfe.erp import SOUND_SPEED, equivalent_radiated_power, nodal_areas
from sarfe.erp.rayleigh import baffled_radiated_power, radiation_efficiency


def disc(radius, rings):
    pts = [np.zeros((1, 2))]
    for i in range(1, rings + 1):
        m = 6 * i
        t = 2 * np.pi * np.arange(m) / m + (0.5 * np.pi / m if i % 2 else 0.0)
        pts.append(radius * i / rings * np.column_stack([np.cos(t), np.sin(t)]))
    pts = np.concatenate(pts)
    return np.column_stack([pts, np.zeros(len(pts))]), Delaunay(pts).simplices


@pytest.fixture(scope="module")
def piston():
    points, triangles = disc(0.1, 16)
    return points, nodal_areas(points, triangles)


@pytest.mark.parametrize("ka", [0.2, 1.0, 2.0, 5.0])
def test_circular_piston_radiation_efficiency(piston, ka):
    points, areas = piston
    omega = ka / 0.1 * SOUND_SPEED
    sigma = radiation_efficiency(points, areas, np.ones(len(points)), omega)
    assert sigma == pytest.approx(1 - j1(2 * ka) / ka, rel=5e-3)


def test_erp_is_high_frequency_limit_of_rayleigh_power(piston):
    """ERP of the harmonic coefficients = ½ρcΣA|v|²; Rayleigh power → ERP for ka ≫ 1 and
    → (ka)²/2 · ERP for ka ≪ 1 (ERP overestimates a small piston's radiation)."""
    points, areas = piston
    n = len(points)
    W = np.zeros((3, n))
    W[1], W[2] = 3e-6, -4e-6          # w = Re(ŵ e^{iθ}), ŵ = w_c − i w_s
    for ka, expected in ((5.0, 1 - j1(10.0) / 5.0), (0.1, 1 - j1(0.2) / 0.1)):
        omega = ka / 0.1 * SOUND_SPEED
        erp = equivalent_radiated_power(W, omega, areas)
        v = 1j * omega * (W[1] - 1j * W[2])
        power = baffled_radiated_power(points, areas, v, omega, block=100)
        assert power / erp.power_total == pytest.approx(expected, rel=5e-3)
    assert expected == pytest.approx(0.1**2 / 2, rel=1e-2)
