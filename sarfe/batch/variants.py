"""Study files: one base case and its variations, expanded into deterministic variants.

A study file (YAML, validated against ``STUDY_SCHEMA``; unknown keys are errors)::

    name: lumped_gap_scatter               # optional, default: file stem
    base_case: ../lumped_rattle.yaml       # relative to the study file
    overrides:                             # optional, written into every variant first
      excitation.sweep: null               # (null removes a key)
      excitation.frequency_hz: [52.0]
    variations:                            # exactly one of grid | list | monte_carlo
      monte_carlo:
        samples: 10
        seed: 7
        parameters:
          contacts[0].gap_m: {distribution: truncated_normal, mean: 1.0e-4, std: 3.0e-5, low: 0.0, high: 2.0e-4}
          contacts[*].friction_coefficient: {distribution: uniform, low: 0.2, high: 0.5}

``grid: {path: [values…], …}`` is the cartesian product (last path varies fastest);
``list: [{path: value, …}, …]`` gives the variants explicitly. Monte Carlo draws come from
``numpy.random.default_rng(seed)``, ``samples`` values per parameter, parameter by parameter in
file order. Distributions: ``normal {mean, std}``, ``uniform {low, high}``,
``lognormal {median, log_std}`` (log_std = standard deviation of ln x),
``truncated_normal {mean, std, low, high}`` (inverse-CDF sampling).
Paths are those of ``sarfe.batch.paths``; inside ``{…}`` flow mappings quote them
(``{'contacts[0].gap_m': 1.0e-4}``), YAML reads ``[`` there as a list.

Each variant's id is ``v`` + 12 hex digits of the SHA-256 of its base case (after overrides) and its
parameter values, so the same inputs give the same id on every run and machine.
"""
from __future__ import annotations

import hashlib
import itertools
import json
import math
import pathlib
from dataclasses import dataclass, field

import jsonschema
import numpy as np
import yaml

from sarfe.batch.paths import PathError, apply_parameters, count_matches, parse_path
from sarfe.case.errors import CaseError
from sarfe.case.read import CaseLoader, read_case_text


class StudyError(ValueError):
    """A study or case file that cannot be used; the message names the file and key."""


_NUMBER = {"type": "number"}
_POSITIVE = {"type": "number", "exclusiveMinimum": 0}
_DISTRIBUTIONS = {
    "normal": {"mean": _NUMBER, "std": {"type": "number", "minimum": 0}},
    "uniform": {"low": _NUMBER, "high": _NUMBER},
    "lognormal": {"median": _POSITIVE, "log_std": {"type": "number", "minimum": 0}},
    "truncated_normal": {"mean": _NUMBER, "std": _POSITIVE, "low": _NUMBER, "high": _NUMBER},
}
_SCALAR = {"type": ["number", "string", "boolean"]}
_VALUE = {"anyOf": [_SCALAR, {"type": "array"}, {"type": "object"}, {"type": "null"}]}  # null removes the key

STUDY_SCHEMA = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "sarfe study file",
    "type": "object",
    "additionalProperties": False,
    "required": ["base_case", "variations"],
    "properties": {
        "name": {"type": "string", "pattern": r"^[A-Za-z0-9_.\-]+$"},
        "description": {"type": "string"},
        "base_case": {"type": "string", "minLength": 1},
        "overrides": {"type": "object", "additionalProperties": _VALUE},
        "variations": {
            "type": "object",
            "additionalProperties": False,
            "minProperties": 1,
            "maxProperties": 1,
            "properties": {
                "grid": {"type": "object", "minProperties": 1,
                         "additionalProperties": {"type": "array", "minItems": 1, "items": _VALUE}},
                "list": {"type": "array", "minItems": 1,
                         "items": {"type": "object", "minProperties": 1, "additionalProperties": _VALUE}},
                "monte_carlo": {
                    "type": "object",
                    "additionalProperties": False,
                    "required": ["samples", "seed", "parameters"],
                    "properties": {
                        "samples": {"type": "integer", "minimum": 1},
                        "seed": {"type": "integer", "minimum": 0},
                        "parameters": {
                            "type": "object", "minProperties": 1,
                            "additionalProperties": {"oneOf": [
                                {"type": "object", "additionalProperties": False,
                                 "required": ["distribution", *fields],
                                 "properties": {"distribution": {"const": name}, **fields}}
                                for name, fields in _DISTRIBUTIONS.items()
                            ]},
                        },
                    },
                },
            },
        },
    },
}


