"""Public decks of pyNastran's models/ read as they are, against the commercial solver's stored
frequencies (tests/data/decks: SOURCE.md, REFERENCE.json) — issue 32.

Each deck reads without edits (its unsupported cards are exactly the analysis-only ones the
case would list in ``ignore_cards``) or is refused with one line; read decks match the stored
frequencies within 1 % (the first six elastic modes, as many as stored) with the deck's default
mass (lumped, as the commercial solver), and the mass equals pyNastran's mass properties
(an independent implementation) within 1e-6.
"""
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as la

from sarfe.fe.deck_assembly import assemble_deck, mass_properties, support_dofs
from sarfe.mesh.formats.deck import DeckError
from sarfe.mesh.formats.nastran import nastran_deck

DECKS = Path(__file__).resolve().parents[1] / "data" / "decks"
REFERENCE = json.loads((DECKS / "REFERENCE.json").read_text())
DECK_SPECS = {name: spec for name, spec in REFERENCE.items() if isinstance(spec, dict)}
READ = [name for name, spec in DECK_SPECS.items()
        if "frequencies_hz" in spec and "refused_cards" not in spec]
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
