r"""The linear stage of a mesh or generator FE case: mesh → shell K, M (per-triangle thickness and
material) → remove the fixed (clip/clamp) DOFs → Craig–Bampton with boundary = the DOFs the
contact rows touch (translations and rotations of the nodes of each contact point's elements) and
the translations of the excitation nodes:

    u = T q,  q = [q_b, q_m],  M_r = Tᵀ M T,  K_r = Tᵀ K T,  f_r = Tᵀ f,

contact rows [w, q₁, q₂]_p = frame_p (u_face,a − u_face,b) (:mod:`sarfe.pipeline.model.
contact_pairs`) touch boundary coordinates only, and the radiating-surface normal displacement
is w_s = N q (:mod:`sarfe.pipeline.model.erp_map`).
One function per step; :func:`build_fe_stage` runs them in order.
"""
from __future__ import annotations

import time

import numpy as np
from scipy.sparse.linalg import ArpackError, ArpackNoConvergence

from sarfe.fe.shell import shell_matrices
from sarfe.pipeline.model.case_mesh import load_case_mesh
from sarfe.pipeline.model.contact_kinematics import ShellSurface
from sarfe.pipeline.model.contact_pairs import (boundary_dofs, contact_geometry,
                                                reduced_coordinates, resolve_contact)
from sarfe.pipeline.model.cutoff import stage_cutoff_hz
from sarfe.pipeline.model.erp_map import erp_map, surface_triangles
from sarfe.pipeline.model.groups import fixed_nodes, resolve_node_group, shell_properties
from sarfe.pipeline.model.stage import next_step
from sarfe.reduction.craig_bampton import craig_bampton
from sarfe.reduction.reduced_model import free_dofs_system
from sarfe.util.progress import bar as progress_bar


def shell_surface(case, mesh) -> ShellSurface:
    """The mesh's shells as the contacts see them: per-triangle thickness (``thickness_m``), no
    offsets (a generated or plain mesh is the mid-surface)."""
    thickness = shell_properties(case, mesh).thickness
    return ShellSurface(mesh.points, mesh.triangles, thickness, np.zeros_like(thickness))


def resolve_contacts(case, mesh) -> dict:
    """{name: ResolvedContact} of every contact of a mesh/generator case."""
    surface = shell_surface(case, mesh)
    return {c.name: resolve_contact(case, mesh, c.index, surface) for c in case.config.contacts}


def mesh_groups(case, mesh) -> tuple:
    """Step 1 (after the mesh): the node groups the case names — fixed nodes, contacts
    {name: ResolvedContact}, load nodes per force — and the radiating triangles. Cheap, and the
    errors a user is most likely to make, so they come first."""
    config = case.config
    fixed = fixed_nodes(case, mesh)
    resolved = resolve_contacts(case, mesh)
    load_nodes = [resolve_node_group(case, mesh, f.group, ("excitation", "forces", i, "group"))
                  for i, f in enumerate(config.excitation.forces)]
    return fixed, resolved, load_nodes, surface_triangles(case, mesh)


def assemble(case, mesh) -> tuple:
    """Step 2: shell stiffness and mass (6 n_nodes square, sparse) from the per-triangle
    materials (E_Pa, nu, rho_kg_m3) and thickness_m (:func:`sarfe.pipeline.model.groups.
    shell_properties`)."""
    section = shell_properties(case, mesh)
    t = section.thickness
    extent = float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
    if t.max() > 0.2 * extent:
        raise case.error(f"thickness {t.max():g} m is not small against the mesh size "
                         f"{extent:.3g} m (thickness_m is in metres)", ("model", "fe", "thickness_m"))
    return shell_matrices(mesh.points, mesh.triangles, t, section.young, section.poisson,
                          section.density)


