"""Stage 1 of a case: every input check (case, mesh, deck) before any work."""
