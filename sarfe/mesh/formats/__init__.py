"""Engineers' model files: Nastran bulk data (pyNastran) and Abaqus input decks."""
