"""Shell decks vs the commercial solver's stored results (issue 32): the public decks of
../shared/decks with the deck defaults (lumped mass unless PARAM,COUPMASS > 0; incompatible-mode
quads, constant-strain triangles and the K6ROT drilling penalty; DKMT where MID3 is given)."""
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse.linalg as sla

from sarfe.fe.deck_assembly import (assemble_deck, global_matrices, load_vector, mass_properties,
                                    support_dofs)
from sarfe.mesh.formats.nastran import read_nastran
from tests.mesh.test_public_decks import deck_frequencies

HERE = Path(__file__).resolve()
# beside the checkout (CI), or beside the folder of worktrees (/work/wt/<name> → /work/shared)
DECKS = next((root / "shared" / "decks" for root in HERE.parents[3:5]
              if (root / "shared" / "decks").is_dir()), HERE.parents[3] / "shared" / "decks")
needs_decks = pytest.mark.skipif(not (DECKS / "REFERENCE.json").is_file(),
                                 reason=f"public decks folder {DECKS} is absent")


def _reference(name):
    return np.array(json.loads((DECKS / "REFERENCE.json").read_text())[name]["frequencies_hz"])


_frequencies = deck_frequencies   # lowest natural frequencies of a deck (M may be singular)


@needs_decks
def test_mode_solid_shell_bar_first_three_modes_within_1_percent():
    """MSC Nastran SOL 103, default lumped mass; measured +0.44, +0.12, −0.71 % (before issue
    32: +1.6, −1.3, +1.6 % lumped, +3.7, +0.8, +16 % with the then default consistent mass)."""
    deck = read_nastran(DECKS / "mode_solid_shell_bar.bdf")
    system = assemble_deck(deck)
    hz = _frequencies(system, support_dofs(system, deck, 2), 3)
    ratio = hz / _reference("mode_solid_shell_bar.bdf") - 1
    assert np.all(np.abs(ratio) < 0.01), ratio


@needs_decks
def test_plate_py_thick_free_plate_within_2_percent():
    """NX Nastran, 20 × 10 CQUAD4 of a 2 × 1 × 0.125 plate with MID3 (Mindlin), free-free:
    six rigid modes, then the four stored modes. Measured −1.27, +1.02, +0.64, −1.68 %
    (before: +0.5 … +5.6 %, no transverse shear). 1 % is out of a Mindlin shell's reach here
    (test_plate_py_converged_mindlin_misses_1_percent): the converged Mindlin plate (k = 5/6,
    80 × 40) is −0.99, +1.07, +0.71, −1.16 % off the stored modes (with its rotary inertia, the
    lumped mass; without: −0.21, +1.97, +2.04, +0.48 %), and the stored modes lie within 0.5 %
    of 3D elasticity (hex20): NX's 20 × 10 answer carries a mesh-level deviation from Mindlin
    theory towards 3D that only its own element would reproduce."""
    deck = read_nastran(DECKS / "plate_py.dat")
    hz = _frequencies(assemble_deck(deck), (), 10)
    assert np.all(hz[:6] < 1e-3 * hz[6])
    ratio = hz[6:] / _reference("plate_py.dat")[6:10] - 1
    assert np.all(np.abs(ratio) < 0.02), ratio


