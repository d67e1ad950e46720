r"""The linear stage of a case: model → (reduced) M, K on the kept DOFs, contact geometry in those
DOFs, unit excitation vectors and the ERP recovery map. Everything here is independent of the
contact law parameters, damping, force amplitudes and frequencies, so a batch over those reuses it.

FE path (a deck file: :mod:`sarfe.pipeline.model.deck_model`, :mod:`sarfe.pipeline.model.deck_stage`): mesh → shell K, M (per-triangle thickness/material) → remove fixed (clip/clamp) DOFs →
Craig–Bampton with boundary = translations of contact and excitation nodes:

    u = T q,  q = [q_b, q_m],  M_r = Tᵀ M T,  K_r = Tᵀ K T,  f_r = Tᵀ f,

contact rows w = n·(u_a − u_b), q_i = t_i·(u_a − u_b) touch boundary coordinates only, and the
radiating-surface normal displacement is w_s = N q (N = ``normal_velocity_basis``).
Matrices path: M, K (and D) as given, no reduction.
"""
from __future__ import annotations

import fnmatch
import hashlib
import importlib
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from sarfe.case.read import SPAN_RANGE_M, Case, load_case
from sarfe.case.errors import CaseError


@dataclass(frozen=True)
class ContactGeometry:
    """Node pairs of one named contact (FE) and their local frames.

    nodes_a, nodes_b (n_p,) mesh node indices (b = −1 for ground); frames (n_p, 3, 3) rows
    [normal, tangent 1, tangent 2] (unit, normal from a towards b); coords_a, coords_b (n_p, 3)
    reduced coordinate of each translation ux, uy, uz (−1 where fixed or ground).
    """

    name: str
    nodes_a: np.ndarray
    nodes_b: np.ndarray
    frames: np.ndarray
    coords_a: np.ndarray
    coords_b: np.ndarray
    distances: np.ndarray      # (n_p,) [m] n·(x_b − x_a), the geometric gap (0 for ground)
    # (n_p,) [N/m] per-pair stiffness of deck springs turned into this contact (from_elements)
    normal_stiffness: np.ndarray | None = None
    tangential_stiffness: np.ndarray | None = None


@dataclass(frozen=True)
class LinearStage:
    """Picklable linear part of a case (see module docstring). n_r kept DOFs, SI units.

    mass, stiffness (n_r, n_r) [kg], [N/m] dense or sparse; damping (n_r, n_r) [N s/m] or None (the
    matrices path's own D; FE damping is applied per case in :func:`solve_case`).
    load_vectors (n_loads, n_r): force on q per 1 N of each ``excitation.forces`` entry (direction
    included); base_vector (n_r,) or None: −Tᵀ M ι per 1 m/s² base acceleration.
    contacts: {name: ContactGeometry} (FE) — matrices contacts are built from the case directly.
    erp_map (n_s, n_r): normal displacement of the radiating nodes w_s = erp_map q; erp_areas (n_s,)
    [m²]; erp_nodes (n_s,) mesh nodes (FE) or DOFs (matrices).
    """

    key: str
    kind: str
    mass: object
    stiffness: object
    damping: object
    load_vectors: np.ndarray
    base_vector: np.ndarray | None
    contacts: dict
    erp_map: np.ndarray
    erp_areas: np.ndarray
    erp_nodes: np.ndarray
    mesh: object = None
    reduced: object = None
    mode_frequencies_hz: np.ndarray = field(default_factory=lambda: np.zeros(0))
    info: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    node_ids: np.ndarray | None = None     # deck GRID / node id of each mesh point (deck path)
    added_damping: np.ndarray | None = None  # (n_r, n_r) [N s/m] a deck's dampers (CBUSH B), reduced

    @property
    def dof_count(self) -> int:
        return self.mass.shape[0]


