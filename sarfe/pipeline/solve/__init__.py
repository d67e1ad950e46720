"""Stage 3 of a case: harmonic balance per point or by continuation with its fallbacks (points),
a sweep by need — linear points where the contacts stay linear, the continuation where they act
(by_need) —, contact pruning (pruned_points), the accuracy target → H, N, cutoff and the
per-point error estimates (case_accuracy), the mesh term of the ± (mesh_error: the loudest point
re-solved on a 2× coarser generated mesh), the headline's ± by time integration where an impact
is not resolved by the harmonics (impact_check)."""
