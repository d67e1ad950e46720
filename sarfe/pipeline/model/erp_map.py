r"""The radiating surface of an FE case and its ERP map: the surface's normal displacement per
reduced coordinate,

    w_s = N q,   N = erp_map (n_s, n_r),

with the radiating nodes' nodal normals and areas A (n_s,) [m²] of the surface triangles
(:func:`sarfe.reduction.recovery.normal_velocity_basis` on the reduced basis u = T q).

    surface_triangles(case, mesh) -> (n_t, 3)        erp.surface, else the 'skin' group, else all
    deck_surface_triangles(case, mesh) -> (n_t, 3)   erp.surface (an element group) or every shell
    erp_map(mesh, triangles, reduced) -> (radiating nodes (n_s,), areas (n_s,) [m²], N (n_s, n_r))
"""
from __future__ import annotations

import numpy as np

from sarfe.erp import nodal_areas, nodal_normals
from sarfe.pipeline.model.groups import resolve_node_group
from sarfe.reduction.recovery import normal_velocity_basis


def surface_triangles(case, mesh) -> np.ndarray:
    """Triangles (n_t, 3) of the radiating surface of a mesh case: erp.surface (an element
    group, or the whole triangles of a node group), else the 'skin' group, else every triangle."""
    surface = case.config.erp.surface
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


def deck_surface_triangles(case, mesh) -> np.ndarray:
    """Triangles of the ERP surface of a deck case: every shell, or the element group
    erp.surface."""
    surface = case.config.erp.surface
    if surface is None:
        return mesh.triangles
    if surface not in mesh.element_groups:
        raise case.error(f"element group '{surface}' not in the deck (available: "
                         f"{', '.join(sorted(mesh.element_groups)[:30])})", ("erp", "surface"))
    return mesh.triangles[mesh.element_groups[surface]]


def erp_map(mesh, triangles, reduced) -> tuple:
    """(radiating nodes (n_s,), their areas (n_s,) [m²], normal-displacement map N (n_s, n_r)
    from reduced coordinates) of the surface ``triangles`` (n_t, 3) on the ``reduced`` model."""
    erp_nodes = np.unique(triangles)
    areas = nodal_areas(mesh.points, triangles)[erp_nodes]
    normals = nodal_normals(mesh.points, triangles)[erp_nodes]
    return erp_nodes, areas, normal_velocity_basis(reduced, normals, erp_nodes)


__all__ = ["surface_triangles", "deck_surface_triangles", "erp_map"]