@pytest.mark.slow
@needs_decks
def test_plate_py_converged_mindlin_misses_1_percent(tmp_path):
    """plate_py's plate, section and material on 80 × 40 CQUAD4 (deck defaults): the converged
    Mindlin answer (the DKMT converges to Mindlin theory, test_deck_assembly) is more than 1 %
    from the stored modes on two of four (measured −0.99, +1.07, +0.71, −1.16 %), and the deck's
    own 20 × 10 mesh is within 0.6 % of it (−0.28, −0.05, −0.07, −0.53 %): no Mindlin shell
    reaches the 1 % target on this deck except by a mesh error of its own."""
    cards = [line for line in (DECKS / "plate_py.dat").read_text().splitlines()
             if line.startswith(("PSHELL", "MAT1", "+ "))]
    nx, ny = 80, 40
    grids = [f"GRID,{j * (nx + 1) + i + 1},,{2.0 * i / nx:.8f},{1.0 * j / ny:.8f},0."
             for j in range(ny + 1) for i in range(nx + 1)]
    quads = [f"CQUAD4,{j * nx + i + 1},1,{j * (nx + 1) + i + 1},{j * (nx + 1) + i + 2},"
             f"{(j + 1) * (nx + 1) + i + 2},{(j + 1) * (nx + 1) + i + 1}"
             for j in range(ny) for i in range(nx)]
    fine = read_nastran(_write(tmp_path, "\n".join(cards + grids + quads)))
    system = assemble_deck(fine)
    reference = _reference("plate_py.dat")[6:10]
    values = sla.eigsh(system.stiffness.tocsc(), M=system.mass.tocsc(), k=10, sigma=-1e3,
                       which="LM", return_eigenvectors=False)
    converged = np.sqrt(np.sort(np.abs(values)))[6:] / (2 * np.pi)
    coarse = _frequencies(assemble_deck(read_nastran(DECKS / "plate_py.dat")), (), 10)[6:]
    errors = converged / reference - 1
    assert np.sum(np.abs(errors) > 0.01) >= 2 and np.all(np.abs(errors) < 0.013), errors
    assert np.all(np.abs(coarse / converged - 1) < 0.006), coarse / converged - 1


@needs_decks
def test_plate_bdf_static_membrane_matches_the_stored_displacements():
    """Patran/MSC SOL 101 of plate.bdf (5 × 5 CQUAD4 in tension, one edge clamped; stored
    displacements from plate.op2, tests/fe/data): the quad membrane reproduces every in-plane
    displacement to 1e-4 of the largest (the two-triangle Allman membrane was 15 % off)."""
    stored = json.loads((HERE.parent / "data" / "plate_op2_displacements.json").read_text())
    table = np.array(stored["displacements"])
    deck = read_nastran(DECKS / "plate.bdf")
    system = assemble_deck(deck)
    fixed = support_dofs(system, deck, 2)
    free = np.setdiff1d(np.arange(system.n_dofs), fixed)
    q = np.zeros(system.n_dofs)
    q[free] = sla.spsolve(system.stiffness[free][:, free].tocsc(),
                          load_vector(system, deck, 2)[free])
    u = system.displacement(q)[deck.node_index(table[:, 0].astype(int))]
    error = np.abs(u[:, :3] - table[:, 1:4]).max() / np.abs(table[:, 1:4]).max()
    assert error < 1e-4, error


@needs_decks
@pytest.mark.parametrize("name", ["plate_py.dat", "mode_solid_shell_bar.bdf", "a101x.dat",
                                  "plate.bdf"])
def test_lumped_mass_keeps_the_consistent_total(name):
    """Translational lumped mass r_cᵀ M r_c equals the consistent one to 1e-12 in x, y, z."""
    deck = read_nastran(DECKS / name)
    _, lumped = global_matrices(deck, mass="lumped")
    _, consistent = global_matrices(deck, mass="consistent")
    for c in range(3):
        rigid = np.zeros((deck.n_nodes, 6))
        rigid[:, c] = 1.0
        rigid = rigid.ravel()
        total = rigid @ consistent @ rigid
        assert rigid @ lumped @ rigid == pytest.approx(total, rel=1e-12, abs=1e-300)
    assert mass_properties(deck, "lumped")[0] == pytest.approx(mass_properties(deck)[0],
                                                               rel=1e-12, abs=1e-300)


