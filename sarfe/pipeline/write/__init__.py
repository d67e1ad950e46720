"""Stage 5 of a case: the result files and the full table (result_files), the PNG figures and
the report's surface maps (figures), which points get an ERP map (map_points: ``output.maps``),
sound.wav and sound_with_background.wav (sound_files)."""
