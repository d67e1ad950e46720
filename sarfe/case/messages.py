"""Schema violations of a case file as one line each: the first violation (in document order) of
the JSON schema (:data:`sarfe.case.schema.CASE_SCHEMA`), said in the case's words.

    validate_schema(data, source=None, lines=None)   raises CaseError: file: key.path: problem (line n)

e.g. ``contacts[0]: unknown key (did you mean 'gap_m'? allowed: …)`` (close spelling, or another
word for the key: ``mu`` → ``friction_coefficient``, :data:`KEY_ALIASES`), ``solver.harmonics: must be
>= 1, got 0``, ``solver.accuracy: must be one of 'fast', 'balanced', 'fine' or a mapping, got 7``.
"""
from __future__ import annotations

import difflib

import jsonschema

from sarfe.case.errors import CaseError, line_of
from sarfe.case.schema import CASE_SCHEMA

_VALIDATOR = jsonschema.Draft202012Validator(CASE_SCHEMA)
_TYPE_NAMES = {"number": "a number", "integer": "an integer", "string": "a string",
               "array": "a list", "object": "a mapping", "boolean": "true/false", "null": "null"}
_PATTERN_HINTS = {
    "^[-+]?[xyz]$": "must be 'x', 'y', 'z' (optionally signed) or a vector [x, y, z]",
    "^ground$": "must be a node/DOF index or 'ground'",
    "^auto$": "must be 'auto' or a vector [x, y, z]",
    "^[A-Za-z0-9_.-]+$": "may contain only letters, digits, '_', '.' and '-'",
}
# Other words for a key (textbooks, other solvers' inputs, a first guess) that close spelling
# cannot find: 'mu' is nothing like 'friction_coefficient'. Keys are compared in lower case; of
# the candidates, the first one the mapping allows is suggested.
KEY_ALIASES = {
    "mu": ("friction_coefficient",), "μ": ("friction_coefficient",),
    "friction": ("friction_coefficient",), "cof": ("friction_coefficient",),
    "e": ("E_Pa",), "young": ("E_Pa",), "youngs_modulus": ("E_Pa",), "modulus": ("E_Pa",),
    "rho": ("rho_kg_m3",), "density": ("rho_kg_m3",), "poisson": ("nu",),
    "poissons_ratio": ("nu",), "thickness": ("thickness_m",), "t": ("thickness_m",),
    "gap": ("gap_m",), "clearance": ("gap_m",), "preload": ("preload_N",),
    "k": ("normal_stiffness_N_m", "stiffness"), "kn": ("normal_stiffness_N_m",),
    "stiffness": ("normal_stiffness_N_m",), "contact_stiffness": ("normal_stiffness_N_m",),
    "kt": ("tangential_stiffness_N_m",), "c": ("damping_N_s_m",),
    "force": ("force_N", "forces"), "amplitude": ("force_N", "amplitude_m_s2"),
    "acceleration": ("amplitude_m_s2", "base_acceleration"), "phase": ("phase_deg",),
    "frequency": ("frequency_hz",), "frequencies": ("frequency_hz",), "freq": ("frequency_hz",),
    "f": ("frequency_hz",), "start": ("start_hz",), "f_start": ("start_hz",),
    "end": ("end_hz",), "stop": ("end_hz",), "f_end": ("end_hz",),
    "zeta": ("modal_zeta", "zeta"), "damping_ratio": ("modal_zeta", "zeta"),
    "h": ("harmonics",), "nh": ("harmonics",), "n_harmonics": ("harmonics",),
    "n": ("samples_per_period",), "samples": ("samples_per_period",),
    "nfft": ("samples_per_period",), "n_modes": ("mode_count",), "num_modes": ("mode_count",),
    "cutoff": ("cutoff_hz",), "fmax": ("cutoff_hz",), "mesh_size": ("mesh_size_m",),
    "element_size": ("mesh_size_m",), "law": ("type",), "kind": ("type",),
    "clamped": ("fixed",), "spc": ("fixed", "supports"), "bc": ("fixed", "supports"),
    "boundary_conditions": ("fixed", "supports"), "output_dir": ("directory",),
    "outdir": ("directory",), "group_pair": ("between",), "target": ("target_dba",),
}


def suggestion(key, allowed) -> str | None:
    """The allowed key ``key`` most likely means: another word for it (:data:`KEY_ALIASES`),
    the same key in another case, or the closest spelling; None if nothing is close."""
    allowed = list(allowed)
    text = str(key)
    for candidate in KEY_ALIASES.get(text.lower(), ()):
        if candidate in allowed:
            return candidate
    by_case = [name for name in allowed if name.lower() == text.lower()]
    if by_case:
        return by_case[0]
    close = difflib.get_close_matches(text, allowed, n=1)
    return close[0] if close else None