@needs_decks
def test_lumped_mass_equals_pynastrans_mass_properties():
    from pyNastran.bdf.bdf import read_bdf
    from pyNastran.bdf.mesh_utils.mass_properties import mass_properties as pyn_mass

    if not hasattr(np, "in1d"):  # pyNastran 1.4 calls np.in1d, removed in NumPy 2.4
        np.in1d = np.isin
    for name in ("plate_py.dat", "mode_solid_shell_bar.bdf"):
        deck = read_nastran(DECKS / name)
        mass, cg = mass_properties(deck, "lumped")
        expected, expected_cg, _ = pyn_mass(read_bdf(DECKS / name, debug=None))
        assert mass == pytest.approx(float(expected), rel=1e-6)
        assert np.allclose(cg, expected_cg, rtol=0, atol=1e-6 * np.ptp(deck.points, axis=0).max())


def _write(tmp_path, text):
    path = tmp_path / "deck.bdf"
    path.write_text("BEGIN BULK\n" + text.strip() + "\nENDDATA\n")
    return path


def _square(params=""):
    grids = "\n".join(f"GRID,{j * 3 + i + 1},,{0.1 * i},{0.1 * j},0." for j in range(3)
                      for i in range(3))
    quads = "\n".join(f"CQUAD4,{j * 2 + i + 1},1,{j * 3 + i + 1},{j * 3 + i + 2},"
                      f"{j * 3 + i + 5},{j * 3 + i + 4}" for j in range(2) for i in range(2))
    return f"{params}\n{grids}\n{quads}\nPSHELL,1,1,0.003,1,,1\nMAT1,1,2.e9,,0.35,1100."


def test_coupmass_selects_the_consistent_mass_and_k6rot_the_drilling_penalty(tmp_path):
    default = read_nastran(_write(tmp_path, _square()))
    assert not default.coupled_mass and default.drilling_penalty == pytest.approx(1e-4)
    coupled = read_nastran(_write(tmp_path, _square("PARAM,COUPMASS,1\nPARAM,K6ROT,10.")))
    assert coupled.coupled_mass and coupled.drilling_penalty == pytest.approx(1e-5)
    m_default = assemble_deck(default).mass
    assert abs(m_default - assemble_deck(default, mass="lumped").mass).max() == 0.0
    assert abs(assemble_deck(coupled).mass
               - assemble_deck(coupled, mass="consistent").mass).max() == 0.0
    # K6ROT = 0: no drilling stiffness, the normal rotations are held (Nastran's AUTOSPC)
    free = read_nastran(_write(tmp_path, _square("PARAM,K6ROT,0.")))
    held = assemble_deck(free)
    assert np.all(held.auto_held_components == 5) and len(held.auto_held_nodes) == 9


def test_free_warped_quad_patch_has_exactly_six_rigid_modes(tmp_path):
    """A warped, skewed CQUAD4 patch (quad membrane + DKMT facets + drilling penalty) on its
    own: K has exactly six zero eigenvalues and K·(rigid motion) = 0."""
    text = _square()
    rng = np.random.default_rng(4)
    lines = []
    for line in text.splitlines():
        if line.startswith("GRID"):
            f = line.split(",")
            x, y = float(f[3]) + 0.02 * rng.uniform(-1, 1), float(f[4]) + 0.02 * rng.uniform(-1, 1)
            z = 0.01 * rng.uniform(-1, 1) + 0.3 * x * y
            line = f"GRID,{f[1]},,{x:.6f},{y:.6f},{z:.6f}"
        lines.append(line)
    deck = read_nastran(_write(tmp_path, "\n".join(lines)))
    k, _ = global_matrices(deck)
    k = k.toarray()
    rigid = np.zeros((deck.n_nodes, 6, 6))
    for c in range(3):
        rigid[:, c, c] = 1.0
        rigid[:, :3, 3 + c] = np.cross(np.eye(3)[c], deck.points)
        rigid[:, 3 + c, 3 + c] = 1.0
    rigid = rigid.reshape(-1, 6)
    assert np.abs(k @ rigid).max() < 1e-10 * np.abs(k).max() * np.abs(rigid).max()
    eigenvalues = np.linalg.eigvalsh(k)
    assert np.sum(eigenvalues < 1e-12 * eigenvalues.max()) == 6
