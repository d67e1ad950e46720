"""Public decks of pyNastran's models/ and the CalculiX test suite read as they are, against the
stored frequencies of the solver that ran them (tests/data/decks: SOURCE.md, REFERENCE.json) —
issue 32.

Each deck reads without edits (its unsupported cards are exactly the analysis-only ones the
case would list in ``ignore_cards``) or is refused with one line; read decks match the stored
frequencies within 1 % (the first six elastic modes, as many as stored) with the deck's default
mass (lumped, as the commercial solver), and the mass equals pyNastran's mass properties
(an independent implementation) within 1e-6.
"""
import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as la
from scipy.optimize import brentq

from sarfe.fe.deck_assembly import assemble_deck, mass_properties, support_dofs
from sarfe.mesh.formats.abaqus import read_abaqus
from sarfe.mesh.formats.deck import DeckError
from sarfe.mesh.formats.nastran import nastran_deck
from tests.fe.test_deck_assembly import hex20_deck

DECKS = Path(__file__).resolve().parents[1] / "data" / "decks"
REFERENCE = json.loads((DECKS / "REFERENCE.json").read_text())
DECK_SPECS = {name: spec for name, spec in REFERENCE.items() if isinstance(spec, dict)}
READ = [name for name, spec in DECK_SPECS.items()
        if "frequencies_hz" in spec and "refused_cards" not in spec and not name.endswith(".inp")]
REFUSED = [name for name, spec in DECK_SPECS.items() if "refused" in spec]
REFUSED_CARDS = [name for name, spec in DECK_SPECS.items() if "refused_cards" in spec]


def deck_frequencies(system, fixed, count):
    """Lowest natural frequencies [Hz] of K, M without the ``fixed`` DOFs; M may be singular
    (massless drilling rotations, lumped beams): M x = μ (K + s M) x, λ = 1/μ − s."""
    free = np.setdiff1d(np.arange(system.n_dofs), np.asarray(fixed, int))
    k = system.stiffness[free][:, free].toarray()
    m = system.mass[free][:, free].toarray()
    shift = 1e-3 * np.abs(np.diag(k)).max() / np.abs(np.diag(m)).max()
    mu = np.sort(la.eigh(m, k + shift * m, eigvals_only=True))[::-1][:count]
    return np.sqrt(np.abs(1.0 / mu - shift)) / (2 * np.pi)


def public_deck_errors(name):
    """(relative errors of the first ≤ 6 elastic modes, relative mass error vs pyNastran,
    the deck) of a deck of REFERENCE.json."""
    from pyNastran.bdf.bdf import read_bdf
    from pyNastran.bdf.mesh_utils.mass_properties import mass_properties as pyn_mass

    spec = REFERENCE[name]
    deck = nastran_deck(DECKS / name)
    system = assemble_deck(deck)
    reference = np.array(spec["frequencies_hz"])[:6]
    skip = spec["rigid_modes"]
    hz = deck_frequencies(system, support_dofs(system, deck, spec["support_set"]),
                          skip + len(reference))[skip:]
    model = read_bdf(str(DECKS / name), debug=None, xref=True)
    wtmass = model.params["WTMASS"].values[0] if "WTMASS" in model.params else 1.0
    expected = pyn_mass(model)[0] * wtmass
    mass = mass_properties(deck)[0]
    return hz / reference - 1, mass / expected - 1, deck


@pytest.mark.parametrize("name", READ)
def test_public_deck_modes_within_1_percent_and_mass_within_1e_6(name):
    if not hasattr(np, "in1d"):
        np.in1d = np.isin
    errors, mass_error, deck = public_deck_errors(name)
    assert sorted(deck.unsupported) == sorted(REFERENCE[name]["ignore_cards"])
    assert np.all(np.abs(errors) < 0.01), errors
    assert abs(mass_error) < 1e-6, mass_error


@pytest.mark.parametrize("name", REFUSED)
def test_public_deck_refused_with_one_line(name):
    with pytest.raises(DeckError) as info:
        nastran_deck(DECKS / name)
    message = str(info.value)
    assert "\n" not in message and name in message
    assert REFERENCE[name]["refused"] in message


