"""JSON schema (Draft 2020-12) of a sarfe case file; the reference text is docs/case-file.md.

Every object has ``additionalProperties: false`` so a misspelt key is an error. Physical ranges
(E > 0, 0 ≤ μ, −1 < ν < 0.5, f > 0, H ≥ 1 …) are checked here; cross-key rules (exactly one of
two keys, node groups present in the mesh, pairing within tolerance) are checked in
:mod:`sarfe.case.normalize`. Defaults are applied in :func:`sarfe.case.normalize.normalize`.
"""
from __future__ import annotations

from sarfe.case.plausibility import POISSON_RANGE
from sarfe.hbm import laws


def _object(properties, required=(), **extra):
    return {"type": "object", "additionalProperties": False, "properties": properties,
            "required": list(required), **extra}


POSITIVE = {"type": "number", "exclusiveMinimum": 0}
NON_NEGATIVE = {"type": "number", "minimum": 0}
NUMBER = {"type": "number"}
NAME = {"type": "string", "minLength": 1}
INDEX = {"type": "integer", "minimum": 0}
VECTOR3 = {"type": "array", "items": NUMBER, "minItems": 3, "maxItems": 3}
# 'x', '-y', '+z' or a vector [x, y, z] (normalized by the case layer)
DIRECTION = {"type": ["string", "array"], "pattern": "^[-+]?[xyz]$",
             "items": NUMBER, "minItems": 3, "maxItems": 3}
# a DOF of a matrices model: an index, or {dof, relative_to, sign}: r = sign·(u[dof] − u[relative_to])
DOF_REFERENCE = {
    "type": ["integer", "object"], "minimum": 0,
    "additionalProperties": False, "required": ["dof"],
    "properties": {
        "dof": INDEX,
        "relative_to": {"type": ["integer", "string"], "minimum": 0, "pattern": "^ground$"},
        "sign": {"enum": [1, -1]},
    },
}
# a matrix: inline rows, or a file (.npz, .npy, .mtx) relative to the case file
MATRIX = {"type": ["string", "array"], "minLength": 1, "minItems": 1,
          "items": {"type": "array", "minItems": 1, "items": NUMBER}}
MATERIAL = _object({
    "E_Pa": POSITIVE,
    "nu": {"type": "number", "exclusiveMinimum": POISSON_RANGE[0],
           "exclusiveMaximum": POISSON_RANGE[1]},
    "rho_kg_m3": POSITIVE,
}, required=("E_Pa", "nu", "rho_kg_m3"))

GRID_IDS = {"type": "array", "items": {"type": "integer", "minimum": 1}, "minItems": 1}
SET_REFERENCE = {"type": ["string", "integer"], "minLength": 1, "minimum": 0}

FE_MODEL = _object({
    "mesh": NAME,
    # an engineer's own deck (Nastran .bdf/.dat/.nas/.fem, Abaqus .inp), read with its
    # properties, supports and loads (sarfe.pipeline.model.deck_model)
    "deck": NAME,
    "units": {"enum": ["SI", "mm-t-s", "mm-kg-ms", "mm-kg-s", "in-lbf-s", "ft-lbf-s"]},
    "ignore_cards": {"type": "array", "items": NAME, "uniqueItems": True},
    "supports": {"type": "array", "items": SET_REFERENCE, "minItems": 1},
    "node_groups": {"type": "object", "additionalProperties": {
        "oneOf": [GRID_IDS, SET_REFERENCE]}},
    "element_groups": {"type": "object", "additionalProperties": {
        "oneOf": [GRID_IDS, SET_REFERENCE]}},
    "generator": _object({
        "name": {"enum": ["door_trim", "instrument_panel", "squeak_rig", "rattle_rig"]},
        "mesh_size_m": POSITIVE,
        "params": {"type": "object"},
    }, required=("name", "mesh_size_m")),
    "mesh_units": {"enum": ["m", "mm"]},
    "materials": {"type": "object", "minProperties": 1, "additionalProperties": MATERIAL},
    "thickness_m": {"type": "object", "minProperties": 1, "additionalProperties": POSITIVE},
    "fixed": {"type": "array", "items": NAME, "minItems": 1},
})   # materials, thickness_m and fixed are required with mesh/generator (sarfe.case.normalize)

MATRICES_MODEL = _object({
    "mass": MATRIX,
    "stiffness": MATRIX,
    "damping": MATRIX,
}, required=("mass", "stiffness"))

DAMPING = _object({
    "modal_zeta": {
        "type": ["number", "array"], "minimum": 0, "exclusiveMaximum": 1, "minItems": 1,
        "items": _object({
            "modes": {"type": "array", "items": {"type": "integer", "minimum": 1},
                      "minItems": 2, "maxItems": 2},
            "zeta": {"type": "number", "minimum": 0, "exclusiveMaximum": 1},
        }, required=("modes", "zeta")),
    },
    "rayleigh": _object({"alpha_1_s": NON_NEGATIVE, "beta_s": NON_NEGATIVE},
                        required=("alpha_1_s", "beta_s")),
})

