r"""Everything ``sarfe solve`` checks before the heavy work, in one place, so that a case that
passes ``sarfe validate`` does not fail on its input later.

    check_case(case, output_dir=None, force=False, write=True) -> CaseCheck

Errors (CaseError, exit 2, one line naming the key or the element):
  * the case file itself (schema, non-finite numbers, signs, units: :func:`sarfe.case.read.load_case`);
  * the mesh: readable, groups present, contacts pair (as :func:`sarfe.pipeline.checks.mesh_checks.check_mesh`),
    no node pair listed twice in one contact;
  * element quality: zero-area triangles, duplicate triangles (same node set), coincident nodes
    that neither an element nor a contact pair joins (a crack) — :mod:`sarfe.mesh.quality`;
  * thickness plausibility: 1e-4·L < t < 0.1·L for the model size L (the bounding-box diagonal),
    which catches a thickness given in mm;
  * the structure is held: every connected part of the mesh holds at least one fixed node (else
    the stiffness has rigid-body modes and the reduction cannot factorize it); a matrices model's
    K plus the springs of the contacts closed at rest is regular (:func:`check_matrices_held`);
  * something is free to move, every force acts on a free DOF and every contact on a free node
    (a force group or a contact all held is an error, partly held a warning:
    :mod:`sarfe.pipeline.checks.held_checks`);
  * the output folder: absent, empty or a sarfe result, and writable (:mod:`sarfe.results.folder`);
    never a folder holding a file the case reads (:mod:`sarfe.pipeline.checks.case_inputs`).

Warnings (one line each, printed and written to summary.json ``warnings``) for inputs far outside
the model's range:
  * H·f_max above the highest frequency the mesh resolves: a bending wave of a plate,
    λ = 2π / k with k⁴ = ω² ρ t / D and D = E t³ / (12 (1 − ν²)), needs about
    :data:`ELEMENTS_PER_WAVELENGTH` element edges h, so f_mesh = (2π / (6 h))² √(D / (ρ t)) / 2π
    (median over the triangles);
  * H·f_max above ``reduction.cutoff_hz`` (the harmonics have no modes to live in);
  * an open gap larger than the structure (the contact can never close), or |gap_m| more than
    :data:`GAP_RANGE` × the thickest shell or the contact's tolerance_m (:func:`gap_warnings`);
  * reduction.mode_count above the interior DOFs; a force group partly fixed; a node pair in two
    contacts (:func:`~sarfe.pipeline.checks.mesh_checks.shared_pair_warnings`);
  * values no squeak-and-rattle input has (:func:`sarfe.case.plausibility.plausibility_warnings`):
    μ > 2, a base acceleration above 50 g, a preload pressing a contact more than 1 mm in.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sarfe.case.plausibility import THICKNESS_RANGE, plausibility_warnings
from sarfe.case.read import load_case
from sarfe.hbm.pruning import linearized_stiffness
from sarfe.mesh import connected_components
from sarfe.mesh.geometry import triangle_areas
from sarfe.mesh.quality import coincident_nodes, degenerate_elements, duplicate_elements
from sarfe.pipeline.checks.case_inputs import case_inputs
from sarfe.pipeline.checks.held_checks import (check_something_free, contact_warnings,
                                               load_warnings)
from sarfe.pipeline.checks.mesh_checks import check_deck, shared_pair_warnings
from sarfe.pipeline.checks.run_cost import (ModelSize, contact_rows, fe_contact_mass,
                                            matrices_contact_mass, plate_bending,
                                            weyl_mode_density)
from sarfe.pipeline.model.case_mesh import load_case_mesh
from sarfe.pipeline.model.contact_pairs import boundary_dofs, node_pairs
from sarfe.pipeline.model.erp_map import surface_triangles
from sarfe.pipeline.model.fe_stage import resolve_contacts
from sarfe.pipeline.model.groups import fixed_nodes, resolve_node_group, shell_properties
from sarfe.pipeline.model.linear_stage import build_linear_model
from sarfe.pipeline.model.nonlinear_model import nonlinear_model
from sarfe.results.folder import check_output_folder
from sarfe.results.vtk import part_ids

ELEMENTS_PER_WAVELENGTH = 6
COINCIDENT_TOLERANCE = 1e-7      # × model size: nodes closer than this are at the same place
DEGENERATE_TOLERANCE = 1e-8      # area ≤ this × (longest edge)²: a zero-area triangle
HELD_BY = "model.fe.fixed or on no triangle"


@dataclass(frozen=True)
class CaseCheck:
    """What :func:`check_case` found: ``info`` for the validate line (nodes, triangles, contact
    pairs), ``warnings`` (one-line strings), ``output`` (the checked result folder or None),
    ``size`` (what the run's cost depends on: :class:`sarfe.pipeline.checks.run_cost.ModelSize`,
    None when the mesh checks were skipped)."""

    info: dict = field(default_factory=dict)
    warnings: tuple = ()
    output: object = None
    size: ModelSize | None = None


def _excitation_top_hz(case) -> float:
    return case.config.excitation.max_frequency_hz


def _where(mesh, triangle) -> str:
    x, y, z = mesh.points[mesh.triangles[triangle]].mean(axis=0)
    return f"at ({x:.4g}, {y:.4g}, {z:.4g}) m"


def check_element_quality(case, mesh, joined=()) -> None:
    """Zero-area and duplicate triangles, unjoined coincident nodes → CaseError naming them."""
    where = ("model", "fe", "mesh") if case.config.model.fe.source == "mesh" else ("model", "fe",
                                                                                  "generator")
    ids = np.arange(mesh.n_triangles)
    bad = degenerate_elements(mesh.points, mesh.triangles, ids, DEGENERATE_TOLERANCE)
    if bad:
        first = bad[0]
        raise case.error(f"{len(bad)} zero-area triangle(s): triangle {first} (nodes "
                         f"{', '.join(map(str, mesh.triangles[first]))}) {_where(mesh, first)}"
                         f"{'' if len(bad) == 1 else ', ' + ', '.join(map(str, bad[1:6]))}"
                         f"{' …' if len(bad) > 6 else ''}", where)
    twins = duplicate_elements(mesh.triangles, ids)
    if twins:
        kept, repeated = twins[0]
        raise case.error(f"{len(twins)} duplicate triangle(s) (same nodes, counted twice): "
                         f"triangle {repeated} repeats triangle {kept} (nodes "
                         f"{', '.join(map(str, mesh.triangles[kept]))}) {_where(mesh, kept)}", where)
    size = float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
    used = np.zeros(mesh.n_nodes, bool)
    used[mesh.triangles.ravel()] = True
    nodes = np.flatnonzero(used)
    pairs = coincident_nodes(mesh.points[nodes], nodes, COINCIDENT_TOLERANCE * size,
                             joined=[(np.searchsorted(nodes, a), np.searchsorted(nodes, b))
                                     for a, b in joined if used[a] and b >= 0 and used[b]])
    if pairs:
        a, b = pairs[0]
        x, y, z = mesh.points[a]
        raise case.error(f"{len(pairs)} pair(s) of coincident nodes that no element or contact "
                         f"joins (a crack): nodes {a} and {b} at ({x:.4g}, {y:.4g}, {z:.4g}) m; "
                         "merge them or pair them in a contact", where)


def check_thickness(case, mesh) -> None:
    size = float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
    low, high = THICKNESS_RANGE
    for name, t in case.config.model.fe.thickness_m.items():
        path = ("model", "fe", "thickness_m", name)
        if t > high * size:
            raise case.error(f"thickness {t:g} m is not small against the model size {size:.3g} m "
                             "— given in mm? thickness_m is in metres", path)
        if t < low * size:
            raise case.error(f"thickness {t:g} m is implausibly thin for a model of {size:.3g} m "
                             "— thickness_m is in metres (2.5 mm = 2.5e-3)", path)


def check_held(case, mesh, fixed_nodes) -> None:
    """Every connected part of the shell mesh holds a fixed node (no rigid-body motion left)."""
    count, labels = connected_components(mesh.n_nodes, mesh.triangles)
    held = np.zeros(count, bool)
    labels_fixed = labels[fixed_nodes]
    held[labels_fixed[labels_fixed >= 0]] = True
    if not held.all():
        free = np.flatnonzero(~held)
        part = free[0]
        members = np.flatnonzero(labels == part)
        x, y, z = mesh.points[members].mean(axis=0)
        raise case.error(f"the structure is not held: {len(free)} of {count} connected part(s) "
                         f"have no fixed node and can move as a rigid body (part of "
                         f"{len(members)} nodes around ({x:.4g}, {y:.4g}, {z:.4g}) m, e.g. node "
                         f"{members[0]}); add a fixed group on it", ("model", "fe", "fixed"))


def held_nodes(mesh, fixed_nodes) -> tuple:
    """(held (n,), used (n,)) bool: a node of ``fixed_nodes`` or on no triangle is held."""
    used = np.zeros(mesh.n_nodes, bool)
    used[mesh.triangles.ravel()] = True
    held = ~used
    held[np.asarray(fixed_nodes, dtype=int)] = True
    return held, used


HELD_MATRIX_LIMIT = 3000        # DOFs: a dense eigenvalue check above costs more than it finds
RIGID_TOLERANCE = 1e-10         # eigenvalue ≤ this × the largest: a rigid-body (null-space) mode


def check_matrices_held(case, stage=None) -> int:
    r"""A ``model.matrices`` model is held at rest, as :func:`check_held` asks of a mesh: the static
    stiffness with the contacts linearized at u = 0 (their preload state: :func:`sarfe.hbm.pruning.
    linearized_stiffness`),

        K_0 = K + Gᵀ diag(k) G      (k: the springs of the contacts closed at rest, k_t of the stuck
                                     tangents; open contacts add nothing),

    must be regular — else the static (0th harmonic) block of the HBM Jacobian is singular at every
    point. K_0 (n, n) [N/m]; its eigenvalues λ ≤ :data:`RIGID_TOLERANCE`·max λ span the rigid-body
    modes. CaseError naming model.matrices.stiffness and the null-space size. Models above
    :data:`HELD_MATRIX_LIMIT` DOFs are not checked (a dense eigenvalue problem). ``stage``: the
    case's linear model when built already. Returns the model's DOF count."""
    stage = build_linear_model(case) if stage is None else stage
    n = stage.dof_count
    if n > HELD_MATRIX_LIMIT:
        return n
    nl = nonlinear_model(case, stage)
    K0 = linearized_stiffness(nl.model, nl.contacts)[0]
    K0 = K0.toarray() if hasattr(K0, "toarray") else np.asarray(K0, dtype=float)
    values, vectors = np.linalg.eigh(0.5 * (K0 + K0.T))
    rigid = values <= RIGID_TOLERANCE * max(np.abs(values).max(initial=0.0), 1e-300)
    if rigid.any():
        count = int(np.count_nonzero(rigid))
        moving = np.flatnonzero(np.abs(vectors[:, rigid]).max(axis=1) > 1e-6)
        shown = ", ".join(map(str, moving[:8])) + (" …" if moving.size > 8 else "")
        raise case.error(f"the structure is not held: the stiffness plus the springs of the "
                         f"contacts closed at rest is singular ({count} rigid-body mode(s), "
                         f"null space of size {count} of {n} DOFs; DOF(s) {shown} move freely); "
                         "add stiffness to ground or a preloaded contact",
                         ("model", "matrices", "stiffness"))
    return n


def bending_resolution_hz(points, triangles, thickness, young, poisson, density) -> np.ndarray:
    """Per triangle, the frequency [Hz] whose plate bending wavelength spans
    :data:`ELEMENTS_PER_WAVELENGTH` of its longest edge h:

        k = 2π / (6 h),  f = k² √(D / (ρ t)) / 2π,  D = E t³ / (12 (1 − ν²))

    points (n, 3) [m]; triangles (n_e, 3); thickness [m], young [Pa], poisson, density [kg/m³]
    scalars or (n_e,) per triangle. Returns (n_e,)."""
    corners = np.asarray(points, dtype=float)[np.asarray(triangles)]
    h = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max(axis=1)
    t = np.asarray(thickness, dtype=float)
    bending = plate_bending(t, young, poisson)
    k = 2 * np.pi / (ELEMENTS_PER_WAVELENGTH * h)
    return k ** 2 * np.sqrt(bending / (np.asarray(density, dtype=float) * t)) / (2 * np.pi)


def mesh_frequency_limit_hz(case, mesh) -> float:
    """Highest frequency [Hz] the case's mesh resolves: the median over its triangles of
    :func:`bending_resolution_hz` with each triangle's material and thickness."""
    section = shell_properties(case, mesh)
    return float(np.median(bending_resolution_hz(mesh.points, mesh.triangles, section.thickness,
                                                 section.young, section.poisson,
                                                 section.density)))