# -------------------------------------------------------------------------------------- hashing
def _file_digest(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def default_cutoff_hz(config) -> float:
    """Reduction cutoff [Hz] when none is given: margin · H · f_max (``reduction.cutoff_margin``,
    1.0 by default: every kept harmonic has the modes up to its frequency, the modes above answer
    quasi-statically through the residual vectors; measured on the door trim, H = 15, against
    2 H f_max: contact amplitudes ≤ 1.7e-4, ERP ≤ 0.012 dB(A), and the error estimate's modal part
    brackets it: :class:`sarfe.case.config.ReductionConfig`).
    ``config``: the case's CaseConfig (or the Case)."""
    config = getattr(config, "config", config)
    return (config.reduction.cutoff_margin * config.solver.harmonics
            * config.excitation.max_frequency_hz)


def _reduction_key(reduction: dict, config) -> dict:
    """The reduction settings a stage depends on: the given ones, plus the default cutoff (which
    follows H and f_max) only when neither cutoff_hz nor mode_count is given."""
    if "cutoff_hz" in reduction or "mode_count" in reduction:
        return dict(reduction)
    return dict(reduction, effective_cutoff_hz=default_cutoff_hz(config))


def linear_model_key(case) -> str:
    """SHA-256 of everything the linear stage depends on (mesh bytes or generator parameters,
    materials, thicknesses, fixed groups, reduction, contact node sets and normals, excitation
    DOFs/groups and directions, ERP surface). Same key → :func:`build_linear_model` is reusable.
    """
    case = load_case(case)
    data = case.data
    model = json.loads(json.dumps(data["model"]))
    for section in model.values():
        for key in ("mesh", "deck", "mass", "stiffness", "damping"):
            if key == "deck" and isinstance(section.get(key), str):   # with its INCLUDEs
                from sarfe.pipeline.model.deck_model import deck_files
                section[key] = {"file_sha256": [_file_digest(f) for f in
                                                deck_files(case.resolve(section[key]))]}
            elif isinstance(section.get(key), str):
                section[key] = {"file_sha256": _file_digest(case.resolve(section[key]))}
    exc = data["excitation"]
    parts = {
        "model": model,
        "reduction": _reduction_key(data.get("reduction", {}), case.config) if case.is_fe else None,
        "contacts": [{k: c.get(k) for k in ("name", "between", "pairs", "pairing_tolerance_m",
                                            "normal", "normal_dof", "tangential_dofs",
                                            "from_elements", "element_axis")}
                     for c in data["contacts"]],
        "forces": [{k: f.get(k) for k in ("group", "dof", "direction", "load_set")}
                   for f in exc.get("forces", [])],
        "base": {k: v for k, v in exc["base_acceleration"].items() if k in ("direction", "influence")}
        if "base_acceleration" in exc else None,
        "erp": {k: data["erp"].get(k) for k in ("surface", "dofs", "areas_m2")},
        "sarfe_linear_stage": 1,
    }
    text = json.dumps(parts, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


# ------------------------------------------------------------------------------- matrices path
def _read_matrix(case: Case, key):
    path_key = ("model", "matrices", key)
    value = case.config.model.matrices.entry(key)
    if not isinstance(value, str):
        rows = [len(r) for r in value]
        if any(n != len(value) for n in rows):
            raise case.error(f"must be a square matrix (list of {len(value)} rows of "
                             f"{len(value)} numbers)", path_key)
        return np.asarray(value, dtype=float)
    path = case.resolve(value)
    try:
        suffix = path.suffix.lower()
        if suffix == ".mtx":
            import scipy.io   # Matrix Market files only

            matrix = sp.csr_matrix(scipy.io.mmread(str(path)))
        elif suffix == ".npy":
            matrix = np.load(path, allow_pickle=False)
        else:
            try:
                matrix = sp.load_npz(path).tocsr()
            except (ValueError, KeyError, OSError):
                with np.load(path, allow_pickle=False) as archive:
                    names = list(archive.files)
                    name = key if key in names else (names[0] if len(names) == 1 else None)
                    if name is None:
                        raise CaseError(f"{path.name} holds arrays {names}; none is named '{key}'")
                    matrix = archive[name]
    except CaseError as exc:
        raise case.error(exc.message, path_key) from None
    except Exception as exc:  # unreadable file of any kind
        if "allow_pickle" in str(exc) or "pickled" in str(exc):   # numpy's advice to unpickle
            with open(path, "rb") as handle:
                head = handle.read(6)
            what = ("holds pickled Python objects, which sarfe does not load"
                    if head.startswith((b"PK", b"\x93NUMPY")) or head[:1] == b"\x80"
                    else "is not a NumPy .npy/.npz file (no zip or NPY header): corrupt or "
                         "another format")
            raise case.error(f"cannot read matrix file {path}: it {what}; save the matrix with "
                             "numpy.save / numpy.savez or scipy.sparse.save_npz", path_key) from None
        raise case.error(f"cannot read matrix file {path}: {exc}", path_key) from None
    if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1]:
        raise case.error(f"must be a square matrix, file holds shape {matrix.shape}", path_key)
    return matrix


def _check_dof(case, dof, n, path):
    if dof != "ground" and not 0 <= dof < n:
        raise case.error(f"DOF {dof} out of range (the model has {n} DOFs: 0…{n - 1})", path)


def _build_matrices(case: Case, progress=False) -> dict:
    config = case.config
    mass = _read_matrix(case, "mass")
    stiffness = _read_matrix(case, "stiffness")
    damping = _read_matrix(case, "damping") if config.model.matrices.entry("damping") is not None \
        else None
    n = mass.shape[0]
    for key, matrix in (("stiffness", stiffness), ("damping", damping)):
        if matrix is not None and matrix.shape != (n, n):
            raise case.error(f"has shape {matrix.shape}, mass has ({n}, {n})",
                             ("model", "matrices", key))
    from sarfe.hbm.model import make_linear_model
    try:
        make_linear_model(mass, damping, stiffness)
    except ValueError as exc:
        word = str(exc).split()[0]
        key = word if word in ("mass", "stiffness", "damping") else "mass"
        raise case.error(str(exc), ("model", "matrices", key)) from None
    for i, contact in ((c.index, c.params) for c in config.contacts):
        refs = ([("normal_dof", contact["normal_dof"])] if "normal_dof" in contact else []) + [
            (("tangential_dofs", j), t) for j, t in enumerate(contact.get("tangential_dofs", []))]
        for key, ref in refs:
            key = key if isinstance(key, tuple) else (key,)
            _check_dof(case, ref["dof"], n, ("contacts", i) + key + ("dof",))
            _check_dof(case, ref["relative_to"], n, ("contacts", i) + key + ("relative_to",))
            if ref["relative_to"] == ref["dof"]:
                raise case.error("a DOF cannot be relative to itself",
                                 ("contacts", i) + key + ("relative_to",))
    exc = config.excitation
    loads = np.zeros((len(exc.forces), n))
    for i, load in enumerate(exc.forces):
        _check_dof(case, load["dof"], n, ("excitation", "forces", i, "dof"))
        loads[i, load["dof"]] = 1.0
    base = None
    if exc.base_acceleration is not None:
        influence = np.asarray(exc.base_acceleration.get("influence", np.ones(n)), dtype=float)
        if influence.shape != (n,):
            raise case.error(f"needs {n} entries (one per DOF), got {len(influence)}",
                             ("excitation", "base_acceleration", "influence"))
        base = -(mass @ influence)
    erp = config.erp
    dofs = np.asarray(erp.dofs or [], dtype=int)
    for j, dof in enumerate(dofs):
        _check_dof(case, int(dof), n, ("erp", "dofs", j))
    erp_map = np.zeros((len(dofs), n))
    erp_map[np.arange(len(dofs)), dofs] = 1.0
    return dict(kind="matrices", mass=mass, stiffness=stiffness, damping=damping,
                load_vectors=loads, base_vector=base, contacts={}, erp_map=erp_map,
                erp_areas=np.asarray(erp.areas_m2 or [], dtype=float), erp_nodes=dofs,
                info={"dofs": n})


# ------------------------------------------------------------------------------------- FE path
def _generate_mesh(name, mesh_size, params):
    """sarfe.mesh.generators.<name>.generate(mesh_size=..., **params) → PanelMesh, through the
    checksummed mesh cache (sarfe.mesh.cache: generated once per parameter set)."""
    from sarfe.mesh.cache import cached_mesh
    from sarfe.mesh.generators import GENERATORS

    if name not in GENERATORS:
        importlib.import_module(f"sarfe.mesh.generators.{name}")  # ImportError names it
    return cached_mesh(name, mesh_size, **params)


def _check_generator_params(case: Case, gen) -> None:
    """An unknown key in model.fe.generator.params → CaseError naming it and the valid ones."""
    import difflib

    from sarfe.mesh.generators import GENERATORS, parameter_names

    if gen["name"] not in GENERATORS:
        return
    valid = parameter_names(gen["name"])
    for key in gen["params"]:
        if key not in valid:
            close = difflib.get_close_matches(str(key), valid, n=1)
            hint = f"did you mean '{close[0]}'? " if close else ""
            raise case.error(f"unknown parameter of generator {gen['name']} ({hint}valid: "
                             f"{', '.join(valid)})", ("model", "fe", "generator", "params", key))


def load_case_mesh(case: Case):
    """The case's PanelMesh (file or generator), in metres; errors name model.fe.mesh/generator."""
    from sarfe.mesh import load_mesh

    fe = case.config.model.fe.data
    if "mesh" in fe:
        path = case.resolve(fe["mesh"])
        try:
            mesh = load_mesh(path, length_unit=fe["mesh_units"])
        except Exception as exc:
            raise case.error(f"cannot read mesh file {path}: {exc}", ("model", "fe", "mesh")) from None
        where = ("model", "fe", "mesh_units")
    else:
        gen = fe["generator"]
        _check_generator_params(case, gen)
        try:
            mesh = _generate_mesh(gen["name"], gen["mesh_size_m"], gen["params"])
        except ImportError as exc:
            raise case.error(f"mesh generator '{gen['name']}' is not available ({exc})",
                             ("model", "fe", "generator", "name")) from None
        except TypeError as exc:
            raise case.error(f"generator rejected a parameter: {exc}",
                             ("model", "fe", "generator", "params")) from None
        except ValueError as exc:
            raise case.error(str(exc), ("model", "fe", "generator")) from None
        where = ("model", "fe", "generator")
    if mesh.n_triangles == 0:
        raise case.error("the mesh has no shell triangles", where[:3])
    extent = float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
    if extent > SPAN_RANGE_M[1]:
        raise case.error(f"the mesh spans {extent:.3g} m — are its coordinates in mm? "
                         "(set mesh_units: mm)", where)
    if extent < SPAN_RANGE_M[0]:
        raise case.error(f"the mesh spans only {extent:.3g} m — are its coordinates in metres "
                         "while mesh_units says mm?", where)
    return mesh


def _available(names):
    names = sorted(names)
    text = ", ".join(names[:30]) + (", …" if len(names) > 30 else "")
    return text or "none"


def resolve_node_group(case, mesh, name, path, allow_elements=True):
    """Node indices of a node group (or the nodes of an element group); glob patterns allowed."""
    matches = [g for g in mesh.node_groups if fnmatch.fnmatchcase(g, name)]
    nodes = [mesh.node_groups[g] for g in matches]
    if not matches and allow_elements:
        elems = [g for g in mesh.element_groups if fnmatch.fnmatchcase(g, name)]
        nodes = [np.unique(mesh.triangles[mesh.element_groups[g]]) for g in elems]
        matches = elems
    if not matches:
        raise case.error(f"node group '{name}' not in mesh (available: "
                         f"{_available(mesh.node_groups)})", path)
    result = np.unique(np.concatenate(nodes)) if nodes else np.zeros(0, int)
    if result.size == 0:
        raise case.error(f"node group '{name}' is empty", path)
    return result


def _per_triangle(case, mesh, mapping, key):
    """Index into list(mapping) per triangle; later keys override earlier ones."""
    owner = np.full(mesh.n_triangles, -1)
    for j, name in enumerate(mapping):
        if name == "*":
            owner[:] = j
            continue
        groups = [g for g in mesh.element_groups if fnmatch.fnmatchcase(g, name)]
        if not groups:
            raise case.error(f"element group '{name}' not in mesh (available: "
                             f"{_available(mesh.element_groups)}, or '*' for all)",
                             ("model", "fe", key, name))
        for g in groups:
            owner[mesh.element_groups[g]] = j
    missing = np.count_nonzero(owner < 0)
    if missing:
        raise case.error(f"{missing} of {mesh.n_triangles} triangles belong to no listed element "
                         f"group (add '*' for a default; groups: {_available(mesh.element_groups)})",
                         ("model", "fe", key))
    return owner


def frame_from_normal(normals):
    """Rows [n, t1, t2] (…, 3, 3) of right-handed orthonormal frames around unit normals (…, 3)."""
    n = np.asarray(normals, dtype=float)
    axis = np.eye(3)[np.argmin(np.abs(n), axis=-1)]
    t1 = np.cross(n, axis)
    t1 /= np.linalg.norm(t1, axis=-1, keepdims=True)
    t2 = np.cross(n, t1)
    return np.stack([n, t1, t2], axis=-2)


def pair_contact(case, mesh, index, normals_all):
    """Node pairs and frames of contacts[index] (nearest-node pairing or explicit pairs)."""
    from scipy.spatial import cKDTree

    contact = case.config.contacts[index].params
    p = ("contacts", index)
    points = mesh.points
    if "pairs" in contact:
        pairs = contact["pairs"]
        a = np.array([q[0] for q in pairs])
        for j, (na, nb) in enumerate(pairs):
            for k, node in enumerate((na, nb)):
                if node == "ground":
                    if k == 0:
                        raise case.error("the first node cannot be 'ground'", p + ("pairs", j, 0))
                    continue
                if not 0 <= node < mesh.n_nodes:
                    raise case.error(f"node {node} out of range (mesh has {mesh.n_nodes} nodes)",
                                     p + ("pairs", j, k))
        a = np.array([q[0] for q in pairs], dtype=int)
        b = np.array([-1 if q[1] == "ground" else q[1] for q in pairs], dtype=int)
    else:
        group_a, group_b = contact["between"]
        a = resolve_node_group(case, mesh, group_a, p + ("between", 0))
        if group_b == "ground":
            b = np.full(len(a), -1)
        else:
            nodes_b = resolve_node_group(case, mesh, group_b, p + ("between", 1))
            distance, nearest = cKDTree(points[nodes_b]).query(points[a])
            tolerance = contact["pairing_tolerance_m"]
            far = distance > tolerance * (1 + 1e-9) + 1e-12
            if np.any(far):
                worst = int(np.argmax(distance))
                raise case.error(
                    f"{np.count_nonzero(far)} of {len(a)} nodes of '{group_a}' have no node of "
                    f"'{group_b}' within pairing_tolerance_m = {tolerance:g} m (farthest: node "
                    f"{a[worst]} at {distance[worst]:.3g} m)", p + ("between",))
            b = nodes_b[nearest]
    offset = np.where(b[:, None] >= 0, points[np.maximum(b, 0)] - points[a], 0.0)
    separation = np.linalg.norm(offset, axis=1)
    if contact["normal"] == "auto":
        normal = normals_all[a].copy()
        if np.any(np.linalg.norm(normal, axis=1) < 0.5):
            raise case.error("node(s) with no surface normal (not on any shell triangle); give "
                             "normal: [x, y, z]", p + ("normal",))
        apart = separation > 1e-9
        flip = apart & (np.einsum("ij,ij->i", normal, offset) < 0)
        normal[flip] *= -1.0
    else:
        vector = np.asarray(contact["normal"], dtype=float)
        length = np.linalg.norm(vector)
        if length == 0 or not np.isfinite(length):
            raise case.error("normal vector must be non-zero", p + ("normal",))
        normal = np.broadcast_to(vector / length, (len(a), 3))
    # geometric gap along the normal (the default gap of the pair; 0 for coincident nodes)
    distance = np.einsum("ij,ij->i", normal, offset)
    return a, b, frame_from_normal(normal), distance


def _mesh_groups(case: Case, config, mesh) -> tuple:
    """Linear stage, step 1 (after the mesh): the node groups the case names — fixed nodes,
    contact pairs {name: (a, b, frames, distance)}, load nodes per force — and the radiating
    triangles. Cheap, and the errors a user is most likely to make, so they come first."""
    from sarfe.erp import nodal_normals

    fe = config.model.fe.data
    fixed_nodes = np.unique(np.concatenate([
        resolve_node_group(case, mesh, g, ("model", "fe", "fixed", i), allow_elements=False)
        for i, g in enumerate(fe["fixed"])]))
    normals_all = nodal_normals(mesh.points, mesh.triangles)
    paired = {c.name: pair_contact(case, mesh, c.index, normals_all) for c in config.contacts}
    load_nodes = [resolve_node_group(case, mesh, f["group"], ("excitation", "forces", i, "group"))
                  for i, f in enumerate(config.excitation.forces)]
    return fixed_nodes, paired, load_nodes, _radiating_triangles(case, config.erp, mesh)


def _radiating_triangles(case: Case, erp, mesh) -> np.ndarray:
    """Triangles (n_t, 3) of the radiating surface: erp.surface (an element group, or the whole
    triangles of a node group), else the 'skin' group, else every triangle."""
    surface = erp.surface
    if surface is not None:
        if surface in mesh.element_groups:
            return mesh.triangles[mesh.element_groups[surface]]
        nodes = resolve_node_group(case, mesh, surface, ("erp", "surface"))
        inside = np.zeros(mesh.n_nodes, bool)
        inside[nodes] = True
        triangles = mesh.triangles[inside[mesh.triangles].all(axis=1)]
        if len(triangles) == 0:
            raise case.error(f"node group '{surface}' contains no whole triangle", ("erp", "surface"))
        return triangles
    if "skin" in mesh.element_groups:
        return mesh.triangles[mesh.element_groups["skin"]]
    return mesh.triangles


def _assemble(case: Case, fe, mesh) -> tuple:
    """Linear stage, step 2: shell stiffness and mass (6 n_nodes square, sparse) from the
    per-triangle materials (E_Pa, nu, rho_kg_m3) and thickness_m."""
    from sarfe.fe.shell import shell_matrices

    materials, thickness = fe["materials"], fe["thickness_m"]
    mat_owner = _per_triangle(case, mesh, materials, "materials")
    thick_owner = _per_triangle(case, mesh, thickness, "thickness_m")
    mats = list(materials.values())
    young = np.array([m["E_Pa"] for m in mats])[mat_owner]
    poisson = np.array([m["nu"] for m in mats])[mat_owner]
    density = np.array([m["rho_kg_m3"] for m in mats])[mat_owner]
    t = np.array(list(thickness.values()), dtype=float)[thick_owner]
    extent = float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
    if t.max() > 0.2 * extent:
        raise case.error(f"thickness {t.max():g} m is not small against the mesh size "
                         f"{extent:.3g} m (thickness_m is in metres)", ("model", "fe", "thickness_m"))
    return shell_matrices(mesh.points, mesh.triangles, t, young, poisson, density)


def _supports(mesh, fixed_nodes, stiffness, mass) -> tuple:
    """Linear stage, step 3: hold the fixed nodes (6 DOFs) and nodes on no triangle →
    (K_ff, M_ff, free DOF numbers, position of every DOF among the free ones or −1)."""
    from sarfe.reduction.reduced_model import free_dofs_system

    n_nodes = mesh.n_nodes
    used = np.zeros(n_nodes, bool)
    used[mesh.triangles.ravel()] = True
    held = np.union1d(fixed_nodes, np.flatnonzero(~used))
    fixed_dofs = (6 * held[:, None] + np.arange(6)).ravel()
    k_ff, m_ff, free = free_dofs_system(stiffness, mass, fixed_dofs)
    position = np.full(6 * n_nodes, -1)
    position[free] = np.arange(len(free))
    return k_ff, m_ff, free, position


def _boundary_positions(paired, load_nodes, position) -> np.ndarray:
    """Linear stage, step 4: the Craig–Bampton boundary — translations of the contact and load
    nodes — as positions among the free DOFs (fixed ones left out)."""
    nodes = [g[0] for g in paired.values()] + [g[1][g[1] >= 0] for g in paired.values()]
    nodes = np.unique(np.concatenate(nodes + load_nodes + [np.zeros(0, int)]))
    positions = position[(6 * nodes[:, None] + np.arange(3)).ravel()]
    return positions[positions >= 0]


def _base_load(excitation, n_nodes, m_ff, free):
    """−M ι per unit base acceleration [N per m/s²] on the free DOFs (None without one)."""
    if excitation.base_acceleration is None:
        return None
    iota = np.zeros(6 * n_nodes)
    for comp in range(3):
        iota[6 * np.arange(n_nodes) + comp] = excitation.base_acceleration["direction"][comp]
    return -(m_ff @ iota[free])


def _reduce(case: Case, reduction, k_ff, m_ff, boundary, free, n_nodes, base_load, progress):
    """Linear stage, step 5: Craig–Bampton reduction (mode_count, or the cutoff: given or
    :func:`default_cutoff_hz`, at least min_mode_count modes) → (ReducedModel, cutoff_hz|None)."""
    from sarfe.reduction.craig_bampton import craig_bampton

    residual = reduction.residual_vectors
    cutoff = reduction.cutoff_hz if reduction.cutoff_hz is not None else (
        None if reduction.mode_count is not None else default_cutoff_hz(case.config))
    bar = _bar(progress, "Craig-Bampton mode blocks", None)
    try:
        def reduce(mode_count, cutoff_hz):
            return craig_bampton(k_ff, m_ff, boundary, mode_count=mode_count,
                                 cutoff_hz=cutoff_hz, progress=(lambda done, total: bar.update(1))
                                 if bar is not None else None, free_dofs=free,
                                 total_dof_count=6 * n_nodes, residual_vectors=residual,
                                 residual_loads=base_load if residual else None)
        reduced = reduce(reduction.mode_count, cutoff)
        if reduction.mode_count is None and reduced.mode_count < reduction.min_mode_count:
            # a cutoff below the first fixed-interface modes leaves only static condensation
            reduced = reduce(min(reduction.min_mode_count, len(free) - len(boundary) - 1), None)
    except Exception as exc:   # any solver's failure (PARDISO, CHOLMOD, ARPACK): one line
        raise reduction_error(case, exc, len(free), len(boundary)) from None
    finally:
        if bar is not None:
            bar.close()
    return reduced, cutoff


SINGULAR_WORDS = ("singular", "positive definite", "pivot", "pardiso", "cholmod", "not spd")


def reduction_error(case: Case, exc: BaseException, free_count: int, boundary_count: int):
    """A CaseError (one line) saying why the Craig–Bampton reduction failed: a singular K_ii (the
    factorization's words: singular, not positive definite, zero pivot) → the structure is not
    held; out of memory, no eigensolver convergence or anything else → that cause, with the
    model's size, under ``reduction``."""
    from scipy.sparse.linalg import ArpackError, ArpackNoConvergence

    text = " ".join(str(exc).split()) or type(exc).__name__
    size = (f"{free_count} free DOFs, {boundary_count} boundary, "
            f"{free_count - boundary_count} interior")
    if isinstance(exc, MemoryError):
        return case.error(f"the Craig–Bampton reduction ran out of memory ({size}): coarsen the "
                          "mesh, lower reduction.mode_count or reduction.cutoff_hz", ("reduction",))
    if isinstance(exc, (ArpackNoConvergence, ArpackError)):
        return case.error(f"the eigensolver of the Craig–Bampton reduction did not converge "
                          f"({size}): {text}; lower reduction.mode_count or give cutoff_hz",
                          ("reduction",))
    if isinstance(exc, np.linalg.LinAlgError) or any(w in text.lower() for w in SINGULAR_WORDS):
        return case.error(f"the structure is not held (singular stiffness K_ii: {text}); check "
                          "the fixed groups", ("model", "fe", "fixed"))
    return case.error(f"the Craig–Bampton reduction failed ({size}): {type(exc).__name__}: "
                      f"{text}", ("reduction",))


def reduced_coordinates(boundary_global, n_nodes):
    """A function: nodes (m,) → (m, 3) reduced coordinates of their translations (−1 when fixed,
    not on the boundary, or the node is −1). ``boundary_global`` (n_b,): the global DOF index
    6·node + component of each boundary coordinate, in reduced order."""
    coord = np.full(6 * n_nodes, -1)
    coord[boundary_global] = np.arange(len(boundary_global))

    def coords_of(nodes):
        nodes = np.asarray(nodes)
        out = np.full((len(nodes), 3), -1)
        ok = nodes >= 0
        out[ok] = coord[6 * nodes[ok, None] + np.arange(3)]
        return out
    return coords_of


def _contact_geometry(paired, coords_of) -> dict:
    """Linear stage, step 6: {name: ContactGeometry} with the reduced coordinates of both sides."""
    return {name: ContactGeometry(name, a, b, frames, coords_of(a), coords_of(b), distance)
            for name, (a, b, frames, distance) in paired.items()}


def _load_vectors(excitation, load_nodes, coords_of, reduced, base_load) -> tuple:
    """Reduced load vectors: per force (n_f, n_r), unit force spread over its nodes along its
    direction; the base-acceleration load (n_r,) projected on the reduced basis (None without)."""
    n_b, n_r = reduced.boundary_count, reduced.reduced_dof_count
    loads = np.zeros((len(load_nodes), n_r))
    for i, (nodes, load) in enumerate(zip(load_nodes, excitation.forces)):
        c = coords_of(nodes)
        direction = np.asarray(load["direction"])
        for comp in range(3):
            ok = c[:, comp] >= 0
            np.add.at(loads[i], c[ok, comp], direction[comp] / len(nodes))
    base = None
    if base_load is not None:
        base = np.zeros(n_r)
        base[:n_b] = base_load[reduced.boundary_dofs]
        base += reduced.interior_basis.T @ base_load[reduced.interior_dofs]
    return loads, base


def _erp_map(mesh, radiating_triangles, reduced) -> tuple:
    """Linear stage, step 7: (radiating nodes, their areas [m²], normal-velocity map
    (n_s, n_r) from reduced coordinates) of the radiating surface."""
    from sarfe.erp import nodal_areas, nodal_normals
    from sarfe.reduction.recovery import normal_velocity_basis

    erp_nodes = np.unique(radiating_triangles)
    areas = nodal_areas(mesh.points, radiating_triangles)[erp_nodes]
    normals = nodal_normals(mesh.points, radiating_triangles)[erp_nodes]
    return erp_nodes, areas, normal_velocity_basis(reduced, normals, erp_nodes)


def _build_fe(case: Case, progress=False) -> dict:
    """The linear stage of an FE case: mesh and groups → assembly → supports → boundary →
    Craig–Bampton reduction → contact geometry and loads → ERP map (one function per step)."""
    config = case.config
    timings = {}
    clock = time.perf_counter()
    stages = _bar(progress, "linear stage: mesh", 4, unit="step")
    mesh = load_case_mesh(case)
    timings["mesh_s"] = time.perf_counter() - clock
    _step(stages, "assembly")
    n_nodes = mesh.n_nodes
    fixed_nodes, paired, load_nodes, radiating_triangles = _mesh_groups(case, config, mesh)

    clock = time.perf_counter()
    stiffness, mass = _assemble(case, config.model.fe.data, mesh)
    timings["assembly_s"] = time.perf_counter() - clock
    _step(stages, "reduction")

    k_ff, m_ff, free, position = _supports(mesh, fixed_nodes, stiffness, mass)
    del stiffness, mass                  # the free-DOF copies are all the reduction needs
    boundary = _boundary_positions(paired, load_nodes, position)
    base_load = _base_load(config.excitation, n_nodes, m_ff, free)
    clock = time.perf_counter()
    reduced, cutoff = _reduce(case, config.reduction, k_ff, m_ff, boundary, free, n_nodes,
                              base_load, progress)
    timings["reduction_s"] = time.perf_counter() - clock
    _step(stages, "contacts, loads, ERP map")
    n_b, n_r = reduced.boundary_count, reduced.reduced_dof_count

    coords_of = reduced_coordinates(free[reduced.boundary_dofs], n_nodes)
    contacts = _contact_geometry(paired, coords_of)
    loads, base = _load_vectors(config.excitation, load_nodes, coords_of, reduced, base_load)
    erp_nodes, areas, erp_map = _erp_map(mesh, radiating_triangles, reduced)

    _step(stages, None)
    info = {"nodes": int(n_nodes), "triangles": int(mesh.n_triangles),
            "total_dofs": int(6 * n_nodes), "free_dofs": int(len(free)),
            "fixed_nodes": int(len(fixed_nodes)), "boundary_dofs": int(n_b),
            "modes": int(reduced.mode_count), "residual_vectors": int(reduced.residual_vector_count),
            "reduced_dofs": int(n_r),
            "cutoff_hz": None if cutoff is None else float(cutoff),
            "radiating_nodes": int(len(erp_nodes)), "radiating_area_m2": float(areas.sum()),
            "linear_solver": reduced.solver}
    return dict(kind="fe", mass=reduced.mass, stiffness=reduced.stiffness, damping=None,
                load_vectors=loads, base_vector=base, contacts=contacts, erp_map=erp_map,
                erp_areas=areas, erp_nodes=erp_nodes, mesh=mesh, reduced=reduced,
                mode_frequencies_hz=reduced.mode_frequencies_hz, info=info, timings=timings)


def _bar(progress, description, total, unit="block"):
    """A tqdm bar on a terminal, one log line per stage otherwise, None without progress
    (:func:`sarfe.util.progress.bar`); shared by the linear stage and the frequency points."""
    from sarfe.util.progress import bar

    return bar(progress, description, total, unit)


def _step(bar, next_description):
    if bar is None:
        return
    bar.update(1)
    if next_description is None:
        bar.close()
    else:
        bar.set_description(f"linear stage: {next_description}")


def check_mesh(case) -> dict:
    """Validation that needs the mesh but no assembly: groups exist, contacts pair. Returns info."""
    case = load_case(case)
    if not case.is_fe:
        _build_matrices(case)
        return {}
    config = case.config
    if config.model.fe.is_deck:
        from sarfe.pipeline.model.deck_model import check_deck
        return check_deck(case)
    mesh = load_case_mesh(case)
    fe = config.model.fe.data
    for i, g in enumerate(fe["fixed"]):
        resolve_node_group(case, mesh, g, ("model", "fe", "fixed", i), allow_elements=False)
    _per_triangle(case, mesh, fe["materials"], "materials")
    _per_triangle(case, mesh, fe["thickness_m"], "thickness_m")
    from sarfe.erp import nodal_normals
    normals = nodal_normals(mesh.points, mesh.triangles)
    paired = [pair_contact(case, mesh, c.index, normals) for c in config.contacts]
    pairs = {c.name: len(p[0]) for c, p in zip(config.contacts, paired)}
    coincident = _mesh_quality(case, mesh, [(a, b) for a, b, _, _ in paired])
    for i, f in enumerate(config.excitation.forces):
        resolve_node_group(case, mesh, f["group"], ("excitation", "forces", i, "group"))
    surface = config.erp.surface
    if surface is not None and surface not in mesh.element_groups:
        resolve_node_group(case, mesh, surface, ("erp", "surface"))
    return {"nodes": mesh.n_nodes, "triangles": mesh.n_triangles, "contact_pairs": pairs,
            "coincident_node_pairs": len(coincident), "coincident_nodes": coincident[:50]}


def _mesh_quality(case, mesh, contact_pairs):
    """Duplicate and zero-area triangles are errors (0-based triangle indices); coincident nodes
    that no contact pairs are returned (0-based node indices) for validate to list."""
    from sarfe.mesh import quality

    where = case.config.model.fe.where
    index = np.arange(mesh.n_triangles)
    duplicates = quality.duplicate_elements(mesh.triangles, index)
    if duplicates:
        text = ", ".join(f"{b} (= {a})" for a, b in duplicates[:10])
        raise case.error(f"{len(duplicates)} duplicate triangle(s) on the same nodes (0-based "
                         f"indices): {text}", where)
    degenerate = quality.degenerate_elements(mesh.points, mesh.triangles, index)
    if degenerate:
        raise case.error(f"{len(degenerate)} zero-area triangle(s) (0-based indices): "
                         f"{', '.join(map(str, degenerate[:10]))}", where)
    joined = [(int(a), int(b)) for pa, pb in contact_pairs for a, b in zip(pa, pb) if b >= 0]
    extent = float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
    return [list(p) for p in quality.coincident_nodes(mesh.points, np.arange(mesh.n_nodes),
                                                      1e-9 * extent, joined)]


def build_linear_model(case, progress=False) -> LinearStage:
    """Linear stage of a case (module docstring); raises CaseError for mesh/group/file problems."""
    case = load_case(case)
    clock = time.perf_counter()
    if case.is_fe and case.config.model.fe.is_deck:
        from sarfe.pipeline.model.deck_stage import build_deck_stage
        parts = build_deck_stage(case, progress)
    else:
        parts = _build_fe(case, progress) if case.is_fe else _build_matrices(case, progress)
    timings = dict(parts.pop("timings", {}))
    timings["linear_stage_s"] = time.perf_counter() - clock
    return LinearStage(key=linear_model_key(case), timings=timings, **parts)
