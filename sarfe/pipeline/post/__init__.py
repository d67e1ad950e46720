"""Stage 4 of a case: per point ERP, contact indicators, linear baseline, bands (records), the
contribution of each contact (contribution_records), impacts, slip and dissipated energy
(contact_dynamics), the arrays of the result files (result_data), and the per-point work on
worker processes (point_workers)."""