GAP_RANGE = 10.0   # |gap_m| above this × the contact's reference length warns


def gap_warnings(case, mesh=None) -> list:
    r"""A ``gap_m`` far from the contact's scale: |g| > :data:`GAP_RANGE` · L with the reference
    length L = max(thickest shell ``thickness_m`` of an FE model, the contact's ``tolerance_m``)
    [m] — a gap in mm given as metres (0.5 for 0.5 mm), or an overclosure that presses the parts
    through each other. Not an error (the model is solved as given); no L (a matrices model with
    tolerance_m = 0), or an open gap already larger than the structure (:func:`range_warnings`),
    no warning."""
    config = case.config
    thickness = config.model.fe.thickness_m if config.model.is_fe else {}
    thickest = max((float(t) for t in thickness.values()), default=0.0)
    size = np.inf if mesh is None else float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
    warnings = []
    for i, contact in enumerate(config.contacts):
        gap = contact.gap_m
        tolerance = float(contact.tolerance_m)
        reference = max(thickest, tolerance)
        if gap is None or reference <= 0.0 or abs(gap) <= GAP_RANGE * reference or gap > size:
            continue
        what = (f"the thickest shell, thickness_m = {thickest:g} m" if thickest >= tolerance
                else f"its tolerance_m = {tolerance:g} m")
        kind = "an overclosure (the parts pressed" if gap < 0 else "an open gap (the parts"
        detail = (f"{kind} {abs(gap) * 1e3:.4g} mm into each other)" if gap < 0
                  else f"{kind} {gap * 1e3:.4g} mm apart)")
        warnings.append(f"contacts[{i}] ({contact.name}): gap_m = {gap:g} m is {detail}, "
                        f"more than {GAP_RANGE:g} × {what}: gap_m is in metres "
                        "(0.5 mm = 5e-4)")
    return warnings