def read_yaml(path) -> dict:
    """Mapping in a YAML file; StudyError names the file on any problem."""
    path = pathlib.Path(path)
    try:     # the case reader's numbers (1e-4 a float) and safety limits (size, aliases, depth)
        data = yaml.load(read_case_text(path), Loader=CaseLoader)
    except CaseError as error:
        raise StudyError(f"{path}: cannot read ({error.message})") from None
    except yaml.YAMLError as error:
        hint = ("; quote parameter paths inside {…} or [...], e.g. {'contacts[0].gap_m': 1.0e-4}"
                if "flow" in str(error) else "")
        raise StudyError(f"{path}: not valid YAML ({' '.join(str(error).split())}){hint}") from None
    if not isinstance(data, dict):
        raise StudyError(f"{path}: expected a mapping at the top level")
    return data


@dataclass(frozen=True)
class Variant:
    """One case to solve: ``case`` is the case mapping with ``parameters`` written into it."""
    index: int                  # position in the batch (table order)
    id: str                     # stable hash id
    source: str                 # study name or case file path
    parameters: dict            # {path: value} varied inputs (empty for a plain case file)
    case: dict = field(repr=False)
    case_dir: str = "."         # directory relative paths in the case refer to


@dataclass(frozen=True)
class Study:
    """A parsed study file (or a single case file: no variations)."""
    name: str
    path: str
    base_case_path: str
    base_case: dict = field(repr=False)     # after overrides
    kind: str = "case"                       # grid | list | monte_carlo | case
    variations: dict = field(default_factory=dict, repr=False)


def canonical_json(value) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"), default=_plain)


