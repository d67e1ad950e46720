"""ERP per harmonic: rigid piston closed form, multi-harmonic sums, levels, geometry helpers."""
import numpy as np
import pytest

from sarfe.erp import (
    AIR_DENSITY,
    SOUND_SPEED,
    equivalent_radiated_power,
    nodal_areas,
    nodal_normals,
    nodal_translations,
    normal_displacement,
)
from sarfe.hbm.harmonics import time_samples


def plate(nx=5, ny=4, lx=0.3, ly=0.2):
    x, y = np.meshgrid(np.linspace(0, lx, nx + 1), np.linspace(0, ly, ny + 1), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    idx = np.arange(points.shape[0]).reshape(nx + 1, ny + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    triangles = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return points, triangles


def test_nodal_areas_sum_to_panel_area_and_normals_are_z():
    points, triangles = plate()
    areas = nodal_areas(points, triangles)
    assert areas.sum() == pytest.approx(0.3 * 0.2)
    # a corner node with one triangle gets a third of it, an interior node of 6 triangles gets 6/3
    cell = 0.3 / 5 * 0.2 / 4
    assert areas.max() == pytest.approx(cell)
    normals = nodal_normals(points, triangles)
    np.testing.assert_allclose(normals, np.tile([0, 0, 1.0], (points.shape[0], 1)))


def test_rigid_piston_gives_half_rho_c_area_velocity_squared():
    points, triangles = plate()
    areas = nodal_areas(points, triangles)
    area = areas.sum()
    omega = 2 * np.pi * 250.0
    amplitude = 1e-5  # [m], uniform normal motion w = 1e-5 (0.6 cos θ + 0.8 sin θ)
    W = np.zeros((3, points.shape[0]))
    W[0] = 3e-4                       # static offset must not radiate
    W[1], W[2] = 0.6 * amplitude, 0.8 * amplitude
    erp = equivalent_radiated_power(W, omega, areas)
    v = omega * amplitude
    expected = 0.5 * AIR_DENSITY * SOUND_SPEED * area * v**2
    assert erp.power_total == pytest.approx(expected, rel=1e-12)
    assert erp.power[0] == pytest.approx(expected, rel=1e-12)
    np.testing.assert_allclose(erp.density_total, 0.5 * AIR_DENSITY * SOUND_SPEED * v**2, rtol=1e-12)
    assert erp.level_total_db == pytest.approx(10 * np.log10(expected / 1e-12), rel=1e-12)
    assert erp.frequencies_hz == pytest.approx([250.0])
    assert erp.level_total_a_db == pytest.approx(erp.level_total_db + (-8.67), abs=0.02)


def test_erp_from_time_domain_mean_square_velocity():
    """P = ρc·RLF·Σ_i A_i ⟨v_i²⟩ over a period (mean square = ½ amplitude² per harmonic)."""
    rng = np.random.default_rng(0)
    points, triangles = plate(3, 3)
    areas = nodal_areas(points, triangles)
    H, N, omega = 4, 64, 2 * np.pi * 80.0
    W = rng.normal(size=(2 * H + 1, points.shape[0])) * 1e-6
    rlf = 0.7
    erp = equivalent_radiated_power(W, omega, areas, density=1.2, sound_speed=340.0,
                                    radiation_loss_factor=rlf)
    nabla = np.zeros((2 * H + 1, 2 * H + 1))
    for k in range(1, H + 1):
        nabla[2 * k - 1, 2 * k], nabla[2 * k, 2 * k - 1] = k, -k
    v = time_samples(omega * nabla @ W, N)                     # (N, n) [m/s]
    expected = 1.2 * 340.0 * rlf * np.mean(v**2, axis=0) @ areas
    assert erp.power_total == pytest.approx(expected, rel=1e-10)
    # harmonic k alone
    for k in range(1, H + 1):
        vk = k * omega * np.hypot(W[2 * k - 1], W[2 * k])
        assert erp.power[k - 1] == pytest.approx(0.5 * 1.2 * 340.0 * rlf * vk**2 @ areas)
    assert erp.power.sum() == pytest.approx(erp.power_total)
    # dB arithmetic: total level = power sum of harmonic levels
    assert erp.level_total_db == pytest.approx(10 * np.log10(np.sum(10 ** (erp.level_db / 10))))
    assert erp.density.shape == (H, points.shape[0])
    assert erp.frequencies_hz == pytest.approx(80.0 * np.arange(1, H + 1))


def test_second_harmonic_has_double_velocity():
    areas = np.array([1.0])
    W = np.array([[0.0], [1e-6], [0.0], [1e-6], [0.0]])
    erp = equivalent_radiated_power(W, 100.0, areas)
    assert erp.power[1] / erp.power[0] == pytest.approx(4.0)
    assert erp.level_db[1] - erp.level_db[0] == pytest.approx(10 * np.log10(4.0))


def test_zero_motion_gives_minus_inf_levels_without_warning():
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        erp = equivalent_radiated_power(np.zeros((5, 3)), 10.0, np.ones(3))
    assert erp.power_total == 0.0
    assert erp.level_total_db == -np.inf and erp.level_total_a_db == -np.inf
    assert np.all(erp.level_db == -np.inf)


def test_input_validation():
    with pytest.raises(ValueError, match="nodal_areas"):
        equivalent_radiated_power(np.zeros((3, 4)), 10.0, np.ones(3))
    with pytest.raises(ValueError, match="omega"):
        equivalent_radiated_power(np.zeros((3, 4)), 0.0, np.ones(4))
    with pytest.raises(ValueError, match="2H\\+1"):
        equivalent_radiated_power(np.zeros((2, 4)), 1.0, np.ones(4))


def test_normal_projection_of_tilted_piston():
    """A piston tilted 30° moving along global z: w = u_z cos 30°."""
    points, triangles = plate(2, 2)
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    rot = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    points = points @ rot.T
    normals = nodal_normals(points, triangles)
    np.testing.assert_allclose(normals, np.tile(rot[:, 2], (points.shape[0], 1)), atol=1e-12)
    U = np.zeros((3, points.shape[0], 3))
    U[1, :, 2] = 2e-6
    W = normal_displacement(U, normals)
    np.testing.assert_allclose(W[1], 2e-6 * c)
    # DOF-vector extraction (6 DOF per node, node-major)
    n = points.shape[0]
    full = np.zeros((3, 6 * n))
    full[1, 6 * np.arange(n) + 2] = 2e-6
    np.testing.assert_allclose(nodal_translations(full, np.arange(n)), U)


def test_reduced_quadratic_form_gives_the_nodal_erp():
    """P_k from the reduced Gram matrix Q = Nᵀ diag(A) N, ½ρc (kω)² (u_kcᵀ Q u_kc + u_ksᵀ Q u_ks),
    equals the ERP of the nodal field w = N u summed over 500 radiating nodes to 1e-10 relative
    (dense and sparse N)."""
    import scipy.sparse as sp

    from sarfe.erp import equivalent_radiated_power
    from sarfe.erp.reduced import harmonic_power_proxy, radiation_gram

    rng = np.random.default_rng(3)
    N = rng.normal(size=(500, 12)) * (rng.uniform(size=(500, 12)) < 0.3)
    areas = rng.uniform(1e-5, 1e-4, 500)
    U = rng.normal(size=(2 * 7 + 1, 12)) * 1e-5
    omega = 2 * np.pi * 83.0
    nodal = equivalent_radiated_power(U @ N.T, omega, areas)
    for erp_map in (N, sp.csr_matrix(N)):
        power = 0.5 * 1.204 * 343.2 * harmonic_power_proxy(U, omega, radiation_gram(erp_map, areas))
        assert np.abs(power - nodal.power).max() <= 1e-10 * nodal.power.max()