REDUCTION = _object({
    "mode_count": {"type": "integer", "minimum": 1},
    "cutoff_hz": POSITIVE,
    "cutoff_margin": {"type": "number", "minimum": 1},
    "min_mode_count": {"type": "integer", "minimum": 0},
    "residual_vectors": {"type": "boolean"},
})

def _law_key_schema(parameter):
    """JSON schema of one scalar law parameter from its declaration (bounds, number)."""
    schema = dict(NUMBER)
    if parameter.minimum is not None:
        schema["exclusiveMinimum" if parameter.exclusive else "minimum"] = parameter.minimum
    if parameter.maximum is not None:
        schema["maximum"] = parameter.maximum
    return schema


def contact_schema():
    """The contact object: geometry keys, then every registered law's keys from its declaration
    (:mod:`sarfe.hbm.laws`; which keys a type allows is checked in :mod:`sarfe.case.normalize`)."""
    law_keys = {}
    for law in laws.LAWS.values():
        for parameter in law.case_parameters():
            law_keys.setdefault(parameter.key, _law_key_schema(parameter))
        for key, schema in law.case_keys.items():
            law_keys.setdefault(key, schema)
    return _object({
        "name": {"type": "string", "pattern": "^[A-Za-z0-9_.-]+$"},
        "type": {"enum": list(laws.names())},
        # FE models: node groups
        "between": {"type": "array", "items": NAME, "minItems": 2, "maxItems": 2},
        "pairing_tolerance_m": NON_NEGATIVE,
        "pairs": {"type": "array", "minItems": 1,
                  "items": {"type": "array", "minItems": 2, "maxItems": 2,
                            "items": {"type": ["integer", "string"], "minimum": 0,
                                      "pattern": "^ground$"}}},
        # FE models: contact points by coordinates on two element groups (b may be 'ground')
        "points_m": {"type": "array", "minItems": 1,
                     "items": {"type": "array", "items": NUMBER, "minItems": 3, "maxItems": 3}},
        "surfaces": {"type": "array", "items": NAME, "minItems": 2, "maxItems": 2},
        "normal": {"type": ["string", "array"], "pattern": "^(auto|separation)$",
                   "items": NUMBER, "minItems": 3, "maxItems": 3},
        "patch_radius_m": POSITIVE,
        # FE decks: CBUSH/CELAS element ids turned into this contact (removed from the linear
        # model; their stiffness along element_axis is the penalty stiffness)
        "from_elements": {"type": "array", "items": {"type": "integer", "minimum": 1},
                          "minItems": 1, "uniqueItems": True},
        "element_axis": {"enum": [1, 2, 3]},
        # matrices models: DOFs
        "normal_dof": DOF_REFERENCE,
        "tangential_dofs": {"type": "array", "items": DOF_REFERENCE, "minItems": 1, "maxItems": 2},
        # every law: the initial gap or a static preload, the rattle tolerance
        "gap_m": NUMBER,
        "preload_N": NON_NEGATIVE,
        "tolerance_m": NON_NEGATIVE,
        # the laws' own keys
        **law_keys,
    }, required=("name", "type"))


CONTACT = contact_schema()

LOAD = _object({
    "group": NAME,
    "load_set": SET_REFERENCE,      # FE decks: a FORCE/MOMENT/DAREA/LOAD set or *CLOAD step
    "scale": NUMBER,                # multiplies the deck's load set (default 1)
    "dof": INDEX,
    "direction": DIRECTION,
    "force_N": NUMBER,
    "phase_deg": NUMBER,
})   # force_N is required except with load_set (sarfe.case.normalize)

EXCITATION = _object({
    "forces": {"type": "array", "items": LOAD, "minItems": 1},
    "base_acceleration": _object({
        "direction": DIRECTION,
        "amplitude_m_s2": NUMBER,
        "phase_deg": NUMBER,
        "influence": {"type": "array", "items": NUMBER, "minItems": 1},
    }, required=("amplitude_m_s2",)),
    "frequency_hz": {"type": ["number", "array"], "exclusiveMinimum": 0, "minItems": 1,
                     "items": POSITIVE},
    "sweep": _object({"start_hz": POSITIVE, "end_hz": POSITIVE}, required=("start_hz", "end_hz")),
})

