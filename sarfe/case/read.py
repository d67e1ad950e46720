"""Case files: read YAML (line numbers kept), validate against the JSON schema, apply defaults.

    load_case(path_or_dict) -> Case      # raises CaseError with one line: file: key.path: problem

The reference of every key is docs/case-file.md; the schema is :data:`sarfe.case.schema.CASE_SCHEMA`.
Checks that need the mesh (node groups, contact pairing) live in :mod:`sarfe.pipeline`.
"""
from __future__ import annotations

import copy
import difflib
import math
import re
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import jsonschema
import yaml

from sarfe.case.config import (DEFAULT_ACCURACY, DEFAULT_ZETA, ContinuationConfig, ErpConfig,
                               ReductionConfig, SolverConfig, build_config,
                               default_samples_per_period)
from sarfe.case.errors import CaseError, format_key_path
from sarfe.case.schema import CASE_SCHEMA
from sarfe.hbm import laws

_VALIDATOR = jsonschema.Draft202012Validator(CASE_SCHEMA)
MESH_SUFFIXES = (".msh", ".bdf", ".nas", ".dat", ".inp")
DECK_SUFFIXES = (".bdf", ".nas", ".dat", ".fem", ".inp")
DECK_KEYS = ("units", "ignore_cards", "supports", "node_groups", "element_groups")
MATRIX_SUFFIXES = (".npz", ".npy", ".mtx")


@dataclass(frozen=True)
class Case:
    """A validated case with every default filled in (``data``), SI units except mesh coordinates.

    ``source``: the YAML file (None for a dict), ``base_dir``: directory that relative file names in
    the case refer to, ``lines``: {key path tuple: line} for error messages.
    """

    name: str
    data: dict
    source: str | None = None
    base_dir: Path = Path(".")
    lines: dict = field(default_factory=dict, compare=False, repr=False)

    @cached_property
    def config(self):
        """The typed configuration (:class:`sarfe.case.config.CaseConfig`), built once from the
        normalized ``data``."""
        return build_config(self.data)

    @property
    def is_fe(self) -> bool:
        return "fe" in self.data["model"]

    def error(self, message, key_path=()) -> CaseError:
        """A CaseError located in this case file (with the line of the deepest known key)."""
        path = tuple(key_path) if not isinstance(key_path, str) else ()
        return CaseError(message, key_path, self.source, _line_of(self.lines, path))

    def resolve(self, file_name) -> Path:
        """A file named in the case, relative to the case file's directory."""
        path = Path(file_name).expanduser()
        return path if path.is_absolute() else self.base_dir / path


# ----------------------------------------------------------------------------------- YAML reading
class CaseLoader(yaml.SafeLoader):
    """SafeLoader that also reads 2.1e9 / 1e-3 as numbers (YAML 1.1 wants '2.1e+9', '1.0e-3')."""


CaseLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                  |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                  |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                  |[-+]?\.(?:inf|Inf|INF)
                  |\.(?:nan|NaN|NAN))$""", re.X),
    list("-+0123456789."))


def _node_lines(node, path=(), lines=None, source=None):
    """Walk a composed YAML node: {key path: 1-based line}; duplicate keys are errors."""
    lines = {} if lines is None else lines
    lines[path] = node.start_mark.line + 1
    if isinstance(node, yaml.MappingNode):
        seen = set()
        for key_node, value_node in node.value:
            key = key_node.value
            if key in seen:
                raise CaseError(f"duplicate key '{key}'", path + (key,), source,
                                key_node.start_mark.line + 1)
            seen.add(key)
            _node_lines(value_node, path + (key,), lines, source)
            lines[path + (key,)] = key_node.start_mark.line + 1
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            _node_lines(item, path + (index,), lines, source)
    return lines


def _line_of(lines, path):
    path = tuple(path)
    while path and path not in lines:
        path = path[:-1]
    return lines.get(path) if path else None


def read_yaml(path):
    """Parse a YAML case file → (data, lines). Malformed YAML → CaseError with line and column."""
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CaseError("case file not found", source=source) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CaseError(f"cannot read case file: {exc}", source=source) from None
    try:
        node = yaml.compose(text, Loader=CaseLoader)
        data = yaml.load(text, Loader=CaseLoader)  # noqa: S506 (a SafeLoader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = exc.problem or exc.context or "syntax error"
        raise CaseError(f"malformed YAML{where}: {problem}", source=source) from None
    except yaml.YAMLError as exc:
        raise CaseError(f"malformed YAML: {exc}", source=source) from None
    if node is None:
        raise CaseError("the case file is empty", source=source)
    lines = _node_lines(node, source=source)
    return data, lines


# ------------------------------------------------------------------------------ schema messages
_TYPE_NAMES = {"number": "a number", "integer": "an integer", "string": "a string",
               "array": "a list", "object": "a mapping", "boolean": "true/false", "null": "null"}
_PATTERN_HINTS = {
    "^[-+]?[xyz]$": "must be 'x', 'y', 'z' (optionally signed) or a vector [x, y, z]",
    "^ground$": "must be a node/DOF index or 'ground'",
    "^auto$": "must be 'auto' or a vector [x, y, z]",
    "^[A-Za-z0-9_.-]+$": "may contain only letters, digits, '_', '.' and '-'",
}


def _describe(value) -> str:
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
        close = difflib.get_close_matches(str(key), allowed, n=1)
        hint = f"did you mean '{close[0]}'? " if close else ""
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
        return path, f"expected {wanted}, got {_describe(inst)}{hint}"
    if v in ("minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum"):
        op = {"minimum": ">=", "exclusiveMinimum": ">", "maximum": "<=", "exclusiveMaximum": "<"}[v]
        return path, f"must be {op} {value:g}, got {inst!r}"
    if v == "enum":
        return path, f"must be one of {', '.join(map(repr, value))}, got {_describe(inst)}"
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
        raise CaseError(f"a case file must be a mapping of sections, got {_describe(data)}",
                        source=source)
    errors = list(_VALIDATOR.iter_errors(data))
    if not errors:
        return
    def order(error):
        return (_line_of(lines, error.absolute_path) or 0, -len(error.absolute_path))
    error = min(errors, key=order)
    # descend into the sub-error of the combinator's branch that fits the value's kind
    while error.context:
        depth = len(error.absolute_path)
        fitting = [e for e in error.context if e.validator not in ("type", "enum")
                   or len(e.absolute_path) > depth]
        if not fitting:   # no branch fits: name every accepted form
            path = tuple(error.absolute_path)
            raise CaseError(f"must be {_accepted_forms(error.context)}, got "
                            f"{_describe(error.instance)}", path, source, _line_of(lines, path))
        error = jsonschema.exceptions.best_match(fitting)
    path, message = _schema_message(error)
    raise CaseError(message, path, source, _line_of(lines, path))


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


# ------------------------------------------------------------------------ numbers and plausibility
def check_finite(data, source=None, lines=None, path=()):
    """Raise CaseError at the first NaN or ±inf anywhere in the case (YAML ``.nan``, ``.inf``):
    no key of a case takes a non-finite number, and the schema's range checks let NaN through."""
    if isinstance(data, float) and not math.isfinite(data):
        text = ".nan" if math.isnan(data) else ("-.inf" if data < 0 else ".inf")
        raise CaseError(f"must be a finite number, got {text}", path, source,
                        _line_of(lines or {}, path))
    if isinstance(data, dict):
        for key, value in data.items():
            check_finite(value, source, lines, path + (key,))
    elif isinstance(data, list):
        for index, value in enumerate(data):
            check_finite(value, source, lines, path + (index,))


