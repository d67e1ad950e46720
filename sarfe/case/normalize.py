"""Cross-key rules and defaults of a schema-valid case: ``normalize(case)`` checks what one key
means for another (exactly one of two keys, keys a contact's law allows, a node and its DOFs) and
fills every default into ``case.data``, so the normalized mapping says everything the run uses.
The defaults themselves are the field defaults of :mod:`sarfe.case.config`; each section has its
function (``_normalize_model`` … ``_normalize_output``). Raises CaseError (one line, key path and
line of the case file).
"""
from __future__ import annotations

import math

from sarfe.case.config import (DEFAULT_ACCURACY, DEFAULT_ZETA, MATRICES_GAP_M, NO_BACKGROUND,
                               AudibilityConfig, CabinConfig,
                               BaseAccelerationConfig, ContactConfig, ContinuationConfig,
                               DeckConfig, DofReference, ErpConfig, FeConfig, ForceConfig,
                               GeneratorConfig, OutputConfig, ReductionConfig, SolverConfig,
                               default_of,
                               default_output_directory, default_output_files,
                               default_samples_per_period)
from sarfe.case.errors import format_key_path
from sarfe.case.plausibility import check_plausible
from sarfe.erp.backgrounds import BackgroundFileError, background_names, load_background
from sarfe.erp.cabin import Cabin
from sarfe.hbm import laws

MESH_SUFFIXES = (".msh", ".bdf", ".nas", ".dat", ".inp")
DECK_SUFFIXES = (".bdf", ".nas", ".dat", ".fem", ".inp")
DECK_KEYS = ("units", "ignore_cards", "supports", "node_groups", "element_groups")
MATRIX_SUFFIXES = (".npz", ".npy", ".mtx")


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


def _case_file(case, name, suffixes, kind, path):
    """A file named in the case (relative to it) with one of ``suffixes`` that exists, else a
    CaseError at ``path`` ('<kind> file must be one of …' / '<kind> file not found: …')."""
    file = case.resolve(name)
    if file.suffix.lower() not in suffixes:
        raise case.error(f"{kind} file must be one of {', '.join(suffixes)}, got '{file.name}'",
                         path)
    if not file.is_file():
        raise case.error(f"{kind} file not found: {file}", path)
    return file


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
        fe.setdefault("mesh_units", default_of(FeConfig, "mesh_units"))
        if source == "mesh":
            _case_file(case, fe["mesh"], MESH_SUFFIXES, "mesh", p + ("mesh",))
        else:
            fe["generator"].setdefault("params", default_of(GeneratorConfig, "params"))
            if "mesh_units" in fe and fe["mesh_units"] != "m":
                raise case.error("generated meshes are in metres; mesh_units must be 'm'",
                                 p + ("mesh_units",))
    else:
        mat = model["matrices"]
        p = ("model", "matrices")
        for key in ("mass", "stiffness", "damping"):
            if isinstance(mat.get(key), str):
                _case_file(case, mat[key], MATRIX_SUFFIXES, "matrix", p + (key,))
        # an empty damping section is what normalizing a case with its own damping matrix leaves
        # (so a normalized case, e.g. after solver.accuracy chose H, loads again)
        if "damping" in mat and data.get("damping"):
            raise case.error("give either model.matrices.damping or a damping section, not both",
                             ("damping",))
        _not_allowed(case, data, (), ("reduction",), "with model.matrices (no reduction)")