def range_warnings(case, mesh=None) -> list:
    """One-line warnings for inputs far outside the model's range (module docstring), and
    those of :func:`sarfe.case.plausibility.plausibility_warnings` (μ, base acceleration,
    preload overclosure)."""
    config = case.config
    warnings = plausibility_warnings(config)
    top = _excitation_top_hz(case)
    H = config.solver.harmonics
    if mesh is not None:
        limit = mesh_frequency_limit_hz(case, mesh)
        if H * top > limit:
            warnings.append(f"excitation {top:g} Hz × {H} harmonics = {H * top:.4g} Hz is above the "
                            f"~{limit:.4g} Hz the mesh resolves ({ELEMENTS_PER_WAVELENGTH} elements "
                            "per bending wavelength): refine the mesh or lower the harmonics")
        size = float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
        for i, contact in enumerate(config.contacts):
            gap = contact.gap_m
            if gap is not None and gap > size:
                warnings.append(f"contacts[{i}] ({contact.name}): gap_m = {gap:g} m is larger "
                                f"than the structure ({size:.3g} m): the contact can never close")
    warnings += gap_warnings(case, mesh)
    cutoff = None if config.reduction is None else config.reduction.cutoff_hz
    if cutoff is not None and H * top > cutoff:
        warnings.append(f"excitation {top:g} Hz × {H} harmonics = {H * top:.4g} Hz is above "
                        f"reduction.cutoff_hz = {cutoff:g} Hz: the higher harmonics have no modes")
    return warnings