# Bounds outside which a value is a unit mistake rather than a material or a load; each message
# says which unit the key is in.
AUDIBLE_LIMIT_HZ = 20e3
# unit plausibility bounds, shared by the case keys, mesh files and decks (sarfe.pipeline.checks.deck_checks):
# below them a value in SI is almost surely in another unit system
MIN_E_PA, MIN_RHO_KG_M3, _MAX_MESH_SIZE_M = 1e5, 1.0, 1.0
SPAN_RANGE_M = (5e-3, 20.0)       # a trim part's overall size [m]
THICKNESS_RANGE = (1e-4, 0.1)     # a shell's thickness / the model size


def _check_plausible(case, data):
    """Signs and orders of magnitude that the schema cannot judge (negative excitation amplitudes,
    moduli in MPa/GPa, densities in t/mm³ or g/cm³, frequencies beyond hearing)."""
    exc = data["excitation"]
    for i, load in enumerate(exc.get("forces", [])):
        if load["force_N"] < 0:
            raise case.error(f"must be >= 0 (an amplitude), got {load['force_N']:g}; reverse the "
                             "direction or set phase_deg: 180", ("excitation", "forces", i, "force_N"))
    base = exc.get("base_acceleration")
    if base is not None and base["amplitude_m_s2"] < 0:
        raise case.error(f"must be >= 0 (an amplitude), got {base['amplitude_m_s2']:g}; reverse the "
                         "direction or set phase_deg: 180",
                         ("excitation", "base_acceleration", "amplitude_m_s2"))
    frequencies = list(exc.get("frequency_hz", [])) + [exc["sweep"][k] for k in ("start_hz", "end_hz")
                                                      if "sweep" in exc]
    for key in ("frequency_hz", "sweep"):
        if key in exc and max(frequencies) > AUDIBLE_LIMIT_HZ:
            raise case.error(f"{max(frequencies):g} Hz is above the audible range (≤ "
                             f"{AUDIBLE_LIMIT_HZ:g} Hz) that squeak and rattle noise is judged in; "
                             "frequencies are in Hz", ("excitation", key))
    fe = data["model"].get("fe")
    if fe is None:
        return
    for name, material in fe.get("materials", {}).items():
        p = ("model", "fe", "materials", name)
        if material["E_Pa"] < MIN_E_PA:
            raise case.error(f"{material['E_Pa']:g} Pa is far too soft for a panel material — "
                             "given in MPa or GPa? E_Pa is in pascals (steel 2.1e+11)", p + ("E_Pa",))
        if material["rho_kg_m3"] < MIN_RHO_KG_M3:
            raise case.error(f"{material['rho_kg_m3']:g} kg/m³ is lighter than air — given in t/mm³ "
                             "or g/cm³? rho_kg_m3 is in kg/m³ (steel 7850)", p + ("rho_kg_m3",))
    generator = fe.get("generator")
    if generator is not None and generator["mesh_size_m"] >= _MAX_MESH_SIZE_M:
        raise case.error(f"{generator['mesh_size_m']:g} m elements are larger than a panel — given in "
                         "mm? mesh_size_m is in metres", ("model", "fe", "generator", "mesh_size_m"))


# ---------------------------------------------------------------------------------- normalizing
def _only_one(case, section, path, keys, required=True):
    given = [k for k in keys if k in section]
    if len(given) > 1:
        raise case.error(f"give only one of {' or '.join(map(repr, keys))}", path + (given[1],))
    if required and not given:
        raise case.error(f"give one of {' or '.join(map(repr, keys))}", path)
    return given[0] if given else None


def _not_allowed(case, section, path, keys, reason):
    for key in keys:
        if key in section:
            raise case.error(f"not allowed {reason}", path + (key,))


def direction_vector(case, value, path):
    """'x' | '-y' | [x, y, z] → unit vector (list of 3 floats)."""
    if isinstance(value, str):
        sign = -1.0 if value.startswith("-") else 1.0
        axis = "xyz".index(value[-1])
        vector = [0.0, 0.0, 0.0]
        vector[axis] = sign
        return vector
    norm = math.sqrt(sum(float(x) ** 2 for x in value))
    if norm == 0.0 or not math.isfinite(norm):
        raise case.error("direction vector must be non-zero and finite", path)
    return [float(x) / norm for x in value]