def supports(mesh, fixed, stiffness, mass) -> tuple:
    """Step 3: hold the fixed nodes (6 DOFs) and nodes on no triangle →
    (K_ff, M_ff, free DOF numbers, position of every DOF among the free ones or −1)."""
    n_nodes = mesh.n_nodes
    used = np.zeros(n_nodes, bool)
    used[mesh.triangles.ravel()] = True
    held = np.union1d(fixed, np.flatnonzero(~used))
    fixed_dofs = (6 * held[:, None] + np.arange(6)).ravel()
    k_ff, m_ff, free = free_dofs_system(stiffness, mass, fixed_dofs)
    position = np.full(6 * n_nodes, -1)
    position[free] = np.arange(len(free))
    return k_ff, m_ff, free, position


def boundary_positions(resolved, load_nodes, position) -> np.ndarray:
    """Step 4: the Craig–Bampton boundary — every DOF the contact rows touch
    (:func:`sarfe.pipeline.model.contact_pairs.boundary_dofs`) and the load nodes' translations —
    as positions among the free DOFs (fixed ones left out)."""
    nodes = np.unique(np.concatenate(load_nodes + [np.zeros(0, int)]))
    dofs = np.union1d(boundary_dofs(resolved), (6 * nodes[:, None] + np.arange(3)).ravel())
    positions = position[dofs]
    return positions[positions >= 0]


def base_load(excitation, n_nodes, m_ff, free):
    """−M ι per unit base acceleration [N per m/s²] on the free DOFs (None without one)."""
    if excitation.base_acceleration is None:
        return None
    iota = np.zeros(6 * n_nodes)
    for comp in range(3):
        iota[6 * np.arange(n_nodes) + comp] = excitation.base_acceleration.direction[comp]
    return -(m_ff @ iota[free])


def reduce_model(case, k_ff, m_ff, boundary, free, n_nodes, residual_loads, progress):
    """Step 5: Craig–Bampton reduction (mode_count, or the cutoff: given or the default rule,
    :mod:`sarfe.pipeline.model.cutoff`; at least min_mode_count modes) → (ReducedModel,
    cutoff_hz | None)."""
    reduction = case.config.reduction
    residual = reduction.residual_vectors
    cutoff = stage_cutoff_hz(case.config)
    bar = progress_bar(progress, "Craig-Bampton mode blocks", None, "block")
    try:
        def reduce_to(mode_count, cutoff_hz):
            return craig_bampton(k_ff, m_ff, boundary, mode_count=mode_count,
                                 cutoff_hz=cutoff_hz, progress=(lambda done, total: bar.update(1))
                                 if bar is not None else None, free_dofs=free,
                                 total_dof_count=6 * n_nodes, residual_vectors=residual,
                                 residual_loads=residual_loads if residual else None)
        reduced = reduce_to(reduction.mode_count, cutoff)
        if reduction.mode_count is None and reduced.mode_count < reduction.min_mode_count:
            # a cutoff below the first fixed-interface modes leaves only static condensation
            reduced = reduce_to(min(reduction.min_mode_count, len(free) - len(boundary) - 1), None)
    except Exception as exc:   # any solver's failure (PARDISO, CHOLMOD, ARPACK): one line
        raise reduction_error(case, exc, len(free), len(boundary)) from None
    finally:
        if bar is not None:
            bar.close()
    return reduced, cutoff


SINGULAR_WORDS = ("singular", "positive definite", "pivot", "pardiso", "cholmod", "not spd")


def reduction_error(case, exc: BaseException, free_count: int, boundary_count: int):
    """A CaseError (one line) saying why the Craig–Bampton reduction failed: a singular K_ii (the
    factorization's words: singular, not positive definite, zero pivot) → the structure is not
    held; out of memory, no eigensolver convergence or anything else → that cause, with the
    model's size, under ``reduction``."""
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


