"""Membranes (ANDES optimal triangle, Allman, CST, the incompatible-mode quad) and the DKMT
bending triangle: patch tests on distorted meshes, rigid-body modes, in-plane bending against
plane-stress elasticity, and the Mindlin plate's closed form."""
import numpy as np
import pytest
import scipy.sparse.linalg as sla

from sarfe.fe.assembly import assemble_pair, element_dofs
from sarfe.fe.membrane import andes_stiffness
from sarfe.fe.reference_meshes import rectangle_triangles
from sarfe.fe.shell import element_kinematics, membrane_stiffness, shell_matrices
from sarfe.fe.shell_quad import quad_membrane_matrices
from sarfe.fe.shell_section import section_shell_element_matrices
from sarfe.mesh.laminate import isotropic_plane_stress

E, NU, T = 7.0e10, 0.3, 0.002


def _plane_stress(n, nu=NU):
    return np.broadcast_to(isotropic_plane_stress(1.0, nu), (n, 3, 3)).copy()


def _linear_field(points):
    """u = ε·x of a constant strain (ε_xx, ε_yy, γ_xy) = (1e-3, −4e-4, 6e-4) plus a rotation
    ω = 2e-4: per node [u, v, θz = ω]."""
    exx, eyy, gxy, omega = 1e-3, -4e-4, 6e-4, 2e-4
    x, y = points[:, 0], points[:, 1]
    u = exx * x + (0.5 * gxy - omega) * y
    v = (0.5 * gxy + omega) * x + eyy * y
    return np.column_stack([u, v, np.full(len(x), omega)])


@pytest.mark.parametrize("membrane", ["andes", "allman", "cst"])
def test_membrane_patch_test_on_a_distorted_mesh(membrane):
    """Boundary nodes given a linear field (θz = its rotation), the interior solved: every
    interior node reproduces the field exactly (constant strain is exact)."""
    points, triangles = rectangle_triangles(0.4, 0.3, 6, 5, distortion=0.35, seed=2)
    k, _ = shell_matrices(points, triangles, T, E, NU, 1000.0, membrane=membrane,
                          drilling_penalty=1e-3)
    exact = np.zeros((len(points), 6))
    exact[:, [0, 1, 5]] = _linear_field(points)
    x, y = points[:, 0], points[:, 1]
    boundary = np.isclose(x, 0) | np.isclose(x, 0.4) | np.isclose(y, 0) | np.isclose(y, 0.3)
    given = np.zeros((len(points), 6), bool)
    given[:, [2, 3, 4]] = True                      # bending DOFs: zero, uncoupled
    given[boundary] = True
    given, unknown = given.ravel(), ~given.ravel()
    q = exact.ravel().copy()
    k = k.tocsc()
    q[unknown] = sla.spsolve(k[unknown][:, unknown], -k[unknown][:, given] @ q[given])
    assert np.abs(q - exact.ravel()).max() < 1e-9 * np.abs(exact).max()


def test_andes_has_three_rigid_modes_and_bends_exactly_in_plane():
    """One ANDES triangle: 3 zero eigenvalues. Two triangles making a rectangle of any aspect
    ratio store exactly the plane-stress energy of pure in-plane bending (u = −κxy,
    v = κ(x² + νy²)/2, θz = κx), where Allman's locks (energy ratio 1.8 … 4.7)."""
    points = np.array([[0.0, 0.0, 0.0], [0.11, 0.02, 0.0], [0.03, 0.09, 0.0]])
    geometry = element_kinematics(points, [[0, 1, 2]])
    k = andes_stiffness(geometry.local_xy, geometry.area, _plane_stress(1))[0]
    eigenvalues = np.linalg.eigvalsh(k)
    assert np.sum(eigenvalues < 1e-12 * eigenvalues.max()) == 3
    for nu in (0.0, 0.3):
        for aspect in (0.5, 1.0, 2.0, 4.0):
            ratios = {m: _bending_energy_ratio(aspect, nu, m) for m in ("andes", "allman")}
            assert ratios["andes"] == pytest.approx(1.0, abs=1e-12)
            assert ratios["allman"] > 1.5


