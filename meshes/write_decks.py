"""Write the Nastran decks of the shipped deck cases from sarfe's own generators.

    meshes/rattle_rig_deck.bdf   rattle rig, 10 mm, default parameters (cases/rattle_rig_deck.yaml)

The deck is the generator's model as an engineer's deck (sarfe.mesh.formats.nastran_writer): CQUAD4 /
CTRIA3, PSHELL + MAT1 per part, SPC1 on the clamped edges, SET1 for the contact and load nodes,
in mm-t-s. `tests/pipeline/model/test_deck_rig.py` checks that the file equals a fresh write and that
the deck case solves to the generator case's ERP.

Usage:  python meshes/write_decks.py
"""
from __future__ import annotations

import pathlib

from sarfe.mesh.generators import rattle_rig
from sarfe.mesh.formats.nastran_writer import ShellProperty, write_panel_deck

HERE = pathlib.Path(__file__).resolve().parent
ABS = (2.2e9, 0.37, 1050.0)
STEEL = (2.1e11, 0.30, 7850.0)


def write_rattle_rig_deck(path=HERE / "rattle_rig_deck.bdf", mesh_size=0.01):
    """The rattle rig of cases/rattle_rig.yaml as a Nastran deck; returns the WrittenDeck."""
    mesh = rattle_rig.generate(mesh_size=mesh_size, gap=0.5e-3)
    properties = [ShellProperty("part_plate", *ABS, 2.5e-3),
                  ShellProperty("part_beam", *STEEL, 1.5e-3)]
    return write_panel_deck(path, mesh, properties, clamped=["clamp_plate", "clamp_beam"],
                            node_sets=["contact_tip_a", "contact_tip_b", "excite_beam"])


if __name__ == "__main__":
    written = write_rattle_rig_deck()
    print(f"{written.path.name}: SET1 {written.set_ids}, PSHELL {written.property_ids}")