SOLVER = _object({
    "harmonics": {"type": "integer", "minimum": 1, "maximum": 200},
    "samples_per_period": {"type": "integer", "minimum": 3},
    "tolerance": {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 1},
    "max_iterations": {"type": "integer", "minimum": 1},
    "stability": {"type": "boolean"},
    # accuracy as an input (sarfe.accuracy.resolve): a preset or a target, the error budget of the
    # run; with resolution 'auto' (the default when no harmonics are given) H, N, modes are chosen
    # for it, with 'fixed' the given H, N are used and an estimate above it is warned about
    "accuracy": {"oneOf": [{"enum": ["fast", "balanced", "fine"]},
                           _object({"erp_db": POSITIVE, "amplitude_rel": POSITIVE})]},
    "resolution": {"enum": ["auto", "fixed"]},
    "error_estimate": {"type": "boolean"},   # per-point error estimate (≈2 Newton steps a point)
    "harmonic_set": {"enum": ["all", "odd", "auto"]},   # orders solved for (sarfe.hbm.harmonic_set)
    # contacts that never switch over the frequencies solved linearly (sarfe.pipeline.solve.pruned_points)
    "prune_contacts": {"oneOf": [{"type": "boolean"}, _object({
        "margin": {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 1}})]},
    # processes for the per-point work after Newton (stability, estimates, records): sarfe.util.workers
    "workers": {"oneOf": [{"enum": ["auto"]}, {"type": "integer", "minimum": 1}]},
    # the mesh term of the ± (sarfe.pipeline.solve.mesh_error): 'auto' = on for generator meshes
    "mesh_error": {"oneOf": [{"enum": ["auto"]}, {"type": "boolean"}]},
    "continuation": _object({
        "initial_step": {"type": "number", "exclusiveMinimum": 0, "maximum": 1},
        "min_step": {"type": "number", "exclusiveMinimum": 0, "maximum": 1},
        "max_step": {"type": "number", "exclusiveMinimum": 0, "maximum": 1},
        "max_points": {"type": "integer", "minimum": 2},
        # linear points where every contact stays open/closed/stuck (sarfe.pipeline.solve.by_need)
        "linear_points": {"type": "boolean"},
    }),
})

ERP = _object({
    "surface": NAME,
    "dofs": {"type": "array", "items": INDEX, "minItems": 1},
    "areas_m2": {"type": "array", "items": POSITIVE, "minItems": 1},
    "rho_kg_m3": POSITIVE,
    "c_m_s": POSITIVE,
    "radiation_loss_factor": {"type": "number", "exclusiveMinimum": 0, "maximum": 10},
    "reference_power_W": POSITIVE,
})

OUTPUT_FILES = ["summary", "response", "erp_vtu", "animation", "plots", "table", "report", "sound"]
OUTPUT = _object({
    "directory": NAME,
    "target_dba": NUMBER,   # optional target level [dB(A)]: a line in the plots and the report
    "files": {"type": "array", "items": {"enum": OUTPUT_FILES}, "uniqueItems": True},
    # which points get an ERP map (sarfe.pipeline.write.map_points): the loudest, every N-th, or
    # the points nearest the listed frequencies [Hz] (the loudest always)
    "maps": {"oneOf": [{"enum": ["loudest"]}, _object({"every": {"type": "integer", "minimum": 1}},
                                                      required=("every",)),
                       {"type": "array", "items": POSITIVE, "minItems": 1}]},
})

# will the occupant hear it (sarfe.case.config.AudibilityConfig, docs/audibility.md): the cabin
# from the ERP to the ear, the background noise it must be heard over, the loudness field
ABSORPTION = {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 1}
AUDIBILITY = _object({
    "background": NAME,         # a shipped spectrum's name, a CSV file, or 'none'
    "loudness_field": {"enum": ["diffuse", "free"]},
    "sound_duration_s": {"type": "number", "exclusiveMinimum": 0, "maximum": 60},
    "cabin": _object({
        "distance_m": POSITIVE,
        "volume_m3": POSITIVE,
        "surface_m2": POSITIVE,
        "absorption": {"oneOf": [ABSORPTION, {"type": "array", "items": ABSORPTION,
                                              "minItems": 1}]},
        "absorption_band_hz": {"type": "array", "items": POSITIVE, "minItems": 1},
        "directivity": POSITIVE,
    }),
})

CASE_SCHEMA = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "$id": "https://sarfe.example/case.schema.json",
    "title": "sarfe case file",
    **_object({
        "name": {"type": "string", "pattern": "^[A-Za-z0-9_.-]+$"},
        "description": {"type": "string"},
        "model": _object({"fe": FE_MODEL, "matrices": MATRICES_MODEL},
                         minProperties=1, maxProperties=1),
        "damping": DAMPING,
        "reduction": REDUCTION,
        "contacts": {"type": "array", "items": CONTACT},
        "excitation": EXCITATION,
        "solver": SOLVER,
        "erp": ERP,
        "output": OUTPUT,
        "audibility": AUDIBILITY,
    }, required=("name", "model", "excitation")),
}
