"""Stage 5 of a case: result files, console table and figures."""