def _bending_energy_ratio(aspect, nu, membrane):
    a, b, kappa = aspect, 1.0, 1.0
    points = np.array([[0, -b / 2, 0], [a, -b / 2, 0], [a, b / 2, 0], [0, b / 2, 0.0]])
    triangles = np.array([[0, 1, 2], [0, 2, 3]])
    geometry = element_kinematics(points, triangles)
    k, _ = membrane_stiffness(geometry, _plane_stress(2, nu), membrane)
    x, y = points[:, 0] - a / 2, points[:, 1]
    field = np.column_stack([-kappa * x * y, 0.5 * kappa * (x**2 + nu * y**2), kappa * x])
    energy = 0.0
    for e, corners in enumerate(triangles):
        rotation = geometry.rotation[e]          # in-plane: rotate (u, v), θz unchanged
        local = [np.r_[(rotation[:2, :2] @ field[n, :2]), field[n, 2]] for n in corners]
        q = np.concatenate(local)
        energy += 0.5 * q @ k[e] @ q
    return energy / (0.5 * kappa**2 * b**3 / 12 * a)  # E = 1, M = EIκ


def _quad_patch(distortion=0.3, seed=1, n=4):
    points, _ = rectangle_triangles(0.4, 0.3, n, n, distortion=distortion, seed=seed)
    index = np.arange(len(points)).reshape(n + 1, n + 1)
    quads = np.stack([index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]],
                     -1).reshape(-1, 4)
    return points, quads


def test_quad_membrane_patch_test_and_exact_in_plane_bending():
    points, quads = _quad_patch()
    k = quad_membrane_matrices(points, quads, _plane_stress(len(quads)) * E * T, 1e-4)
    dofs = (6 * quads[:, :, None] + np.arange(6)).reshape(len(quads), 24)
    stiffness, _ = assemble_pair(k, np.zeros_like(k), dofs, 6 * len(points))
    # patch test: with θz equal to the field's rotation the drilling penalty is idle too
    exact = np.zeros((len(points), 6))
    exact[:, [0, 1, 5]] = _linear_field(points)
    x, y = points[:, 0], points[:, 1]
    boundary = np.isclose(x, 0) | np.isclose(x, 0.4) | np.isclose(y, 0) | np.isclose(y, 0.3)
    given = np.zeros((len(points), 6), bool)
    given[:, [2, 3, 4]] = True
    given[boundary] = True
    given, unknown = given.ravel(), ~given.ravel()
    q = exact.ravel().copy()
    stiffness = stiffness.tocsc()
    q[unknown] = sla.spsolve(stiffness[unknown][:, unknown],
                             -stiffness[unknown][:, given] @ q[given])
    # round-off of the weak penalty's conditioning (α = 1e-4): 1e-9 measured
    assert np.abs(q - exact.ravel()).max() < 1e-7 * np.abs(exact).max()
    # one rectangle in pure in-plane bending: the plane-stress energy exactly (QM6)
    a, b, kappa = 3.0, 1.0, 1.0
    corners = np.array([[0, -b / 2, 0], [a, -b / 2, 0], [a, b / 2, 0], [0, b / 2, 0.0]])
    k = quad_membrane_matrices(corners, [[0, 1, 2, 3]], _plane_stress(1), 0.0)[0]
    xc, yc = corners[:, 0] - a / 2, corners[:, 1]
    field = np.zeros((4, 6))
    field[:, 0], field[:, 1] = -kappa * xc * yc, 0.5 * kappa * (xc**2 + NU * yc**2)
    q = field.ravel()
    assert 0.5 * q @ k @ q == pytest.approx(0.5 * kappa**2 * b**3 / 12 * a, rel=1e-12)


def test_warped_quad_membrane_is_free_of_rigid_motions():
    points, quads = _quad_patch()
    points[:, 2] = 0.05 * np.sin(7 * points[:, 0]) * np.cos(5 * points[:, 1])   # warped
    k = quad_membrane_matrices(points, quads, _plane_stress(len(quads)) * E * T, 1e-4)
    for quad, ke in zip(quads, k):
        x = points[quad]
        rigid = np.zeros((4, 6, 6))
        for c in range(3):
            rigid[:, c, c] = 1.0
            rigid[:, :3, 3 + c] = np.cross(np.eye(3)[c], x)
            rigid[:, 3 + c, 3 + c] = 1.0
        assert np.abs(ke @ rigid.reshape(24, 6)).max() < 1e-10 * np.abs(ke).max()