@pytest.mark.parametrize("name", REFUSED_CARDS)
def test_public_deck_refusal_lists_every_missing_card_type(name, tmp_path):
    """A case on the deck is refused at validate with one line naming every card type the
    reader lacks, with its count and first line (not the first one alone)."""
    from sarfe.case.errors import CaseError
    from sarfe.pipeline import check_mesh, load_case

    data = {"name": "public", "model": {"fe": {"deck": str(DECKS / name), "units": "mm-t-s"}},
            "excitation": {"base_acceleration": {"direction": "z", "amplitude_m_s2": 1.0},
                           "frequency_hz": [100.0]}}
    with pytest.raises(CaseError) as info:
        check_mesh(load_case(data, base_dir=tmp_path))
    message = str(info.value)
    expected = REFERENCE[name]["refused_cards"]
    assert "\n" not in message and f"{len(expected)} card types sarfe does not model" in message
    for card, count in expected.items():
        assert f"{card} ({count}, first at {DECKS / name}:" in message


def cantilever_timoshenko_hz(young, shear_modulus, density, area, inertia, shear_factor, length,
                             count, rotary_inertia=True):
    """Lowest ``count`` bending frequencies [Hz] of a clamped-free Timoshenko beam: the roots b
    of Huang's (1961) frequency equation
        2 + [b²(r² − s²)² + 2] cosh(bα) cos(bβ) − b (r² + s²)/√(1 − b² r² s²) sinh(bα) sin(bβ) = 0,
    α, β = √((∓(r² + s²) + √((r² − s²)² + 4/b²))/2), r² = I/(A L²) (rotary inertia, 0 without),
    s² = E I/(k A G L²), ω = b √(E I/(ρ A L⁴)). r = s = 0 is Euler–Bernoulli's cos·cosh = −1."""
    r2 = inertia / (area * length**2) if rotary_inertia else 0.0
    s2 = young * inertia / (shear_factor * area * shear_modulus * length**2)

    def equation(b):     # divided by cosh(bα), so that it stays finite
        root = np.sqrt((r2 - s2) ** 2 + 4.0 / b**2)
        alpha, beta = np.sqrt((root - r2 - s2) / 2), np.sqrt((root + r2 + s2) / 2)
        return (2.0 / np.cosh(b * alpha) + (b**2 * (r2 - s2) ** 2 + 2) * np.cos(b * beta)
                - b * (r2 + s2) / np.sqrt(1 - b**2 * r2 * s2) * np.tanh(b * alpha) * np.sin(b * beta))

    grid = np.linspace(0.5, 20.0 * count**2, 4000 * count)       # b ≈ λ², λ_n ≈ (n − ½) π
    values = equation(grid)
    change = np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))[:count]
    roots = np.array([brentq(equation, grid[i], grid[i + 1]) for i in change])
    return roots * np.sqrt(young * inertia / (density * area * length**4)) / (2 * np.pi)


def test_calculix_pipe_beam_deck_reads_and_matches_beam_theory():
    """CalculiX's simplebeampipe3.inp (10 B32R, PIPE R = 0.11, t = 0.01, L = 10) read unedited,
    with CalculiX's consistent mass: mass = ρ π (R² − r²) L to 1e-12; the six bending modes
    equal Huang's Timoshenko closed form (Cowper's k, no rotary inertia, as sarfe's beam) to
    1e-4 — the deck is read as the beam it describes. Against CalculiX's stored modes:
    −0.79, −0.79, −0.89, −0.89, −1.11, −1.11 %: the 1 % target is missed on the third pair
    because CalculiX's expanded B32R (a C3D20R with eight integration points on the wall) is
    stiffer than the pipe — 0.71, 0.89, 1.21 % above its 3D elasticity
    (test_calculix_pipe_deck_vs_converged_3d_elasticity), 0.80, 0.98, 1.32 % above the closed
    form with rotary inertia, 0.73, 0.46, 0.09 % above Euler–Bernoulli (REFERENCE.json note)."""
    name = "simplebeampipe3.inp"
    spec = REFERENCE[name]
    deck = read_abaqus(DECKS / name)
    assert deck.unsupported == {} and len(deck.beams.card) == 20       # B32R: two beams each
    outer, wall, length, young, nu, rho = 0.11, 0.01, 10.0, 1e7, 0.3, 7.8e-9
    inner = outer - wall
    area, inertia = np.pi * (outer**2 - inner**2), np.pi * (outer**4 - inner**4) / 4
    assert mass_properties(deck)[0] == pytest.approx(rho * area * length, rel=1e-12)
    system = assemble_deck(deck, mass=spec["mass"])
    hz = deck_frequencies(system, support_dofs(system, deck, spec["support_set"]), 6)
    m2 = (inner / outer) ** 2
    cowper = 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)
    theory = cantilever_timoshenko_hz(young, young / (2 * (1 + nu)), rho, area, inertia, cowper,
                                      length, 3, rotary_inertia=False)
    assert np.allclose(hz, np.repeat(theory, 2), rtol=1e-4, atol=0), hz / np.repeat(theory, 2) - 1
    errors = hz / np.array(spec["frequencies_hz"]) - 1
    assert np.all(np.abs(errors[:4]) < 0.01), errors
    assert np.all(np.abs(errors) < 0.012), errors


