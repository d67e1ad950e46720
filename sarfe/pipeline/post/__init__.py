"""Stage 4 of a case: per point ERP, contact indicators, linear baseline, bands (records), the
contribution of each contact (contribution_records), impacts, slip and dissipated energy
(contact_dynamics), will the occupant hear it (audibility_records), what would fix it: onset
factor and level sensitivities per contact (margin_records), the review's answers at the loudest
point and the target (review), the arrays of the result files (result_data), and the per-point
work on worker processes (point_workers)."""
