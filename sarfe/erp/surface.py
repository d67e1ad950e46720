r"""Radiating-surface geometry for ERP: lumped nodal areas, nodal normals, normal displacement.

For a triangle t with vertices (a, b, c) the area vector is  s_t = ½ (x_b − x_a) × (x_c − x_a),
|s_t| its area. Lumping gives each vertex one third of the area of every triangle it belongs to,

    A_i = Σ_{t ∋ i} |s_t| / 3,        so Σ_i A_i = Σ_t |s_t| exactly;

the nodal normal is the area-weighted mean of the adjacent triangle normals,

    n_i = Σ_{t ∋ i} s_t / |Σ_{t ∋ i} s_t|     (orientation follows the triangle winding),

and the surface-normal displacement harmonics are  W[:, i] = U[:, i, :] · n_i.
"""
from __future__ import annotations

import numpy as np

from sarfe.mesh import geometry

__all__ = ["triangle_area_vectors", "nodal_areas", "nodal_normals", "normal_displacement",
           "nodal_translations"]


def _checked(points, triangles):
    x = np.asarray(points, dtype=float)
    tri = np.asarray(triangles, dtype=int)
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"points must be (n, 3), got {x.shape}")
    if tri.ndim != 2 or tri.shape[1] != 3:
        raise ValueError(f"triangles must be (n_tri, 3), got {tri.shape}")
    if tri.size and (tri.min() < 0 or tri.max() >= x.shape[0]):
        raise ValueError("triangles refer to points that do not exist")
    return x, tri


def triangle_area_vectors(points, triangles) -> np.ndarray:
    """s_t = ½ (x_b − x_a) × (x_c − x_a) [m²], shape (n_tri, 3) (sarfe.mesh.geometry, with checks)."""
    return geometry.triangle_area_vectors(*_checked(points, triangles))


def nodal_areas(points, triangles) -> np.ndarray:
    """Lumped nodal areas A_i = Σ_{t ∋ i} |s_t| / 3 [m²], shape (n,) (0 for unused points)."""
    return geometry.nodal_areas(*_checked(points, triangles))


def nodal_normals(points, triangles) -> np.ndarray:
    """Area-weighted unit nodal normals n_i following the triangle winding, shape (n, 3); zero rows
    for points on no triangle (sarfe.mesh.geometry.node_normals without re-orientation)."""
    return geometry.node_normals(*_checked(points, triangles), orient=False)


def normal_displacement(displacement, normals) -> np.ndarray:
    """W = U · n per node: displacement harmonics (2H+1, n, 3) [m], normals (n, 3) → (2H+1, n) [m]."""
    U = np.asarray(displacement, dtype=float)
    normals = np.asarray(normals, dtype=float)
    if U.ndim != 3 or U.shape[2] != 3 or U.shape[1:] != normals.shape:
        raise ValueError(
            f"displacement (2H+1, n, 3) and normals (n, 3) do not match: {U.shape}, {normals.shape}")
    return np.einsum("hij,ij->hi", U, normals)


def nodal_translations(displacement, nodes, dofs_per_node: int = 6) -> np.ndarray:
    """Translations (2H+1, len(nodes), 3) [m] of ``nodes`` from DOF harmonics (2H+1, n_dof).

    DOF numbering is node-major, dof = dofs_per_node · node + [ux, uy, uz, …] (sarfe/fe).
    """
    U = np.asarray(displacement, dtype=float)
    nodes = np.asarray(nodes, dtype=int)
    dofs = dofs_per_node * nodes[:, None] + np.arange(3)
    if dofs.size and dofs.max() >= U.shape[-1]:
        raise ValueError(f"node {nodes.max()} needs DOF {dofs.max()} but displacement has {U.shape[-1]}")
    return U[:, dofs]
