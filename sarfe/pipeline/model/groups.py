r"""Node and element groups of a case's mesh: the nodes a group name (or glob pattern) means, the
fixed nodes, and the per-triangle shell properties of the ``materials`` / ``thickness_m`` groups.

    resolve_node_group(case, mesh, name, path) -> (m,) node indices
    fixed_nodes(case, mesh) -> (m,) the nodes of model.fe.fixed (6 DOFs held each)
    triangle_owners(case, mesh, mapping, key) -> (n_t,) index into list(mapping) per triangle
    shell_properties(case, mesh) -> ShellProperties: t [m], E [Pa], ν, ρ [kg/m³] per triangle

Errors are one-line CaseErrors naming the key (``model.fe.fixed[0]``, ``contacts[1].between[0]``)
and the groups the mesh has.
"""
from __future__ import annotations

import fnmatch
from dataclasses import dataclass

import numpy as np


def available(names) -> str:
    """'a, b, c' of the first 30 group names (sorted), '…' after them; 'none' for no name."""
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
                         f"{available(mesh.node_groups)})", path)
    result = np.unique(np.concatenate(nodes)) if nodes else np.zeros(0, int)
    if result.size == 0:
        raise case.error(f"node group '{name}' is empty", path)
    return result


def fixed_nodes(case, mesh) -> np.ndarray:
    """The nodes of the groups of ``model.fe.fixed`` (node groups only), sorted and unique."""
    return np.unique(np.concatenate([
        resolve_node_group(case, mesh, g, ("model", "fe", "fixed", i), allow_elements=False)
        for i, g in enumerate(case.config.model.fe.fixed)]))


def triangle_owners(case, mesh, mapping, key):
    """Index into list(mapping) per triangle (n_t,): the element group (or '*', every triangle)
    of ``model.fe.<key>`` that owns it; later keys override earlier ones."""
    owner = np.full(mesh.n_triangles, -1)
    for j, name in enumerate(mapping):
        if name == "*":
            owner[:] = j
            continue
        groups = [g for g in mesh.element_groups if fnmatch.fnmatchcase(g, name)]
        if not groups:
            raise case.error(f"element group '{name}' not in mesh (available: "
                             f"{available(mesh.element_groups)}, or '*' for all)",
                             ("model", "fe", key, name))
        for g in groups:
            owner[mesh.element_groups[g]] = j
    missing = np.count_nonzero(owner < 0)
    if missing:
        raise case.error(f"{missing} of {mesh.n_triangles} triangles belong to no listed element "
                         f"group (add '*' for a default; groups: {available(mesh.element_groups)})",
                         ("model", "fe", key))
    return owner


@dataclass(frozen=True)
class ShellProperties:
    """Isotropic shell section of every triangle (n_t,): thickness t [m], Young's modulus E [Pa],
    Poisson's ratio ν, density ρ [kg/m³]."""

    thickness: np.ndarray
    young: np.ndarray
    poisson: np.ndarray
    density: np.ndarray


def shell_properties(case, mesh) -> ShellProperties:
    """Per-triangle section from ``model.fe.materials`` and ``model.fe.thickness_m`` (element
    groups → values, :func:`triangle_owners`; the materials' groups are checked first)."""
    fe = case.config.model.fe
    materials, thickness = fe.materials, fe.thickness_m
    mat_owner = triangle_owners(case, mesh, materials, "materials")
    thick_owner = triangle_owners(case, mesh, thickness, "thickness_m")
    mats = list(materials.values())
    return ShellProperties(
        thickness=np.array(list(thickness.values()), dtype=float)[thick_owner],
        young=np.array([m.E_Pa for m in mats])[mat_owner],
        poisson=np.array([m.nu for m in mats])[mat_owner],
        density=np.array([m.rho_kg_m3 for m in mats])[mat_owner])


__all__ = ["available", "resolve_node_group", "fixed_nodes", "triangle_owners",
           "ShellProperties", "shell_properties"]