def describe(value) -> str:
    if isinstance(value, (dict, list)):
        kind = "a mapping" if isinstance(value, dict) else "a list"
        return kind
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _schema_message(error):
    """(key path tuple, one-line message) for a jsonschema ValidationError."""
    path = tuple(error.absolute_path)
    v, value, inst = error.validator, error.validator_value, error.instance
    if v == "additionalProperties":
        allowed = sorted(error.schema.get("properties", {}))
        extra = sorted(set(inst) - set(allowed))
        key = extra[0]
        close = suggestion(key, allowed)
        hint = f"did you mean '{close}'? " if close else ""
        return path + (key,), f"unknown key ({hint}allowed: {', '.join(allowed)})"
    if v == "required":
        missing = [k for k in value if k not in inst]
        return path + (missing[0],), "missing required key"
    if v == "type":
        types = [value] if isinstance(value, str) else value
        wanted = " or ".join(_TYPE_NAMES.get(t, t) for t in types)
        hint = ""
        if isinstance(inst, str) and ("number" in types or "integer" in types):
            try:
                float(inst)
                hint = " (a number written as text; plain PyYAML reads 2.0e4 as text, use 2.0e+4)"
            except ValueError:
                pass
        return path, f"expected {wanted}, got {describe(inst)}{hint}"
    if v in ("minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum"):
        op = {"minimum": ">=", "exclusiveMinimum": ">", "maximum": "<=", "exclusiveMaximum": "<"}[v]
        return path, f"must be {op} {value:g}, got {inst!r}"
    if v == "enum":
        return path, f"must be one of {', '.join(map(repr, value))}, got {describe(inst)}"
    if v == "pattern":
        return path, f"{_PATTERN_HINTS.get(value, 'must match ' + value)}, got {inst!r}"
    if v == "minItems":
        return path, f"needs at least {value} item{'s' if value > 1 else ''}, got {len(inst)}"
    if v == "maxItems":
        return path, f"takes at most {value} item{'s' if value > 1 else ''}, got {len(inst)}"
    if v == "minLength":
        return path, "must not be empty"
    if v in ("minProperties", "maxProperties"):
        props = error.schema.get("properties")
        if props and value == 1:
            return path, f"give exactly one of {' or '.join(map(repr, props))}"
        return path, f"needs {'at least' if v == 'minProperties' else 'at most'} {value} entries"
    if v == "uniqueItems":
        return path, "has duplicate entries"
    return path, error.message


def validate_schema(data, source=None, lines=None):
    """Raise CaseError for the first schema violation (document order)."""
    lines = lines or {}
    if not isinstance(data, dict):
        raise CaseError(f"a case file must be a mapping of sections, got {describe(data)}",
                        source=source)
    errors = list(_VALIDATOR.iter_errors(data))
    if not errors:
        return
    def order(error):
        return (line_of(lines, error.absolute_path) or 0, -len(error.absolute_path))
    error = min(errors, key=order)
    # descend into the sub-error of the combinator's branch that fits the value's kind
    while error.context:
        depth = len(error.absolute_path)
        fitting = [e for e in error.context if e.validator not in ("type", "enum")
                   or len(e.absolute_path) > depth]
        if not fitting:   # no branch fits: name every accepted form
            path = tuple(error.absolute_path)
            raise CaseError(f"must be {_accepted_forms(error.context)}, got "
                            f"{describe(error.instance)}", path, source, line_of(lines, path))
        error = jsonschema.exceptions.best_match(fitting)
    path, message = _schema_message(error)
    raise CaseError(message, path, source, line_of(lines, path))


def _accepted_forms(errors) -> str:
    """'one of 'fast', 'balanced', 'fine' or a mapping' from the type/enum errors of the branches
    of a oneOf/anyOf."""
    forms = []
    for error in errors:
        if error.validator == "enum":
            forms.append(", ".join(map(repr, error.validator_value)))
        else:
            types = error.validator_value
            types = [types] if isinstance(types, str) else types
            forms.append(" or ".join(_TYPE_NAMES.get(t, t) for t in types))
    forms = list(dict.fromkeys(forms))
    return ("one of " if any(e.validator == "enum" for e in errors) else "") + " or ".join(forms)


__all__ = ["validate_schema", "describe", "suggestion", "KEY_ALIASES"]