def _normalize_model(case, data):
    model = data["model"]
    if "fe" in model:
        fe = model["fe"]
        p = ("model", "fe")
        source = _only_one(case, fe, p, ("mesh", "generator", "deck"))
        if source == "deck":
            _normalize_deck(case, fe, p)
            return
        _not_allowed(case, fe, p, DECK_KEYS, "without model.fe.deck")
        for key in ("materials", "thickness_m", "fixed"):
            if key not in fe:
                raise case.error(f"missing required key (with model.fe.{source})", p + (key,))
        fe.setdefault("mesh_units", "m")
        if source == "mesh":
            mesh = case.resolve(fe["mesh"])
            if mesh.suffix.lower() not in MESH_SUFFIXES:
                raise case.error(f"mesh file must be one of {', '.join(MESH_SUFFIXES)}, got "
                                 f"'{mesh.name}'", p + ("mesh",))
            if not mesh.is_file():
                raise case.error(f"mesh file not found: {mesh}", p + ("mesh",))
        else:
            fe["generator"].setdefault("params", {})
            if "mesh_units" in fe and fe["mesh_units"] != "m":
                raise case.error("generated meshes are in metres; mesh_units must be 'm'",
                                 p + ("mesh_units",))
    else:
        mat = model["matrices"]
        p = ("model", "matrices")
        for key in ("mass", "stiffness", "damping"):
            if isinstance(mat.get(key), str):
                path = case.resolve(mat[key])
                if path.suffix.lower() not in MATRIX_SUFFIXES:
                    raise case.error(f"matrix file must be one of {', '.join(MATRIX_SUFFIXES)}, "
                                     f"got '{path.name}'", p + (key,))
                if not path.is_file():
                    raise case.error(f"matrix file not found: {path}", p + (key,))
        # an empty damping section is what normalizing a case with its own damping matrix leaves
        # (so a normalized case, e.g. after solver.accuracy chose H, loads again)
        if "damping" in mat and data.get("damping"):
            raise case.error("give either model.matrices.damping or a damping section, not both",
                             ("damping",))
        _not_allowed(case, data, (), ("reduction",), "with model.matrices (no reduction)")


def _normalize_deck(case, fe, p):
    """model.fe.deck: the file exists and is a deck; units, ignore_cards, fixed defaults."""
    deck = case.resolve(fe["deck"])
    if deck.suffix.lower() not in DECK_SUFFIXES:
        raise case.error(f"deck file must be one of {', '.join(DECK_SUFFIXES)}, got "
                         f"'{deck.name}'", p + ("deck",))
    if not deck.is_file():
        raise case.error(f"deck file not found: {deck}", p + ("deck",))
    _not_allowed(case, fe, p, ("mesh_units",), "with model.fe.deck (use 'units')")
    fe.setdefault("units", "SI")
    fe.setdefault("ignore_cards", [])
    fe.setdefault("node_groups", {})
    fe.setdefault("element_groups", {})


def _normalize_damping(case, data):
    if not data.get("damping"):       # absent, or {} left by normalizing a matrices damping
        if "matrices" in data["model"] and "damping" in data["model"]["matrices"]:
            data["damping"] = {}
            return
        data["damping"] = {"modal_zeta": DEFAULT_ZETA}
        return
    damping = data["damping"]
    _only_one(case, damping, ("damping",), ("modal_zeta", "rayleigh"))
    zeta = damping.get("modal_zeta")
    if isinstance(zeta, list):
        for i, entry in enumerate(zeta):
            first, last = entry["modes"]
            if last < first:
                raise case.error(f"mode range must be [first, last] with first <= last, got "
                                 f"{entry['modes']}", ("damping", "modal_zeta", i, "modes"))