def interior_dof_count(mesh, fixed_nodes, boundary_dofs) -> int:
    """Interior DOFs of the Craig–Bampton split, as the linear stage makes it: 6 per node on a
    triangle that is not fixed, minus the boundary DOFs (global numbers 6·node + component: what
    the contact rows touch and the load nodes' translations) on such nodes. At most this many
    fixed-interface modes exist."""
    used = np.zeros(mesh.n_nodes, bool)
    used[mesh.triangles.ravel()] = True
    free = used.copy()
    free[np.asarray(fixed_nodes, dtype=int)] = False
    boundary = np.unique(np.asarray(boundary_dofs, dtype=np.int64))
    boundary = boundary[(boundary >= 0) & free[np.maximum(boundary, 0) // 6]]
    return int(6 * np.count_nonzero(free) - boundary.size)


def mode_count_warnings(case, interior) -> list:
    """reduction.mode_count above the ``interior`` DOF count: a warning stating the clip."""
    reduction = case.config.reduction
    asked = None if reduction is None else reduction.mode_count
    if asked is None or asked <= interior:
        return []
    return [f"reduction.mode_count = {asked} asks more modes than the structure has: its "
            f"{interior} interior DOFs give at most {interior} fixed-interface modes, so the "
            f"reduction keeps all it finds ({asked} asked, at most {interior} available; a full "
            "eigenproblem): lower mode_count or give reduction.cutoff_hz"]


def reduced_model_warnings(case, stage) -> list:
    """Warnings that need the reduced model: fewer modes kept than reduction.mode_count asked
    (unless :func:`mode_count_warnings` said so before the reduction), H·f_max above the highest
    fixed-interface mode."""
    modes = np.asarray(stage.mode_frequencies_hz)
    reduction = case.config.reduction
    if stage.kind != "fe" or reduction is None or reduction.mode_count is None:
        return []
    warnings = []
    asked, kept = reduction.mode_count, int(stage.info.get("modes", modes.size))
    interior = stage.info.get("free_dofs", 0) - stage.info.get("boundary_dofs", 0)
    said_before = not case.config.model.fe.is_deck and asked > interior
    if kept < asked and not said_before:
        warnings.append(f"reduction.mode_count = {asked}: the reduction kept {kept} modes "
                        f"({asked} asked, {kept} available from {interior} interior DOFs)")
    top, H = _excitation_top_hz(case), case.config.solver.harmonics
    if modes.size and H * top > modes.max():
        warnings.append(f"excitation {top:g} Hz × {H} harmonics = {H * top:.4g} Hz is above the "
                        f"highest kept mode ({modes.max():.4g} Hz, reduction.mode_count = "
                        f"{modes.size})")
    return warnings


def output_target(case, output_dir=None, force=False):
    """The checked result folder of a case (``output_dir`` or ``output.directory``): absent, empty
    or a previous sarfe result (or, with ``force``, anything but the current or home folder or a
    folder holding an input of the case: :func:`sarfe.pipeline.checks.case_inputs.case_inputs`),
    and writable — else CaseError, before any work (rules: :mod:`sarfe.results.folder`)."""
    target = output_dir if output_dir is not None else case.config.output.directory
    return check_output_folder(target, force=force, protected=case_inputs(case))


def part_contact_mass(config, mesh, paired, section) -> tuple:
    """m_c per contact from the parts' masses (:func:`sarfe.pipeline.checks.run_cost.
    fe_contact_mass`): each triangle's part (its ``part_*`` group; one part without groups) and
    its mass ρ t A [kg]."""
    part, _ = part_ids(mesh.n_triangles, {name: triangles for name, triangles
                                           in mesh.element_groups.items()
                                           if name.startswith("part_")})
    mass = section.density * section.thickness * triangle_areas(mesh.points, mesh.triangles)
    return fe_contact_mass(config, paired, mesh.triangles, part, mass)


def check_case(case, output_dir=None, force=False, write=True, mesh_checks=True,
               assemble=True) -> CaseCheck:
    """All checks of the module docstring. Raises CaseError at the first problem. ``assemble``
    (deck path): also assemble the deck, for what solve refuses there (`solve` passes False:
    its linear stage assembles right after, with the same lines)."""
    case = load_case(case)
    output = output_target(case, output_dir, force) if write else None
    if not mesh_checks:
        return CaseCheck({}, tuple(range_warnings(case)), output)
    if not case.is_fe:
        stage = build_linear_model(case)
        dofs = check_matrices_held(case, stage)
        masses = matrices_contact_mass(stage.mass, case.config) \
            if case.config.contacts and dofs <= HELD_MATRIX_LIMIT else ()
        size = ModelSize(dofs=dofs, radiating_nodes=len(case.config.erp.dofs or ()),
                         contacts=len(case.config.contacts),
                         contact_rows=contact_rows(case.config, None), contact_mass_kg=masses)
        return CaseCheck({}, tuple(range_warnings(case)), output, size)
    config = case.config
    if config.model.fe.is_deck:   # a Nastran/Abaqus deck: its own checks, with ids
        info = check_deck(case, assemble=assemble)
        size = ModelSize(dofs=6 * info.pop("free_nodes"), nodes=info["nodes"],
                         triangles=info["triangles"], radiating_nodes=info.pop("radiating_nodes"),
                         contacts=len(config.contacts),
                         contact_rows=contact_rows(config, info["contact_pairs"]),
                         mode_density_per_hz=info.pop("mode_density_per_hz"), fe=True)
        return CaseCheck(info, tuple(range_warnings(case)) + tuple(info.pop("warnings")), output,
                         size)
    mesh = load_case_mesh(case)
    fixed = fixed_nodes(case, mesh)
    held, used = held_nodes(mesh, fixed)
    check_something_free(case, held, used)
    section = shell_properties(case, mesh)
    check_thickness(case, mesh)
    resolved = resolve_contacts(case, mesh)
    paired = node_pairs(resolved)
    shared = shared_pair_warnings(case, paired, mesh.points)
    load_nodes = [resolve_node_group(case, mesh, f.group, ("excitation", "forces", i, "group"))
                  for i, f in enumerate(config.excitation.forces)]
    warned = load_warnings(case, held, load_nodes, HELD_BY)
    warned += contact_warnings(case, paired, held, HELD_BY)
    # erp.surface: an element group, or a node group's triangles
    radiating = np.unique(surface_triangles(case, mesh)).size
    joined = [(int(a), int(b)) for p in paired.values() for a, b in zip(p[0], p[1])]
    check_element_quality(case, mesh, joined)
    check_held(case, mesh, fixed)
    info = {"nodes": mesh.n_nodes, "triangles": mesh.n_triangles,
            "contact_pairs": {name: len(p[0]) for name, p in paired.items()}}
    loads = np.concatenate([np.zeros(0, int)] + load_nodes)
    interior = interior_dof_count(mesh, fixed, np.union1d(
        boundary_dofs(resolved), (6 * loads[:, None] + np.arange(3)).ravel()))
    geometry = tuple(w for r in resolved.values() for w in r.warnings)
    size = ModelSize(dofs=6 * int(np.count_nonzero(used & ~held)), nodes=mesh.n_nodes,
                     triangles=mesh.n_triangles, radiating_nodes=int(radiating),
                     contacts=len(config.contacts),
                     contact_rows=contact_rows(config, info["contact_pairs"]),
                     mode_density_per_hz=weyl_mode_density(
                         mesh.points, mesh.triangles, section.density * section.thickness,
                         plate_bending(section.thickness, section.young, section.poisson)),
                     fe=True, contact_mass_kg=part_contact_mass(config, mesh, paired, section))
    return CaseCheck(info, tuple(range_warnings(case, mesh)) + tuple(shared)
                     + tuple(warned) + geometry
                     + tuple(mode_count_warnings(case, interior)), output, size)


__all__ = ["CaseCheck", "check_case", "held_nodes", "check_matrices_held", "output_target",
           "check_element_quality", "check_held", "check_thickness", "bending_resolution_hz",
           "mesh_frequency_limit_hz", "range_warnings", "reduced_model_warnings",
           "interior_dof_count", "mode_count_warnings", "gap_warnings"]
