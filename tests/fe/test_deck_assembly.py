"""Deck assembly: closed forms (beam, spring–mass, CONM2 offset, rigid-body modes with RBE2/RBE3),
patch tests of the solid cells, and the real decks' natural frequencies vs the commercial solver."""
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as la

from sarfe.fe.deck_assembly import (assemble_deck, global_matrices, load_vector, support_dofs)
from sarfe.mesh.formats.deck import DeckError
from sarfe.mesh.formats.nastran import read_nastran

# beside the checkout (CI), or beside the folder of worktrees (/work/wt/<name> → /work/shared)
DECKS = next((root / "shared" / "decks" for root in Path(__file__).resolve().parents[3:5]
              if (root / "shared" / "decks").is_dir()),
             Path(__file__).resolve().parents[3] / "shared" / "decks")
needs_decks = pytest.mark.skipif(not (DECKS / "REFERENCE.json").is_file(),
                                 reason=f"public decks folder {DECKS} is absent")


def _write(tmp_path, text):
    path = tmp_path / "deck.bdf"
    path.write_text("BEGIN BULK\n" + text.strip() + "\nENDDATA\n")
    return path


def _fixed(*fields):
    """One small-field (8-character) line."""
    def text(field):
        if isinstance(field, (str, int)):
            return str(field)
        value = f"{field:.6g}"
        return value if "." in value or "e" in value else value + "."
    return "".join(f"{text(field):<8}" for field in fields)


def _frequencies(system, fixed=(), count=None):
    """Natural frequencies [Hz], ascending. M may be singular (lumped mass leaves the shells'
    penalty-held drilling rotations massless, their λ = ∞): solve M x = μ (K + s M) x,
    λ = 1/μ − s, with K + s M definite for s > 0, and keep the μ > 0."""
    free = np.setdiff1d(np.arange(system.n_dofs), np.asarray(fixed, int))
    k = system.stiffness[free][:, free].toarray()
    m = system.mass[free][:, free].toarray()
    shift = 1e-3 * np.abs(np.diag(k)).max() / np.abs(np.diag(m)).max()
    mu = la.eigh(m, k + shift * m, eigvals_only=True)
    mu = np.sort(mu[mu > 1e-12 * mu.max()])[::-1]
    hz = np.sqrt(np.abs(1.0 / mu - shift)) / (2 * np.pi)
    return hz if count is None else hz[:count]