def test_huang_closed_form_has_the_euler_bernoulli_limit():
    """k → ∞ without rotary inertia: the roots of cos β cosh β = −1 (1.87510, 4.69409, 7.85476)."""
    hz = cantilever_timoshenko_hz(1.0, 1.0, 1.0, 1.0, 1.0, 1e12, 1.0, 3, rotary_inertia=False)
    assert np.allclose(np.sqrt(2 * np.pi * hz), [1.875104, 4.694091, 7.854757], rtol=1e-6)


def _hex20_pipe(outer, wall, length, counts, young, poisson, density):
    """A DeckModel of a straight pipe along z of hex20 cells (counts = cells through the wall,
    around, along), curved edges on the exact circles; node indices of the end z = length."""
    nr, nt, nz = counts
    shape = (2 * nr + 1, 2 * nt, 2 * nz + 1)
    r, theta, z = np.meshgrid(np.linspace(outer - wall, outer, shape[0]),
                              np.arange(shape[1]) * np.pi / nt, np.linspace(0, length, shape[2]),
                              indexing="ij")
    points = np.column_stack([(r * np.cos(theta)).ravel(), (r * np.sin(theta)).ravel(), z.ravel()])
    deck = hex20_deck(points, shape, counts, young, poisson, density, "hex20 pipe", wrap_y=True)
    return deck, np.flatnonzero(np.isclose(deck.points[:, 2], length))


@pytest.mark.slow
def test_calculix_pipe_deck_vs_converged_3d_elasticity():
    """The pipe of simplebeampipe3.inp as 3D elasticity (hex20, 1 × 32 × 80, the whole end face
    held as CalculiX's expanded root; 1 × 48 × 120 moves the modes by ≤ 0.03 %): sarfe's reading
    of the deck (Timoshenko beams) is within 0.15 % of it on all six modes, while CalculiX's
    stored modes are 0.69 … 1.18 % above it (measured −0.688, −0.860, −1.182 %; 48 × 120:
    −0.714, −0.887, −1.211 %): the stored answer, not the reading, misses 1 %."""
    from sarfe.fe.modes import natural_frequencies
    from sarfe.mesh.formats.deck import SupportSet

    spec = REFERENCE["simplebeampipe3.inp"]
    deck = read_abaqus(DECKS / "simplebeampipe3.inp")
    system = assemble_deck(deck, mass=spec["mass"])
    beam = deck_frequencies(system, support_dofs(system, deck, spec["support_set"]), 6)
    solid, end = _hex20_pipe(0.11, 0.01, 10.0, (1, 32, 80), 1e7, 0.3, 7.8e-9)
    solid = dataclasses.replace(solid, supports={"end": SupportSet(end, np.ones((len(end), 6), bool))})
    system = assemble_deck(solid, mass="consistent")
    hz = natural_frequencies(system.stiffness, system.mass, count=6,
                             fixed=support_dofs(system, solid, "end"), shift_hz=1000.0)
    assert np.all(np.abs(beam / hz - 1) < 1.5e-3), beam / hz - 1
    stored = np.array(spec["frequencies_hz"])
    assert np.all(stored / hz - 1 > 0.006) and np.all(stored[4:] / hz[4:] - 1 > 0.01), stored / hz - 1