def _normalize_contacts(case, data):
    """Contact keys checked against the contact's law (:mod:`sarfe.hbm.laws`): its parameters (with
    their defaults), normal / tangential DOFs it needs, keys of other laws not allowed."""
    contacts = data.setdefault("contacts", [])
    fe = case.is_fe
    names = set()
    every_key = set().union(*(law.keys() for law in laws.LAWS.values()))
    for i, contact in enumerate(contacts):
        p = ("contacts", i)
        if contact["name"] in names:
            raise case.error(f"duplicate contact name '{contact['name']}'", p + ("name",))
        names.add(contact["name"])
        law = laws.law(contact["type"])
        kind = law.name
        if fe:
            _not_allowed(case, contact, p, ("normal_dof", "tangential_dofs"),
                         "with model.fe (use 'between' node groups)")
            deck = "deck" in data["model"]["fe"]
            if "from_elements" in contact and not deck:
                raise case.error("needs model.fe.deck (CBUSH/CELAS elements of a deck)",
                                 p + ("from_elements",))
            if "between" not in contact and "pairs" not in contact and "from_elements" not in contact:
                raise case.error("missing required key (node groups [a, b] or [a, ground], "
                                 "or explicit node 'pairs', or deck 'from_elements')", p + ("between",))
            _only_one(case, contact, p, ("between", "pairs", "from_elements"))
            if "element_axis" in contact and "from_elements" not in contact:
                raise case.error("only with from_elements", p + ("element_axis",))
            if "between" in contact and contact["between"][0] == "ground":
                raise case.error("the first group cannot be 'ground'", p + ("between", 0))
            for j, pair in enumerate(contact.get("pairs", [])):
                if pair[0] == pair[1]:
                    raise case.error(f"node {pair[0]} is paired with itself (a pair joins two "
                                     "different nodes, or a node and 'ground')", p + ("pairs", j))
            contact.setdefault("pairing_tolerance_m", 1e-3)
            contact.setdefault("normal", "auto")
            has_normal = True
        else:
            _not_allowed(case, contact, p, ("between", "pairs", "normal", "pairing_tolerance_m"),
                         "with model.matrices (use 'normal_dof' / 'tangential_dofs')")
            has_normal = "normal_dof" in contact
            if law.normal_dof == "required" and not has_normal:
                raise case.error(f"missing required key (a {kind} contact needs a normal DOF)",
                                 p + ("normal_dof",))
            if law.tangent_dofs == "required" and "tangential_dofs" not in contact:
                raise case.error(f"missing required key (a {kind} contact needs a tangential DOF)",
                                 p + ("tangential_dofs",))
            for key in ("normal_dof",):
                if isinstance(contact.get(key), int):
                    contact[key] = {"dof": contact[key]}
            if "tangential_dofs" in contact:
                contact["tangential_dofs"] = [{"dof": t} if isinstance(t, int) else t
                                              for t in contact["tangential_dofs"]]
            for ref in ([contact["normal_dof"]] if has_normal else []) + contact.get(
                    "tangential_dofs", []):
                ref.setdefault("relative_to", "ground")
                ref.setdefault("sign", 1)
        others = sorted(every_key - law.keys(), key=lambda k: list(contact).index(k)
                        if k in contact else 0)
        if law.tangent_dofs == "forbidden":
            others.append("tangential_dofs")
        _not_allowed(case, contact, p, others, f"for a {kind} contact")
        normal_keys = [q.key for q in law.case_parameters() if q.normal_part]
        tangent_keys = [q.key for q in law.tangent.PARAMETERS] if law.tangent is not None else []
        # FE decks: a contact made of CBUSH/CELAS elements takes its springs from them
        from_elements = {"normal_stiffness", "tangential_stiffness"} if "from_elements" in contact \
            else set()
        if has_normal:
            for q in law.case_parameters():
                key = q.key
                if q.normal_part and q.required and key not in contact \
                        and q.name not in from_elements:
                    raise case.error("missing required key", p + (key,))
        else:
            _not_allowed(case, contact, p, tuple(normal_keys) + ("gap_m",),
                         "without a normal DOF (the normal load is the constant preload_N)")
            if "preload_N" not in contact:
                raise case.error("missing required key (normal load of a friction contact "
                                 "without normal DOF)", p + ("preload_N",))
        tangent = laws.uses_tangent(law, contact) if fe else "tangential_dofs" in contact
        for q in law.case_parameters():
            if q.normal_part or not q.required:
                continue
            if q.key in tangent_keys and not tangent or q.name in from_elements:
                continue
            if q.key not in contact:
                raise case.error("missing required key", p + (q.key,))
        if law.prepare is not None:
            try:
                law.prepare(contact, case.resolve)
            except laws.LawInputError as error:
                raise case.error(str(error), p + (error.key,)) from None
        _only_one(case, contact, p, ("gap_m", "preload_N"), required=False)
        if has_normal and "preload_N" not in contact and not fe:
            contact.setdefault("gap_m", 0.0)  # FE: default = geometric gap of each node pair
        contact.setdefault("tolerance_m", 0.0)


