"""Stage 5 of a case: the result files and the console table (result_files), the PNG figures and
the report's surface maps (figures)."""
