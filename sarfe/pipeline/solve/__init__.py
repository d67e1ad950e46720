"""Stage 3 of a case: harmonic balance per point or by continuation with its fallbacks (points),
contact pruning (pruned_points), the accuracy target → H, N, cutoff and the per-point error
estimates (case_accuracy), the mesh term of the ± (mesh_error: the loudest point re-solved on a
2× coarser generated mesh)."""