def _normalize_excitation(case, data):
    exc = data["excitation"]
    p = ("excitation",)
    kind = _only_one(case, exc, p, ("forces", "base_acceleration"))
    _only_one(case, exc, p, ("frequency_hz", "sweep"))
    if isinstance(exc.get("frequency_hz"), (int, float)):
        exc["frequency_hz"] = [exc["frequency_hz"]]
    if "sweep" in exc and exc["sweep"]["start_hz"] == exc["sweep"]["end_hz"]:
        raise case.error("end_hz must differ from start_hz", p + ("sweep", "end_hz"))
    fe = case.is_fe
    if kind == "forces":
        for i, load in enumerate(exc["forces"]):
            q = p + ("forces", i)
            if fe and "load_set" in load:
                if "deck" not in data["model"]["fe"]:
                    raise case.error("needs model.fe.deck", q + ("load_set",))
                _not_allowed(case, load, q, ("dof", "group", "direction", "force_N"),
                             "with load_set (the deck's forces times 'scale')")
                load["force_N"] = float(load.setdefault("scale", 1.0))   # amplitude factor
            elif fe:
                _not_allowed(case, load, q, ("dof", "scale"), "with model.fe (use 'group')")
                for key in ("group", "direction", "force_N"):
                    if key not in load:
                        raise case.error("missing required key", q + (key,))
                load["direction"] = direction_vector(case, load["direction"], q + ("direction",))
            else:
                _not_allowed(case, load, q, ("group", "direction", "load_set", "scale"),
                             "with model.matrices (use 'dof')")
                for key in ("dof", "force_N"):
                    if key not in load:
                        raise case.error("missing required key", q + (key,))
            load.setdefault("phase_deg", 0.0)
    else:
        base = exc["base_acceleration"]
        q = p + ("base_acceleration",)
        if fe:
            _not_allowed(case, base, q, ("influence",), "with model.fe (use 'direction')")
            if "direction" not in base:
                raise case.error("missing required key", q + ("direction",))
            base["direction"] = direction_vector(case, base["direction"], q + ("direction",))
        else:
            _not_allowed(case, base, q, ("direction",), "with model.matrices (use 'influence')")
        base.setdefault("phase_deg", 0.0)


def _normalize_solver(case, data):
    solver = data.setdefault("solver", {})
    # no harmonics given: sarfe chooses H, N (and the mode count) for the accuracy budget
    # (default 'balanced'), starting its screening from H = 5; given harmonics are used as they are
    solver.setdefault("resolution", "fixed" if "harmonics" in solver else "auto")
    if solver["resolution"] == "auto":
        solver.setdefault("accuracy", DEFAULT_ACCURACY)
    H = solver.setdefault("harmonics", SolverConfig.harmonics)
    N = solver.setdefault("samples_per_period", default_samples_per_period(H))
    if N < 2 * H + 1:
        raise case.error(f"must be >= 2H+1 = {2 * H + 1} for harmonics H = {H}, got {N}",
                         ("solver", "samples_per_period"))
    for key in ("tolerance", "max_iterations", "stability", "error_estimate", "harmonic_set",
                "prune_contacts", "workers"):          # defaults: sarfe.case.config.SolverConfig
        solver.setdefault(key, getattr(SolverConfig, key))
    cont = solver.setdefault("continuation", {})
    for key in ("initial_step", "min_step", "max_step", "max_points"):
        cont.setdefault(key, getattr(ContinuationConfig, key))
    if cont["min_step"] > cont["max_step"]:
        raise case.error("must be <= max_step", ("solver", "continuation", "min_step"))
    if not cont["min_step"] <= cont["initial_step"] <= cont["max_step"]:
        raise case.error("must lie between min_step and max_step",
                         ("solver", "continuation", "initial_step"))


