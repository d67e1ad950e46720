"""Stage 1 of a case: every input check before any work — case_checks (check_case, the warnings
for inputs far outside the model's range), mesh_checks (check_mesh / check_deck: groups, pairing,
shared node pairs, quality without assembly), held_checks (nothing left to move, a force or a
contact on held nodes only, for a mesh and a deck alike), case_inputs (every file a case reads: never inside
an output folder), run_cost (the cost validate and solve state before the run: H, N, cutoff,
≈ modes, points, CPU s, bytes written). The checks a deck's reading runs are part of building it
(:mod:`sarfe.pipeline.model.deck_checks`)."""