def _cantilever(n_el, length, load):
    grids = "\n".join(f"GRID,{i + 1},,{length * i / n_el},0.,0." for i in range(n_el + 1))
    bars = "\n".join(f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,1.,0." for i in range(n_el))
    return f"""{grids}
{bars}
PBAR,1,1,4.e-4,3.333333e-8,1.333333e-8,2.e-8
MAT1,1,2.1e11,,0.3,7800.
SPC1,1,123456,1
FORCE,2,{n_el + 1},,{load},0.,0.,1.
"""


def test_cantilever_bar_tip_deflection_and_first_frequency(tmp_path):
    length, load, n_el = 1.0, 10.0, 10
    deck = read_nastran(_write(tmp_path, _cantilever(n_el, length, load)))
    system = assemble_deck(deck, mass="consistent")   # the Hermite beam's consistent mass
    fixed = support_dofs(system, deck, 1)
    free = np.setdiff1d(np.arange(system.n_dofs), fixed)
    force = load_vector(system, deck, 2)
    q = np.zeros(system.n_dofs)
    q[free] = np.linalg.solve(system.stiffness[free][:, free].toarray(), force[free])
    tip = system.displacement(q)[-1]
    e, i2, area, rho = 2.1e11, 1.333333e-8, 4e-4, 7800.0
    # bending in the x–z plane uses I2: w = F L³ / (3 E I2)
    assert tip[2] == pytest.approx(load * length**3 / (3 * e * i2), rel=1e-9)
    first = _frequencies(system, fixed, 1)[0]
    closed = 1.875104**2 / (2 * np.pi) * np.sqrt(e * i2 / (rho * area * length**4))
    assert first == pytest.approx(closed, rel=2e-4)


def test_timoshenko_shear_factor_softens_short_beam(tmp_path):
    # one element, PBEAM K1 = K2 = 5/6: tip = F L³/(3EI) + F L/(k G A)
    text = """GRID,1,,0.,0.,0.
GRID,2,,0.2,0.,0.
CBEAM,1,1,1,2,0.,1.,0.
PBEAM,1,1,1.e-3,1.e-7,1.e-7,,2.e-7
,0.,0.,0.,0.,0.,0.,0.,0.
,0.8333333333,0.8333333333
MAT1,1,2.e11,8.e10,,7800.
SPC1,1,123456,1
FORCE,2,2,,1.,0.,1.,0.
"""
    deck = read_nastran(_write(tmp_path, text))
    assert deck.beams.shear_factor_1[0] == pytest.approx(5 / 6)
    system = assemble_deck(deck)
    fixed = support_dofs(system, deck, 1)
    free = np.setdiff1d(np.arange(system.n_dofs), fixed)
    q = np.zeros(system.n_dofs)
    q[free] = np.linalg.solve(system.stiffness[free][:, free].toarray(),
                              load_vector(system, deck, 2)[free])
    expected = 0.2**3 / (3 * 2e11 * 1e-7) + 0.2 / (5 / 6 * 8e10 * 1e-3)
    assert system.displacement(q)[1, 1] == pytest.approx(expected, rel=1e-6)


def test_spring_mass_on_cbush_and_its_damping(tmp_path):
    k, m, ge = 4.0e5, 2.5, 0.06
    deck = read_nastran(_write(tmp_path, f"""
GRID,1,,0.,0.,0.
GRID,2,,0.,0.,0.
CBUSH,1,1,1,2,,,,0
{_fixed("PBUSH", 1, "K", k, 2 * k, 3 * k, 1.0, 1.0, 1.0)}
{_fixed("", "", "GE", ge)}
CONM2,2,2,,{m},,,,,+
+,1.e-3,,1.e-3,,,1.e-3
SPC1,1,123456,1
"""))
    system = assemble_deck(deck)
    fixed = support_dofs(system, deck, 1)
    hz = _frequencies(system, fixed)
    expected = np.sqrt(np.array([k, 2 * k, 3 * k]) / m) / (2 * np.pi)
    assert np.allclose(np.sort(hz)[3:], np.sort(expected), rtol=1e-10)
    assert np.allclose(system.structural_damping.toarray(), ge * system.stiffness.toarray())


def test_conm2_offset_gives_rigid_transfer_mass(tmp_path):
    m, e = 3.0, np.array([0.1, -0.2, 0.3])
    deck = read_nastran(_write(tmp_path, f"""
GRID,1,,1.,2.,3.
CONM2,1,1,,{m},{e[0]},{e[1]},{e[2]},,+
+,0.5,0.01,0.6,0.02,0.03,0.7
"""))
    _, mass = global_matrices(deck)
    block = mass.toarray()[:6, :6]
    i_cg = np.array([[0.5, -0.01, -0.02], [-0.01, 0.6, -0.03], [-0.02, -0.03, 0.7]])
    assert np.allclose(block[:3, :3], m * np.eye(3))
    # inertia about the node: parallel-axis theorem, I_cg + m (|e|² I − e eᵀ)
    assert np.allclose(block[3:, 3:], i_cg + m * (e @ e * np.eye(3) - np.outer(e, e)))
    # translation–rotation coupling: f = m (a + α × e) → ∂f/∂α = −m [e]×
    cross = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    assert np.allclose(block[:3, 3:], -m * cross)


def _free_plate_with_rigid_elements(n=4):
    grids, quads = [], []
    for j in range(n + 1):
        for i in range(n + 1):
            grids.append(f"GRID,{j * (n + 1) + i + 1},,{0.1 * i},{0.1 * j},0.")
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1
            quads.append(f"CQUAD4,{j * n + i + 1},1,{a},{a + 1},{a + n + 2},{a + n + 1}")
    top = (n + 1) ** 2
    return "\n".join(grids + quads) + f"""
PSHELL,1,1,0.003,1
MAT1,1,2.e9,,0.35,1100.
GRID,{top + 1},,0.2,0.2,0.1
GRID,{top + 2},,0.05,0.05,-0.1
RBE2,900,{top + 1},123456,1,{n + 1},{top - n},{top}
RBE3,901,,{top + 2},123456,1.,123,2,3
,{n + 2}
CONM2,902,{top + 1},,0.05
CONM2,903,{top + 2},,0.02,,,,,+
+,1.e-5,,1.e-5,,,1.e-5
"""


def test_free_model_with_rbe2_rbe3_has_exactly_six_rigid_modes(tmp_path):
    deck = read_nastran(_write(tmp_path, _free_plate_with_rigid_elements()))
    system = assemble_deck(deck)
    hz = _frequencies(system)
    assert np.all(hz[:6] < 1e-3 * hz[6])
    assert hz[6] > 1.0
    # the RBE2 independent node carries the dependent corners rigidly
    assert len(system.auto_held_nodes) == 0


def test_rbe2_dependent_dofs_follow_rigidly(tmp_path):
    deck = read_nastran(_write(tmp_path, _free_plate_with_rigid_elements()))
    system = assemble_deck(deck)
    q = np.zeros(system.n_dofs)
    independent = deck.node_index([26])[0]
    q[system.dof_index(independent, 3)] = 1e-3  # rotate the spider's hub about x
    u = system.displacement(q)
    for corner in deck.node_index([1, 5, 21, 25]):
        r = deck.points[corner] - deck.points[independent]
        assert np.allclose(u[corner, :3], np.cross([1e-3, 0, 0], r), atol=1e-15)
        assert np.allclose(u[corner, 3:], [1e-3, 0, 0])


def test_support_on_a_dependent_dof_is_an_error(tmp_path):
    deck = read_nastran(_write(tmp_path, _free_plate_with_rigid_elements() + "SPC1,7,3,1\n"))
    system = assemble_deck(deck)
    with pytest.raises(DeckError, match="node 1 component 3 is dependent"):
        support_dofs(system, deck, 7)


def test_solid_only_nodes_lose_their_rotations():
    deck = read_nastran(DECKS / "mode_solid_shell_bar.bdf") if DECKS.is_dir() else None
    if deck is None:
        pytest.skip(f"public decks folder {DECKS} is absent")
    system = assemble_deck(deck)
    held = system.auto_held_components
    # rotations of solid/rod nodes, and the lateral translations of the rods' clamped feet
    # (GRIDs 24, 25 carry only CROD axial/torsion stiffness)
    translations = deck.node_ids[system.auto_held_nodes[held < 3]]
    assert set(translations.tolist()) == {24, 25}
    assert np.all(system.stiffness.diagonal() > 0)


# the shared decks' frequencies vs the stored ones: tests/fe/test_shell_decks.py


def test_isotropic_section_shell_equals_the_shell_element():
    from sarfe.mesh.laminate import isotropic_plane_stress
    from sarfe.fe.shell import shell_element_matrices
    from sarfe.fe.shell_section import section_shell_element_matrices

    rng = np.random.default_rng(3)
    points, triangles = rng.random((9, 3)), np.arange(9).reshape(3, 3)
    t, e, nu, rho = 0.003, 2.2e9, 0.35, 1050.0
    k_ref, m_ref = shell_element_matrices(points, triangles, t, e, nu, rho)
    q = np.broadcast_to(isotropic_plane_stress(e, nu), (3, 3, 3))
    k, m = section_shell_element_matrices(points, triangles, q * t, 0 * q, q * t**3 / 12,
                                          rng.random((3, 3)), np.full(3, rho * t),
                                          np.full(3, rho * t**3 / 12))
    assert np.abs(k - k_ref).max() <= 1e-12 * np.abs(k_ref).max()
    assert np.abs(m - m_ref).max() <= 1e-12 * np.abs(m_ref).max()


def _unit_cells():
    from sarfe.fe.solid_cells import _HEX_EDGES, _TET_EDGES

    hexa = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                     [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    tet = hexa[[0, 1, 3, 4]]
    wedge = hexa[[0, 1, 3, 4, 5, 7]]
    return {"tet4": (tet, 1 / 6), "wedge6": (wedge, 0.5), "hex8": (hexa, 1.0),
            "tet10": (np.vstack([tet, tet[_TET_EDGES].mean(axis=1)]), 1 / 6),
            "hex20": (np.vstack([hexa, hexa[_HEX_EDGES].mean(axis=1)]), 1.0)}


@pytest.mark.parametrize("kind", ["tet4", "tet10", "hex8", "hex20", "wedge6"])
def test_solid_cells_mass_rigid_motion_and_constant_strain(kind):
    from sarfe.fe.solid_cells import solid_cell_matrices

    points, volume = _unit_cells()[kind]
    rng = np.random.default_rng(5)
    points = points + 0.03 * rng.standard_normal(3)  # a shifted cell
    n = len(points)
    k, m, _ = solid_cell_matrices(points, np.arange(n)[None], kind, np.array([7e10]),
                                  np.array([0.3]), np.array([2700.0]))
    assert m[0][0::3, 0::3].sum() == pytest.approx(2700.0 * volume, rel=1e-12)
    rigid = np.cross([0.3, -0.2, 0.5], points).ravel() + np.tile([1.0, 2.0, 3.0], n)
    assert np.abs(k[0] @ rigid).max() < 1e-6 * np.abs(k[0]).max()
    # constant strain ε = sym(G): energy ½ ε:C:ε V exactly
    grad = rng.random((3, 3))
    u = (points @ grad.T).ravel()
    strain = 0.5 * (grad + grad.T)
    lam, mu = 7e10 * 0.3 / (1.3 * 0.4), 7e10 / 2.6
    energy = 0.5 * np.sum((lam * np.trace(strain) * np.eye(3) + 2 * mu * strain) * strain) * volume
    assert 0.5 * u @ k[0] @ u == pytest.approx(energy, rel=1e-10)


def test_hex8_cantilever_does_not_lock():
    import scipy.sparse as sp

    from sarfe.fe.solid_cells import solid_cell_matrices

    length, n_el, young = 10.0, 10, 1e3
    x = np.linspace(0, length, n_el + 1)
    points = np.array([[xi, y, z] for xi in x for y in (0, 1.0) for z in (0, 1.0)])
    node = lambda i, j, l: 4 * i + 2 * j + l  # noqa: E731
    cells = np.array([[node(i, 0, 0), node(i + 1, 0, 0), node(i + 1, 1, 0), node(i, 1, 0),
                       node(i, 0, 1), node(i + 1, 0, 1), node(i + 1, 1, 1), node(i, 1, 1)]
                      for i in range(n_el)])
    k, _, dofs = solid_cell_matrices(points, cells, "hex8", np.full(n_el, young),
                                     np.zeros(n_el), np.ones(n_el))
    size = 6 * len(points)
    rows = np.repeat(dofs, dofs.shape[1], axis=1).ravel()
    cols = np.tile(dofs, (1, dofs.shape[1])).ravel()
    stiffness = sp.csr_matrix((k.ravel(), (rows, cols)), shape=(size, size))
    free = np.setdiff1d(np.unique(dofs), [6 * n + c for n in range(4) for c in range(3)])
    force = np.zeros(size)
    tip = [node(n_el, j, l) for j in (0, 1) for l in (0, 1)]
    force[[6 * t + 2 for t in tip]] = -0.25
    u = np.zeros(size)
    u[free] = np.linalg.solve(stiffness[free][:, free].toarray(), force[free])
    bernoulli = -length**3 / (3 * young / 12)
    # incompatible modes: within 0.5 % of the beam (shear adds ~0.25 %); plain trilinear ~ −30 %
    assert u[6 * tip[0] + 2] / bernoulli == pytest.approx(1.0, abs=5e-3)


def test_units_give_the_same_frequencies(tmp_path):
    si = read_nastran(_write(tmp_path, _cantilever(6, 1.0, 1.0)))
    mm = _cantilever(6, 1000.0, 1.0).replace("4.e-4,3.333333e-8,1.333333e-8,2.e-8",
                                             "400.,33333.33,13333.33,20000.")
    mm = mm.replace("2.1e11,,0.3,7800.", "2.1e5,,0.3,7.8e-9")
    path = tmp_path / "mm"
    path.mkdir()
    deck_mm = read_nastran(_write(path, mm), units="mm-t-s")
    f_si = _frequencies(assemble_deck(si), support_dofs(assemble_deck(si), si, 1), 4)
    system = assemble_deck(deck_mm)
    f_mm = _frequencies(system, support_dofs(system, deck_mm, 1), 4)
    assert np.allclose(f_mm, f_si, rtol=1e-6)


def hex20_deck(points, shape, counts, young, poisson, density, name, wrap_y=False):
    """A DeckModel of hex20 cells on a structured grid of points (shape = 2·counts + 1 nodes
    per axis, the second axis 2·counts when it wraps around, as a pipe's circumference)."""
    from sarfe.fe.solid_cells import _HEX_CORNERS, _HEX_EDGES
    from sarfe.mesh.formats.deck import DeckModel, SolidElements

    grid = np.arange(np.prod(shape)).reshape(shape)
    corners = (_HEX_CORNERS + 1).astype(int)
    local = np.vstack([corners, (corners[_HEX_EDGES[:, 0]] + corners[_HEX_EDGES[:, 1]]) // 2])
    i, j, k = (a.ravel() for a in np.meshgrid(*map(np.arange, counts), indexing="ij"))
    c = np.stack([2 * i, 2 * j, 2 * k], 1)[:, None, :] + local[None]
    cells = grid[c[..., 0], c[..., 1] % shape[1] if wrap_y else c[..., 1], c[..., 2]]
    used = np.unique(cells)
    remap = np.full(len(points), -1)
    remap[used] = np.arange(len(used))
    m = len(cells)
    block = SolidElements("hex20", np.arange(1, m + 1), np.ones(m, int), remap[cells],
                          np.full(m, young), np.full(m, poisson), np.full(m, density))
    return DeckModel(name, np.arange(1, len(used) + 1), points[used],
                     np.tile(np.eye(3), (len(used), 1, 1)), solids={"hex20": block})


def _hex20_plate(lx, ly, thickness, counts, young, poisson, density):
    """A DeckModel of a plate of hex20 cells (counts = cells along x, y, z)."""
    nx, ny, nz = counts
    x, y, z = np.meshgrid(np.linspace(0, lx, 2 * nx + 1), np.linspace(0, ly, 2 * ny + 1),
                          np.linspace(-thickness / 2, thickness / 2, 2 * nz + 1), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    return hex20_deck(points, x.shape, counts, young, poisson, density, "hex20 plate")


def _shell_plate(lx, ly, thickness, counts, young, poisson, density):
    from sarfe.mesh.laminate import isotropic_plane_stress
    from sarfe.mesh.formats.deck import DeckModel, ShellElements

    nx, ny = counts
    x, y = np.meshgrid(np.linspace(0, lx, nx + 1), np.linspace(0, ly, ny + 1), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    grid = np.arange(len(points)).reshape(nx + 1, ny + 1)
    a, b, c, d = (grid[:-1, :-1].ravel(), grid[1:, :-1].ravel(), grid[1:, 1:].ravel(),
                  grid[:-1, 1:].ravel())
    triangles = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    m = len(triangles)
    q = isotropic_plane_stress(young, poisson)
    shells = ShellElements(np.arange(1, m + 1), np.ones(m, int), triangles, np.arange(m),
                           np.tile(q * thickness, (m, 1, 1)), np.zeros((m, 3, 3)),
                           np.tile(q * thickness**3 / 12, (m, 1, 1)), np.zeros((m, 2, 2)),
                           np.tile([1.0, 0, 0], (m, 1)), np.full(m, density * thickness),
                           np.full(m, density * thickness**3 / 12), np.full(m, thickness),
                           np.zeros(m))
    return DeckModel("shell plate", np.arange(1, len(points) + 1), points,
                     np.tile(np.eye(3), (len(points), 1, 1)), shells=shells)


@pytest.mark.slow
@pytest.mark.parametrize("width_over_thickness, low, high", [(8, 0.005, 0.07), (100, -0.002, 0.003)])
def test_kirchhoff_shell_vs_3d_hex20_free_plate(width_over_thickness, low, high):
    """Transverse-shear measurement (docs/decks.md): free 2 × 1 plate (plate_py's material);
    converged DKT (80 × 40) vs 3D quadratic solid (40 × 20 × 2 hex20), modes 7–10."""
    from sarfe.fe.modes import natural_frequencies

    e, nu, rho = 2.9e7, 0.32, 7.3315e-4
    t = 1.0 / width_over_thickness
    shift = 1000.0 / width_over_thickness
    shell = assemble_deck(_shell_plate(2.0, 1.0, t, (80, 40), e, nu, rho), mass="consistent")
    solid = assemble_deck(_hex20_plate(2.0, 1.0, t, (40, 20, 2), e, nu, rho), mass="consistent")
    f_shell = natural_frequencies(shell.stiffness, shell.mass, count=10, shift_hz=shift)[6:]
    f_solid = natural_frequencies(solid.stiffness, solid.mass, count=10, shift_hz=shift)[6:]
    ratio = f_shell / f_solid - 1
    assert np.all(ratio > low) and np.all(ratio < high), ratio


@needs_decks
def test_hex20_plate_matches_the_commercial_solvers_thick_plate():
    """plate_py's 2 × 1 × 0.125 plate as 20 × 10 × 2 hex20 (3D elasticity, shear included)
    reproduces the commercial solver's (Mindlin shell) free-free frequencies to 0.5 %."""
    from sarfe.fe.modes import natural_frequencies

    reference = json.loads((DECKS / "REFERENCE.json").read_text())
    expected = np.array(reference["plate_py.dat"]["frequencies_hz"][6:10])
    deck = read_nastran(DECKS / "plate_py.dat")
    q = deck.shells.membrane[0] / 0.125
    poisson = q[0, 1] / q[0, 0]
    young = q[0, 0] * (1 - poisson**2)
    system = assemble_deck(_hex20_plate(2.0, 1.0, 0.125, (20, 10, 2), young, poisson,
                                        deck.shells.mass_per_area[0] / 0.125), mass="consistent")
    hz = natural_frequencies(system.stiffness, system.mass, count=10, shift_hz=100.0)[6:]
    assert np.allclose(hz, expected, rtol=5e-3), hz / expected


@pytest.mark.parametrize("text, needle", [
    ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,2.,0.,0.\nCTRIA3,7,1,1,2,3\n"
     "PSHELL,1,1,0.01,1\nMAT1,1,7.e10,,0.3,2700.", "shell element 7 has zero area"),
    ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nCBAR,8,1,1,2,1.,0.,0.\n"
     "PBAR,1,1,1.e-4,1.e-9,1.e-9,1.e-9\nMAT1,1,7.e10,,0.3,2700.", "CBAR 8: orientation"),
    ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,-1.\n"
     "CTETRA,9,1,1,2,3,4\nCTETRA,10,1,1,3,2,4\nPSOLID,1,1\nMAT1,1,7.e10,,0.3,2700.", "solid element"),
])
def test_degenerate_elements_name_their_id(tmp_path, text, needle):
    deck = read_nastran(_write(tmp_path, text))
    if "CTETRA" in text:  # both orientations of one tet are fine (|det J|)
        assert assemble_deck(deck).n_dofs > 0
        return
    with pytest.raises(DeckError, match=needle):
        assemble_deck(deck)


def test_cylindrical_cd_frame_for_supports_and_loads(tmp_path):
    # node 2 on the y axis with CD = cylindrical system 5: its component 1 is radial = +y
    deck = read_nastran(_write(tmp_path, """
CORD2C,5,,0.,0.,0.,0.,0.,1.
,1.,0.,0.
GRID,1,,0.,0.,0.
GRID,2,,0.,1.,0.,5
CELAS2,1,1000.,2,1
CELAS2,2,1000.,2,2
CELAS2,3,1000.,2,3
SPC1,2,1,2
FORCE,3,2,,1.,0.,2.,0.
"""))
    assert np.allclose(deck.displacement_frames[1], [[0, 1, 0], [-1, 0, 0], [0, 0, 1]], atol=1e-12)
    system = assemble_deck(deck)
    radial = system.dof_index(1, 0)
    assert radial in support_dofs(system, deck, 2)
    load = load_vector(system, deck, 3)
    assert load[radial] == pytest.approx(2.0)  # global +y force is radial at θ = 90°
    assert load[system.dof_index(1, 1)] == pytest.approx(0.0, abs=1e-12)


def test_two_offset_shells_equal_one_of_double_thickness(tmp_path):
    """ZOFFS = ±t/2 on two coincident PSHELLs of thickness t sharing the nodes: stiffness and
    mass equal one shell of thickness 2t (parallel axes: 2 (t³/12 + t (t/2)²) = (2t)³/12)."""
    grids = "GRID,1,,0.,0.,0.\nGRID,2,,0.3,0.05,0.\nGRID,3,,0.25,0.2,0.01\nGRID,4,,0.,0.22,0.\n"
    material = "MAT1,1,2.e9,,0.35,1100.\n"
    two = read_nastran(_write(tmp_path, grids + material + "PSHELL,1,1,0.002,1\n"
                              "CQUAD4,1,1,1,2,3,4,,0.001\nCQUAD4,2,1,1,2,3,4,,-0.001"))
    (tmp_path / "one").mkdir()
    one = read_nastran(_write(tmp_path / "one", grids + material + "PSHELL,1,1,0.004,1\n"
                              "CQUAD4,1,1,1,2,3,4"))
    k2, m2 = global_matrices(two)
    k1, m1 = global_matrices(one)
    assert np.abs((k2 - k1).toarray()).max() < 1e-9 * np.abs(k1.toarray()).max()
    assert np.abs((m2 - m1).toarray()).max() < 1e-12 * np.abs(m1.toarray()).max()
    # one offset shell alone: its membrane–bending coupling is B = o A, mass first moment ρ t o
    single = read_nastran(_write(tmp_path / "one", grids + material + "PSHELL,1,1,0.002,1\n"
                                 "CQUAD4,1,1,1,2,3,4,,0.001"))
    assert np.allclose(single.shells.coupling, 0.001 * single.shells.membrane)


def test_rbe3_reference_follows_the_weighted_mean_motion(tmp_path):
    """Four independent nodes at the corners of a square around the reference (translations,
    weights 1, 1, 3, 3): reference translation = Σ w u / Σ w for a uniform-plus-antisymmetric
    field, reference rotation = the least-squares rotation of a pure rigid rotation."""
    deck = read_nastran(_write(tmp_path, """
GRID,1,,-1.,-1.,0.
GRID,2,,1.,-1.,0.
GRID,3,,1.,1.,0.
GRID,4,,-1.,1.,0.
GRID,5,,0.,0.,0.
RBE3,7,,5,123456,1.,123,1,2
,3.,123,3,4
"""))
    system = assemble_deck(deck, mass="consistent")
    # (no elements: every DOF is held for lack of stiffness, so probe C directly)
    from sarfe.fe.constraints import constraint_matrix

    c_matrix, independent = constraint_matrix(deck.points, deck.rbe2, deck.rbe3, deck.n_nodes)
    assert len(system.dof_nodes) == 0
    u_ind = np.zeros((5, 6))
    u_ind[:4, 2] = [1.0, 2.0, 3.0, 4.0]  # uz of the corners
    full = c_matrix @ u_ind.ravel()[independent]
    weights = np.array([1.0, 1.0, 3.0, 3.0])
    # weighted least squares of uz = w_r + θx y − θy x over the corners
    x, y = deck.points[:4, 0], deck.points[:4, 1]
    design = np.column_stack([np.ones(4), y, -x])
    fit = np.linalg.solve(design.T @ (weights[:, None] * design), design.T @ (weights * u_ind[:4, 2]))
    assert np.allclose(full.reshape(5, 6)[4, [2, 3, 4]], fit)
    rigid = np.zeros((5, 6))
    rotation = np.array([0.01, -0.02, 0.03])
    rigid[:4, :3] = np.cross(rotation, deck.points[:4])
    full = (c_matrix @ rigid.ravel()[independent]).reshape(5, 6)
    assert np.allclose(full[4, 3:], rotation) and np.allclose(full[4, :3], 0, atol=1e-15)


def test_material_axis_rotation_equals_swapped_orthotropic_material(tmp_path):
    """MAT8 (E1, E2) with THETA = 90° gives the same K as MAT8 (E2, E1) with THETA = 0."""
    def deck(folder, theta, e1, e2, nu12):
        (tmp_path / folder).mkdir()
        return read_nastran(_write(tmp_path / folder, f"""
GRID,1,,0.,0.,0.
GRID,2,,0.4,0.,0.
GRID,3,,0.4,0.3,0.
GRID,4,,0.,0.3,0.
CQUAD4,1,1,1,2,3,4,{theta}
MAT8,1,{e1},{e2},{nu12},4.e9,,,1500.
PCOMP,1
,1,0.002,0.
"""))
    a = deck("a", "90.", "1.2e11", "9.e9", "0.3")
    b = deck("b", "0.", "9.e9", "1.2e11", f"{0.3 * 9e9 / 1.2e11:.12f}")
    k_a, _ = global_matrices(a)
    k_b, _ = global_matrices(b)
    assert np.abs((k_a - k_b).toarray()).max() < 1e-9 * np.abs(k_a.toarray()).max()


@pytest.mark.filterwarnings("ignore:CONM2.*inertia method:UserWarning")  # pyNastran's own inertia
def test_point_masses_and_offsets_equal_pynastran_mass_properties(tmp_path):
    from pyNastran.bdf.mesh_utils.mass_properties import mass_properties as pyn_mass

    from sarfe.fe.deck_assembly import mass_properties
    from sarfe.mesh.formats.nastran_bdf import load_bdf

    path = _write(tmp_path, _free_plate_with_rigid_elements() + """
CORD2R,4,,0.1,0.,0.,0.1,0.,1.
,1.,1.,0.
CONM2,904,3,4,0.03,0.01,0.02,0.03
CONM2,905,7,-1,0.04,0.5,0.5,0.5
""")
    mass, cg = mass_properties(read_nastran(path))
    ref_mass, ref_cg, _ = pyn_mass(load_bdf(path))
    assert mass == pytest.approx(float(ref_mass), rel=1e-9)
    assert np.allclose(cg, ref_cg, atol=1e-9)


def test_chained_rigid_elements_resolve_and_circular_ones_are_refused(tmp_path):
    from sarfe.fe.constraints import constraint_matrix

    base = "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,1.,2.,0.\n"
    deck = read_nastran(_write(tmp_path, base + "RBE2,10,1,123456,2\nRBE2,11,2,123456,3\n"))
    c_matrix, independent = constraint_matrix(deck.points, deck.rbe2, deck.rbe3, 3)
    assert independent.tolist() == list(range(6))  # node 1 carries everything
    rotation = np.array([0.0, 0.0, 0.01])
    u = (c_matrix @ np.r_[np.zeros(3), rotation]).reshape(3, 6)
    assert np.allclose(u[2, :3], np.cross(rotation, deck.points[2]))
    (tmp_path / "loop").mkdir()
    loop = read_nastran(_write(tmp_path / "loop", base + "RBE2,10,1,123456,2\nRBE2,11,2,123456,1\n"))
    with pytest.raises(DeckError, match="rigid"):
        assemble_deck(loop)


def test_chexa20_cantilever_read_from_a_deck(tmp_path):
    """CHEXA (20 nodes, Nastran's midside order) written from a structured grid and read
    back: the tip deflection of a 10 × 1 × 1 cantilever equals Euler–Bernoulli + shear."""
    model = _hex20_plate(10.0, 1.0, 1.0, (10, 1, 1), 1e3, 0.0, 1.0)
    block = model.solids["hex20"]
    lines = [f"GRID,{i + 1},,{x:.6f},{y:.6f},{z:.6f}" for i, (x, y, z) in enumerate(model.points)]
    for eid, cell in zip(block.element_ids, block.connectivity + 1):
        fields = [str(n) for n in cell]
        lines.append(f"CHEXA,{eid},1," + ",".join(fields[:6]))
        lines.append("," + ",".join(fields[6:14]))
        lines.append("," + ",".join(fields[14:]))
    root = np.flatnonzero(np.isclose(model.points[:, 0], 0.0)) + 1
    tip = np.flatnonzero(np.isclose(model.points[:, 0], 10.0)) + 1
    lines += ["PSOLID,1,1", "MAT1,1,1000.,,0.,1."]
    lines += [f"SPC1,1,123,{n}" for n in root]
    deck = read_nastran(_write(tmp_path, "\n".join(lines)))
    assert len(deck.solids["hex20"].element_ids) == 10
    system = assemble_deck(deck)
    fixed = support_dofs(system, deck, 1)
    free = np.setdiff1d(np.arange(system.n_dofs), fixed)
    force = np.zeros((deck.n_nodes, 6))
    force[deck.node_index(tip), 2] = -1.0 / len(tip)
    q = np.zeros(system.n_dofs)
    q[free] = np.linalg.solve(system.stiffness[free][:, free].toarray(),
                              (system.transformation.T @ force.ravel())[free])
    w = system.displacement(q)[deck.node_index(tip), 2].mean()
    bending = 10.0**3 / (3 * 1e3 / 12)
    shear = 10.0 / (5 / 6 * 500.0)
    assert -w == pytest.approx(bending + shear, rel=0.01)
