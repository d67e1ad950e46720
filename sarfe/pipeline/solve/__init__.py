"""Stage 3 of a case: harmonic balance per point or by continuation, pruning, accuracy."""