def _normalize_reduction(case, data):
    if not case.is_fe:
        return
    red = data.setdefault("reduction", {})
    _only_one(case, red, ("reduction",), ("mode_count", "cutoff_hz"), required=False)
    for key in ("cutoff_margin", "min_mode_count", "residual_vectors"):
        red.setdefault(key, getattr(ReductionConfig, key))   # defaults: sarfe.case.config


def _normalize_erp(case, data):
    erp = data.setdefault("erp", {})
    p = ("erp",)
    if case.is_fe:
        _not_allowed(case, erp, p, ("dofs", "areas_m2"), "with model.fe (use 'surface')")
    else:
        _not_allowed(case, erp, p, ("surface",), "with model.matrices (use 'dofs' and 'areas_m2')")
        if ("dofs" in erp) != ("areas_m2" in erp):
            raise case.error("give both 'dofs' and 'areas_m2'", p)
        if "dofs" in erp and len(erp["dofs"]) != len(erp["areas_m2"]):
            raise case.error(f"needs one area per DOF in erp.dofs ({len(erp['dofs'])}), got "
                             f"{len(erp['areas_m2'])}", p + ("areas_m2",))
    for key in ("rho_kg_m3", "c_m_s", "radiation_loss_factor", "reference_power_W"):
        erp.setdefault(key, getattr(ErpConfig, key))          # defaults: sarfe.case.config


def _normalize_output(case, data):
    out = data.setdefault("output", {})
    out.setdefault("directory", str(Path("results") / data["name"]))
    default = ["summary", "response", "plots", "table", "report"] + (
        ["erp_vtu", "animation"] if case.is_fe else [])
    out.setdefault("files", default)
    if "summary" not in out["files"]:
        out["files"] = ["summary"] + list(out["files"])


def normalize(case: Case) -> Case:
    """Cross-key rules and defaults; returns a Case whose ``data`` has every key filled in."""
    data = case.data
    _normalize_model(case, data)
    _normalize_damping(case, data)
    _normalize_contacts(case, data)
    _normalize_excitation(case, data)
    _normalize_solver(case, data)
    _normalize_reduction(case, data)
    _normalize_erp(case, data)
    _normalize_output(case, data)
    _check_plausible(case, data)
    return case


def load_case(path_or_dict, base_dir=None) -> Case:
    """Read (a YAML file) or take (a dict), validate and fill defaults → :class:`Case`.

    Raises CaseError (a ValueError) with one line ``file: key.path: problem (line n)``.
    """
    if isinstance(path_or_dict, Case):
        return path_or_dict
    if isinstance(path_or_dict, dict):
        data, lines, source = copy.deepcopy(path_or_dict), {}, None
        base = Path(base_dir) if base_dir else Path.cwd()
    else:
        source = str(path_or_dict)
        data, lines = read_yaml(path_or_dict)
        base = Path(base_dir) if base_dir else Path(path_or_dict).resolve().parent
    check_finite(data, source, lines)
    validate_schema(data, source, lines)
    case = Case(name=data["name"], data=data, source=source, base_dir=base, lines=lines)
    return normalize(case)


__all__ = ["Case", "CaseError", "load_case", "read_yaml", "validate_schema", "normalize",
           "direction_vector", "format_key_path"]