def load_vectors(excitation, load_nodes, coords_of, reduced, base) -> tuple:
    """Reduced load vectors: per force (n_f, n_r), unit force spread over its nodes along its
    direction; the base-acceleration load (n_r,) projected on the reduced basis (None without)."""
    n_b, n_r = reduced.boundary_count, reduced.reduced_dof_count
    loads = np.zeros((len(load_nodes), n_r))
    for i, (nodes, load) in enumerate(zip(load_nodes, excitation.forces)):
        c = coords_of(nodes)
        direction = np.asarray(load.direction)
        for comp in range(3):
            ok = c[:, comp] >= 0
            np.add.at(loads[i], c[ok, comp], direction[comp] / len(nodes))
    reduced_base = None
    if base is not None:
        reduced_base = np.zeros(n_r)
        reduced_base[:n_b] = base[reduced.boundary_dofs]
        reduced_base += reduced.interior_basis.T @ base[reduced.interior_dofs]
    return loads, reduced_base


def build_fe_stage(case, progress=False) -> dict:
    """The linear stage of a mesh/generator case (the fields of :class:`sarfe.pipeline.model.
    stage.LinearStage`): mesh and groups → assembly → supports → boundary → Craig–Bampton
    reduction → contact geometry and loads → ERP map (module docstring)."""
    config = case.config
    timings = {}
    clock = time.perf_counter()
    stages = progress_bar(progress, "linear stage: mesh", 4, "step")
    mesh = load_case_mesh(case)
    timings["mesh_s"] = time.perf_counter() - clock
    next_step(stages, "assembly")
    n_nodes = mesh.n_nodes
    fixed, resolved, load_nodes, radiating = mesh_groups(case, mesh)

    clock = time.perf_counter()
    stiffness, mass = assemble(case, mesh)
    timings["assembly_s"] = time.perf_counter() - clock
    next_step(stages, "reduction")

    k_ff, m_ff, free, position = supports(mesh, fixed, stiffness, mass)
    del stiffness, mass                  # the free-DOF copies are all the reduction needs
    boundary = boundary_positions(resolved, load_nodes, position)
    base = base_load(config.excitation, n_nodes, m_ff, free)
    clock = time.perf_counter()
    reduced, cutoff = reduce_model(case, k_ff, m_ff, boundary, free, n_nodes, base, progress)
    timings["reduction_s"] = time.perf_counter() - clock
    next_step(stages, "contacts, loads, ERP map")
    n_b, n_r = reduced.boundary_count, reduced.reduced_dof_count

    boundary_global = free[reduced.boundary_dofs]
    coords_of = reduced_coordinates(boundary_global, n_nodes)
    contacts = contact_geometry(resolved, boundary_global, n_r)
    loads, reduced_base = load_vectors(config.excitation, load_nodes, coords_of, reduced, base)
    erp_nodes, areas, surface_map = erp_map(mesh, radiating, reduced)

    next_step(stages, None)
    info = {"nodes": int(n_nodes), "triangles": int(mesh.n_triangles),
            "total_dofs": int(6 * n_nodes), "free_dofs": int(len(free)),
            "fixed_nodes": int(len(fixed)), "boundary_dofs": int(n_b),
            "modes": int(reduced.mode_count), "residual_vectors": int(reduced.residual_vector_count),
            "reduced_dofs": int(n_r),
            "cutoff_hz": None if cutoff is None else float(cutoff),
            "radiating_nodes": int(len(erp_nodes)), "radiating_area_m2": float(areas.sum()),
            "linear_solver": reduced.solver}
    return dict(kind="fe", mass=reduced.mass, stiffness=reduced.stiffness, damping=None,
                load_vectors=loads, base_vector=reduced_base, contacts=contacts,
                erp_map=surface_map, erp_areas=areas, erp_nodes=erp_nodes, mesh=mesh,
                reduced=reduced, mode_frequencies_hz=reduced.mode_frequencies_hz, info=info,
                timings=timings)


__all__ = ["build_fe_stage", "shell_surface", "resolve_contacts", "mesh_groups", "assemble", "supports", "boundary_positions",
           "base_load", "reduce_model", "reduction_error", "load_vectors", "SINGULAR_WORDS"]
