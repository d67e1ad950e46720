"""The case file: YAML reading with line numbers, schema, normalisation, typed configuration."""
