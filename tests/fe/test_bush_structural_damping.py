"""Structural damping GE of CBUSH/PBUSH and CELAS springs (Nastran reader → deck assembly → HBM).

Closed form: a mass m on a spring k with hysteretic damping i·GE·k, driven by F cos ωt, has
|u| = F / |k − mω² + i·GE·k|, so at ω = ω_n = √(k/m) the amplitude is F/(k·GE). With PARAM,W4 = ω_n
Nastran's transient rule B = GE·k/W4 gives the same force i ω B = i GE k at resonance, so the
harmonic balance on the assembled deck must reproduce F/(k·GE) there.
"""
import numpy as np
import pytest

from sarfe.fe.deck_assembly import assemble_deck, support_dofs
from sarfe.mesh.formats.nastran import read_nastran

K_N_M, MASS_KG, GE, FORCE_N = 4.0e5, 2.5, 0.06, 3.0
OMEGA_N = np.sqrt(K_N_M / MASS_KG)


def _deck(tmp_path, spring, w4=None, units_scale=1.0, extra=""):
    """GRID 2 (mass m, CONM2) on a spring to the held GRID 1 along z; units_scale = deck length
    unit in m (1e-3: mm-t-s, where k is N/mm and m is t)."""
    k = f"{K_N_M * units_scale:.10e}"      # N/m → N/mm; Nastran reals need the exponent or a '.'
    m = f"{MASS_KG / 1000.0 if units_scale != 1.0 else MASS_KG:.10e}"
    cards = {"CBUSH": f"CBUSH,1,7,1,2,,,,0\nPBUSH,7,K,{k},{k},{k},1.,1.,1.\n,,GE,{GE}",
             "CELAS1": f"CELAS1,1,7,2,3,1,3\nPELAS,7,{k},{GE}",
             "CELAS2": f"CELAS2,1,{k},2,3,1,3,{GE}"}[spring]
    text = (f"GRID,1,,0.,0.,0.\nGRID,2,,0.,0.,0.\n{cards}\nCONM2,2,2,,{m}\n"
            "SPC1,1,123456,1\nSPC1,1,12456,2\n"
            + (f"PARAM,W4,{w4:.12e}\n" if w4 is not None else "") + extra)
    path = tmp_path / "bush.bdf"
    path.write_text("BEGIN BULK\n" + text + "ENDDATA\n")
    return path


def _free_uz(system, deck):
    fixed = support_dofs(system, deck, 1)
    free = np.setdiff1d(np.arange(system.n_dofs), fixed)
    z = int(system.dof_index(1, 2))
    assert list(free) == [z]                 # the model is the 1-DOF oscillator of GRID 2, uz
    return z


@pytest.mark.parametrize("spring", ["CBUSH", "CELAS1", "CELAS2"])
def test_w4_turns_ge_into_viscous_damping_with_the_hysteretic_resonance_amplitude(tmp_path, spring):
    """B = GE·k/W4 on uz; harmonic balance (a contact that never closes, H = 3) at ω = W4 = ω_n
    gives |u| = F/(k·GE) within 1e-9 and no higher harmonics; the note names PARAM,W4."""
    from sarfe.hbm import make_contact_set, make_linear_model, solve_frequency

    deck = read_nastran(_deck(tmp_path, spring, w4=OMEGA_N))
    assert any("PARAM,W4" in note and "1 spring" in note for note in deck.notes)
    assert not np.any(deck.springs.structural_damping)
    system = assemble_deck(deck)
    z = _free_uz(system, deck)
    assert system.viscous_damping[z, z] == pytest.approx(GE * K_N_M / OMEGA_N, rel=1e-12)
    model = make_linear_model(*(a[[z]][:, [z]].toarray() for a in (
        system.mass, system.viscous_damping, system.stiffness)))
    far = make_contact_set(np.ones((1, 1)), ["rattle"], [0], [[-1, -1]], [1.0],
                           normal_stiffness=[1.0])
    harmonics = 3
    excitation = np.zeros((2 * harmonics + 1, 1))
    excitation[1, 0] = FORCE_N
    solution = solve_frequency(model, far, excitation, OMEGA_N, harmonics, 32)
    assert solution.converged
    amplitude = np.hypot(*solution.displacement[1:3, 0])
    assert amplitude == pytest.approx(FORCE_N / (K_N_M * GE), rel=1e-9)
    assert np.abs(solution.displacement[3:, 0]).max() < 1e-12 * amplitude
    # phase: at resonance the response lags the force by 90° (pure sine term)
    assert abs(solution.displacement[1, 0]) < 1e-9 * amplitude


def test_w4_conversion_follows_the_deck_units(tmp_path):
    """mm-t-s deck: k in N/mm, W4 in rad/s → B in N·s/mm, converted to SI: GE·k/W4 [N·s/m]."""
    deck = read_nastran(_deck(tmp_path, "CBUSH", w4=OMEGA_N, units_scale=1e-3), "mm-t-s")
    system = assemble_deck(deck)
    z = _free_uz(system, deck)
    assert system.stiffness[z, z] == pytest.approx(K_N_M, rel=1e-12)
    assert system.viscous_damping[z, z] == pytest.approx(GE * K_N_M / OMEGA_N, rel=1e-12)


def test_without_w4_ge_stays_hysteretic_and_material_damping_is_noted(tmp_path):
    """No PARAM,W4: structural_damping = GE·K, no viscous part (the pipeline refuses it);
    MAT1 GE and PARAM,G, which sarfe does not apply, are listed in the deck's notes."""
    extra = "MAT1,5,2.e11,,0.3,7800.,,,0.02\nPARAM,G,0.03\n"
    deck = read_nastran(_deck(tmp_path, "CBUSH", extra=extra))
    system = assemble_deck(deck)
    z = _free_uz(system, deck)
    assert system.structural_damping[z, z] == pytest.approx(GE * K_N_M, rel=1e-12)
    assert system.viscous_damping.nnz == 0 or not np.any(system.viscous_damping.data)
    assert any("material GE of MAT 5 not applied" in note for note in deck.notes)
    assert any("PARAM,G,0.03 not applied" in note for note in deck.notes)
