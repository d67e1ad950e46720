"""sarfe.case — the case file, from YAML to a typed configuration, in the order it is read:

    read.py          load_case(path | dict) -> Case; read_yaml (line numbers kept), CaseLoader
    plausibility.py  non-finite numbers, unit-mistake bounds (E, ρ, span, thickness, frequency)
    schema.py        the JSON schema (every key, type and range; docs/case-file.md is its text)
    messages.py      validate_schema: the first schema violation as one line
    normalize.py     cross-key rules; every default written into Case.data
    config.py        CaseConfig: frozen dataclasses per section, the single source of defaults
    errors.py        CaseError (file: key.path: problem (line n)), exit codes

The pipeline reads ``case.config``; ``case.data`` is the normalized mapping written out
(summary.json ``case_data``). A changed setting is a new Case with the typed section replaced
(``case.with_solver(harmonics=H, samples_per_period=N)``, ``with_reduction``, ``with_contact``,
``with_generator``), never an edited mapping loaded again.
"""
