"""sarfe.case — the case file, from YAML to a typed configuration. One way, top to bottom:

    read.py          load_case(path | dict) -> Case; read_yaml (line numbers kept), CaseLoader
    plausibility.py  non-finite numbers, unit-mistake bounds (E, ρ, span, thickness, frequency)
    schema.py        the JSON schema (every key, type and range; docs/case-file.md is its text)
    messages.py      validate_schema: the first schema violation as one line
    normalize.py     cross-key rules; every default written into Case.data
    config.py        CaseConfig: frozen dataclasses per section, the single source of defaults
    errors.py        CaseError (file: key.path: problem (line n)), exit codes
"""