def _plain(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serializable")


def variant_id(base_case: dict, parameters: dict) -> str:
    digest = hashlib.sha256(canonical_json({"base": base_case, "parameters": parameters}).encode())
    return "v" + digest.hexdigest()[:12]


def is_study_file(path) -> bool:
    """True when the YAML file at ``path`` has a top-level ``base_case`` key."""
    return "base_case" in read_yaml(path)


def load_study(path) -> Study:
    """Read and validate a study file; the base case is read relative to it."""
    path = pathlib.Path(path)
    data = read_yaml(path)
    validator = jsonschema.Draft202012Validator(STUDY_SCHEMA)
    errors = sorted(validator.iter_errors(data), key=lambda e: list(e.absolute_path))
    if errors:
        error = min(errors, key=lambda e: len(e.context or ()))
        where = ".".join(str(p) for p in error.absolute_path) or "(top level)"
        raise StudyError(f"{path}: {where}: {_short(error)}")
    base_path = (path.parent / data["base_case"]).resolve()
    base = read_yaml(base_path)
    try:
        base = apply_parameters(base, data.get("overrides", {}))
    except PathError as error:
        raise StudyError(f"{path}: overrides: {error}") from None
    (kind, variations), = data["variations"].items()
    study = Study(name=data.get("name", path.stem), path=str(path), base_case_path=str(base_path),
                  base_case=base, kind=kind, variations=variations)
    for parameter_path in _parameter_paths(study):
        try:
            parse_path(parameter_path)
            if count_matches(base, parameter_path) == 0:
                raise PathError(f"parameter path {parameter_path!r} matches nothing in the base case")
        except PathError as error:
            raise StudyError(f"{path}: variations: {error}") from None
    if kind == "monte_carlo":
        for name, spec in variations["parameters"].items():
            low, high = spec.get("low"), spec.get("high")
            if low is not None and not low < high:
                raise StudyError(f"{path}: variations.monte_carlo.parameters.{name}: low must be < high")
    return study


def _short(error) -> str:
    if error.validator == "additionalProperties":
        return error.message.replace("Additional properties are not allowed", "unknown key(s)")
    if error.validator == "oneOf" and isinstance(error.instance, dict):
        kinds = ", ".join(_DISTRIBUTIONS)
        needed = _DISTRIBUTIONS.get(error.instance.get("distribution"))
        if needed is None:
            return f"distribution must be one of {kinds}"
        return f"{error.instance['distribution']} needs exactly: {', '.join(needed)}"
    return error.message


def _parameter_paths(study: Study) -> list[str]:
    if study.kind == "grid":
        return list(study.variations)
    if study.kind == "list":
        return list(dict.fromkeys(p for item in study.variations for p in item))
    if study.kind == "monte_carlo":
        return list(study.variations["parameters"])
    return []


def draw(rng: np.random.Generator, spec: dict, samples: int) -> np.ndarray:
    """``samples`` values of one distribution ``spec`` (see module docstring)."""
    kind = spec["distribution"]
    if kind == "normal":
        return rng.normal(spec["mean"], spec["std"], samples)
    if kind == "uniform":
        return rng.uniform(spec["low"], spec["high"], samples)
    if kind == "lognormal":
        return rng.lognormal(math.log(spec["median"]), spec["log_std"], samples)
    if kind == "truncated_normal":
        return _truncated_normal(rng.uniform(0.0, 1.0, samples), spec["mean"], spec["std"], spec["low"], spec["high"])
    raise StudyError(f"unknown distribution {kind!r}")


def _truncated_normal(u, mean, std, low, high):
    """Inverse CDF of N(mean, std²) restricted to [low, high] at probabilities ``u``.

    x = mean + std Φ⁻¹(Φ(a) + u (Φ(b) − Φ(a))), a, b = (low, high − mean)/std; for a > 0 the
    mirrored form with Φ(−·) keeps the precision of the far tail.
    """
    from scipy.special import ndtr, ndtri

    a, b = (low - mean) / std, (high - mean) / std
    if a > 0:
        x = mean - std * ndtri(ndtr(-a) - u * (ndtr(-a) - ndtr(-b)))
    else:
        x = mean + std * ndtri(ndtr(a) + u * (ndtr(b) - ndtr(a)))
    return np.clip(x, low, high)


def parameter_sets(study: Study) -> list[dict]:
    """The ``{path: value}`` of every variant, in generation order (deterministic)."""
    if study.kind == "grid":
        paths = list(study.variations)
        return [dict(zip(paths, values)) for values in itertools.product(*study.variations.values())]
    if study.kind == "list":
        return [dict(item) for item in study.variations]
    if study.kind == "monte_carlo":
        spec = study.variations
        rng = np.random.default_rng(spec["seed"])
        columns = {path: draw(rng, dist, spec["samples"]) for path, dist in spec["parameters"].items()}
        return [{path: float(values[k]) for path, values in columns.items()} for k in range(spec["samples"])]
    return [{}]


def study_variants(study: Study, start: int = 0) -> list[Variant]:
    """Expand a study into variants numbered from ``start``."""
    variants = []
    case_dir = str(pathlib.Path(study.base_case_path).parent)
    for offset, parameters in enumerate(parameter_sets(study)):
        try:
            case = apply_parameters(study.base_case, parameters)
        except PathError as error:
            raise StudyError(f"{study.path}: variant {offset}: {error}") from None
        variants.append(Variant(index=start + offset, id=variant_id(study.base_case, parameters),
                                source=study.name, parameters=parameters, case=case, case_dir=case_dir))
    return variants


def case_file_study(path) -> Study:
    """A plain case file seen as a one-variant study."""
    path = pathlib.Path(path).resolve()
    return Study(name=str(path), path=str(path), base_case_path=str(path), base_case=read_yaml(path))


def collect_variants(inputs) -> list[Variant]:
    """Variants of every study file, case file, Study or case mapping in ``inputs`` (in order).

    Raises StudyError on a bad file or when two variants are identical (same id).
    """
    if isinstance(inputs, (str, pathlib.Path, Study, dict)):
        inputs = [inputs]
    variants: list[Variant] = []
    for item in inputs:
        if isinstance(item, Study):
            study = item
        elif isinstance(item, dict):
            study = Study(name="case", path="<dict>", base_case_path=str(pathlib.Path.cwd() / "case.yaml"),
                          base_case=item)
        elif is_study_file(item):
            study = load_study(item)
        else:
            study = case_file_study(item)
        variants.extend(study_variants(study, start=len(variants)))
    seen: dict[str, Variant] = {}
    for variant in variants:
        if variant.id in seen:
            first = seen[variant.id]
            raise StudyError(f"variants {first.index} ({first.source}) and {variant.index} ({variant.source}) "
                             f"are identical (id {variant.id}); remove the duplicate")
        seen[variant.id] = variant
    return variants