def _mindlin_hard_simply_supported(m, n, a, t, rho, k=5 / 6):
    """Lowest ω/2π [Hz] of mode (m, n) of a hard simply supported square Mindlin plate:
    det[[−D k² − κGt + ρIω², κGt k²], [κGt, −κGt k² + ρtω²]] = 0, k² = (m² + n²)π²/a²."""
    g = E / (2 * (1 + NU))
    d = E * t**3 / (12 * (1 - NU**2))
    inertia = t**3 / 12
    wave = ((m * np.pi / a) ** 2 + (n * np.pi / a) ** 2)
    s = k * g * t
    coefficients = [rho * inertia * rho * t,
                    (-d * wave - s) * rho * t - rho * inertia * s * wave,
                    (d * wave + s) * s * wave - s * s * wave]
    return np.sqrt(np.sort(np.roots(coefficients).real)[0]) / (2 * np.pi)


def _ss_plate(n, t, rho, shear_factor=5 / 6):
    a = 1.0
    points, triangles = rectangle_triangles(a, a, n, n)
    m = len(triangles)
    q = isotropic_plane_stress(E, NU)
    g = E / (2 * (1 + NU))
    shear = None if shear_factor is None else np.tile(shear_factor * g * t * np.eye(2),
                                                      (m, 1, 1))
    k, mass = section_shell_element_matrices(
        points, triangles, np.tile(q * t, (m, 1, 1)), np.zeros((m, 3, 3)),
        np.tile(q * t**3 / 12, (m, 1, 1)), np.tile([1.0, 0, 0], (m, 1)), np.full(m, rho * t),
        np.full(m, rho * t**3 / 12), transverse_shear=shear)
    stiffness, mass = assemble_pair(k, mass, element_dofs(triangles), 6 * len(points))
    x, y = points[:, 0], points[:, 1]
    fixed = np.zeros((len(points), 6), bool)
    fixed[:, [0, 1, 5]] = True
    on_x = np.isclose(x, 0) | np.isclose(x, a)   # w = 0 and the tangential rotation β_y = −θx
    on_y = np.isclose(y, 0) | np.isclose(y, a)
    fixed[on_x, 2] = fixed[on_x, 3] = True
    fixed[on_y, 2] = fixed[on_y, 4] = True
    free = np.flatnonzero(~fixed.ravel())
    values = sla.eigsh(stiffness[free][:, free].tocsc(), 4, mass[free][:, free].tocsc(),
                       sigma=0, which="LM")[0]
    return np.sort(np.sqrt(values)) / (2 * np.pi), stiffness


@pytest.mark.parametrize("thickness", [0.01, 0.1, 0.2])
def test_dkmt_converges_to_the_mindlin_closed_form(thickness):
    """Hard simply supported square plate, t/a = 0.01 … 0.2: the DKMT converges at second
    order to Mindlin's closed form (measured +0.5 … +1.9 % at 16 × 16, four times less at
    32 × 32); without the shear term (DKT) t/a = 0.2 is 10 … 30 % stiff."""
    rho = 7800.0
    exact = np.sort([_mindlin_hard_simply_supported(m, n, 1.0, thickness, rho)
                     for m, n in ((1, 1), (1, 2), (2, 1), (2, 2))])
    coarse = _ss_plate(16, thickness, rho)[0] / exact - 1
    fine = _ss_plate(32, thickness, rho)[0] / exact - 1
    assert np.all(np.abs(coarse) < 0.025) and np.all(np.abs(fine) < 0.006)
    assert np.all(np.abs(coarse) / np.abs(fine) > 3.5)


def test_dkmt_thin_limit_is_the_dkt():
    """Transverse shear stiffness × 1e8 (a thin plate's Gt/(D/L²) and beyond): the DKMT
    stiffness equals the DKT's to 1e-6."""
    _, dkt = _ss_plate(6, 0.01, 7800.0, shear_factor=None)
    _, stiff_shear = _ss_plate(6, 0.01, 7800.0, shear_factor=5e7)
    assert abs(stiff_shear - dkt).max() < 1e-6 * abs(dkt).max()
