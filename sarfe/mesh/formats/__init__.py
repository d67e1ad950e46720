"""Engineers' model files (decks) → :class:`~sarfe.mesh.formats.deck.DeckModel`.

- deck: ``DeckModel`` (nodes, frames, shells, solids, beams, springs, masses, rigid elements,
  supports, loads, sets) in the file's units, ``UNIT_SYSTEMS``, ``to_si``, ``DeckError``.
- nastran: Nastran bulk data → DeckModel (``read_nastran``, ``nastran_deck``); nastran_bdf: the file
  through pyNastran (``load_bdf``) and a card's line for messages (``card_where``);
  nastran_sections (PSHELL, PCOMP, materials), nastran_sets (SPC, loads, SET1);
  beam_library (PBARL/PBEAML shapes → A, I1, I2, J by closed forms);
  nastran_writer (a PanelMesh written as a deck).
- abaqus: Abaqus ``.inp`` → DeckModel (``read_abaqus``, ``section_values``); abaqus_lines (keyword
  blocks, ``*INCLUDE``); abaqus_model (parts and instances flattened); abaqus_beams (B31/B32/B32R
  with ``*BEAM SECTION`` RECT, CIRC, PIPE → Timoshenko beams).
"""