def _normalize_deck(case, fe, p):
    """model.fe.deck: the file exists and is a deck; ignore_cards, groups defaults."""
    _case_file(case, fe["deck"], DECK_SUFFIXES, "deck", p + ("deck",))
    _not_allowed(case, fe, p, ("mesh_units",), "with model.fe.deck (use 'units')")
    # ``units`` stays absent when the case does not give it (DeckConfig's default SI applies):
    # the deck's units check yields to an explicit ``units:`` only (deck_checks.units_given)
    for key in ("ignore_cards", "node_groups", "element_groups"):
        fe.setdefault(key, default_of(DeckConfig, key))


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
            if not any(k in contact for k in ("between", "pairs", "from_elements", "points_m")):
                raise case.error("missing required key (node groups [a, b] or [a, ground], "
                                 "or explicit node 'pairs', or contact 'points_m' with "
                                 "'surfaces', or deck 'from_elements')", p + ("between",))
            _only_one(case, contact, p, ("between", "pairs", "from_elements", "points_m"))
            if "points_m" in contact and "surfaces" not in contact:
                raise case.error("missing required key (the element groups [a, b] or "
                                 "[a, ground] the points_m lie on)", p + ("surfaces",))
            if "surfaces" in contact and not any(k in contact for k in ("between", "points_m")):
                raise case.error("only with between or points_m", p + ("surfaces",))
            if "surfaces" in contact and contact["surfaces"][0] == "ground":
                raise case.error("the first surface cannot be 'ground'", p + ("surfaces", 0))
            if "from_elements" in contact:
                _not_allowed(case, contact, p, ("normal", "patch_radius_m"),
                             "with from_elements (the spring axis is the normal)")
            if "element_axis" in contact and "from_elements" not in contact:
                raise case.error("only with from_elements", p + ("element_axis",))
            if "between" in contact and contact["between"][0] == "ground":
                raise case.error("the first group cannot be 'ground'", p + ("between", 0))
            if "between" in contact and contact["between"][0] == contact["between"][1]:
                raise case.error(f"group '{contact['between'][0]}' is on both sides: a contact "
                                 "joins two different groups (or a group and 'ground')",
                                 p + ("between", 1))
            for j, pair in enumerate(contact.get("pairs", [])):
                if pair[0] == pair[1]:
                    raise case.error(f"node {pair[0]} is paired with itself (a pair joins two "
                                     "different nodes, or a node and 'ground')", p + ("pairs", j))
            for key in ("pairing_tolerance_m", "normal", "patch_radius_m"):
                contact.setdefault(key, default_of(ContactConfig, key))
            has_normal = True
        else:
            _not_allowed(case, contact, p, ("between", "pairs", "normal", "pairing_tolerance_m",
                                            "points_m", "surfaces", "patch_radius_m"),
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
                for key in ("relative_to", "sign"):
                    ref.setdefault(key, default_of(DofReference, key))
            _check_contact_dofs(case, contact, p)
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
            contact.setdefault("gap_m", MATRICES_GAP_M)  # FE: the geometric gap of each pair
        contact.setdefault("tolerance_m", default_of(ContactConfig, "tolerance_m"))


def _check_contact_dofs(case, contact, p):
    """A matrices contact's DOFs: none measured against itself (r = u[d] − u[d] ≡ 0), no
    direction given twice (the same relative displacement as two tangents, or as the normal and
    a tangent: its force would count twice)."""
    refs = ([(("normal_dof",), contact["normal_dof"])] if "normal_dof" in contact else []) + [
        (("tangential_dofs", j), ref) for j, ref in enumerate(contact.get("tangential_dofs", []))]
    seen = {}
    for path, ref in refs:
        if ref["relative_to"] == ref["dof"]:
            raise case.error(f"DOF {ref['dof']} is measured relative to itself (a relative "
                             "displacement that is always 0)", p + path + ("relative_to",))
        key = frozenset((ref["dof"], ref["relative_to"]))     # u0 − u1 and u1 − u0 alike
        if key in seen:
            first = format_key_path(p + seen[key])
            raise case.error(f"DOF {ref['dof']} (relative to {ref['relative_to']}) is already "
                             f"{first}: each direction of a contact is a different relative "
                             "displacement", p + path)
        seen[key] = path


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
                load["force_N"] = float(load.setdefault(       # the amplitude factor
                    "scale", default_of(ForceConfig, "scale")))
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
            load.setdefault("phase_deg", default_of(ForceConfig, "phase_deg"))
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
        base.setdefault("phase_deg", default_of(BaseAccelerationConfig, "phase_deg"))


def _normalize_solver(case, data):
    solver = data.setdefault("solver", {})
    # no harmonics given: sarfe chooses H, N (and the mode count) for the accuracy budget
    # (default 'balanced'), starting its screening from H = 5; given harmonics are used as they are
    solver.setdefault("resolution", "fixed" if "harmonics" in solver
                      else default_of(SolverConfig, "resolution"))
    if solver["resolution"] == "auto":
        solver.setdefault("accuracy", DEFAULT_ACCURACY)
    H = solver.setdefault("harmonics", default_of(SolverConfig, "harmonics"))
    N = solver.setdefault("samples_per_period", default_samples_per_period(H))
    if N < 2 * H + 1:
        raise case.error(f"must be >= 2H+1 = {2 * H + 1} for harmonics H = {H}, got {N}",
                         ("solver", "samples_per_period"))
    for key in ("tolerance", "max_iterations", "stability", "error_estimate", "harmonic_set",
                "prune_contacts", "workers", "mesh_error"):   # defaults: sarfe.case.config.SolverConfig
        solver.setdefault(key, default_of(SolverConfig, key))
    generated = "generator" in data.get("model", {}).get("fe", {})
    if solver["mesh_error"] is True and not generated:     # sarfe.pipeline.solve.mesh_error
        raise case.error("true needs a generated mesh (model.fe.generator) to coarsen; use "
                         "'auto' or false", ("solver", "mesh_error"))
    cont = solver.setdefault("continuation", {})
    for key in ("initial_step", "min_step", "max_step", "max_points", "linear_points"):
        cont.setdefault(key, default_of(ContinuationConfig, key))
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
        red.setdefault(key, default_of(ReductionConfig, key))


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
        erp.setdefault(key, default_of(ErpConfig, key))


def _normalize_output(case, data):
    out = data.setdefault("output", {})
    out.setdefault("directory", default_output_directory(data["name"]))
    out.setdefault("files", default_output_files(case.is_fe))
    out.setdefault("maps", default_of(OutputConfig, "maps"))
    if "summary" not in out["files"]:
        out["files"] = ["summary"] + list(out["files"])


def _normalize_audibility(case, data):
    """audibility: defaults (sarfe.case.config.AudibilityConfig, CabinConfig); the background is
    read here, so `validate` finds a bad file: a shipped name stays a name, a file is resolved
    against the case file's folder (the normalized case holds its absolute path); the cabin must
    make a valid :class:`sarfe.erp.cabin.Cabin` (one absorption per band centre, increasing)."""
    section = data.setdefault("audibility", {})
    p = ("audibility",)
    for key in ("background", "loudness_field", "sound_duration_s"):
        section.setdefault(key, default_of(AudibilityConfig, key))
    cabin = section.setdefault("cabin", {})
    for key in ("distance_m", "volume_m3", "surface_m2", "absorption", "directivity"):
        cabin.setdefault(key, default_of(CabinConfig, key))
    background = section["background"]
    if background != NO_BACKGROUND:
        shipped = background in background_names()
        if not shipped:
            file = case.resolve(background)
            if not file.is_file():
                raise case.error(f"background {background!r}: neither a shipped spectrum "
                                 f"({', '.join(background_names())}), 'none' nor a file "
                                 f"(looked for {file})", p + ("background",))
            section["background"] = background = str(file)
        try:
            load_background(background)
        except BackgroundFileError as error:
            raise case.error(f"background: {error}", p + ("background",)) from None
    absorption = cabin["absorption"]
    bands = cabin.get("absorption_band_hz")
    if isinstance(absorption, list) and bands is None and len(absorption) > 1:
        raise case.error("a list of absorption coefficients needs 'absorption_band_hz' (one "
                         "band centre per value)", p + ("cabin", "absorption"))
    try:
        Cabin(volume_m3=cabin["volume_m3"], surface_m2=cabin["surface_m2"],
              absorption=absorption, absorption_band_hz=bands or (),
              directivity=cabin["directivity"], distance_m=cabin["distance_m"])
    except ValueError as error:
        key = "absorption_band_hz" if "band" in str(error) else "absorption"
        raise case.error(str(error).replace("Cabin.", "audibility.cabin."),
                         p + ("cabin", key)) from None


def normalize(case):
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
    _normalize_audibility(case, data)
    check_plausible(case, data)
    return case


__all__ = ["normalize", "direction_vector", "MESH_SUFFIXES", "DECK_SUFFIXES", "MATRIX_SUFFIXES"]
