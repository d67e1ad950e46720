"""Stage 4 of a case: ERP, contact indicators, baseline, estimates and records per point."""
