"""Structured reference meshes for verification and benchmarks (plates, cylindrical panels).

Production panel meshes come from ``sarfe.mesh`` (Gmsh); these small numpy generators give
the closed-form / cross-model checks of ``sarfe.fe`` exactly known geometry.
"""

from __future__ import annotations

import numpy as np

from sarfe.mesh.gmsh_model import gmsh_session

__all__ = [
    "rectangle_triangles",
    "cylindrical_panel_triangles",
    "cylindrical_panel_solid",
    "gmsh_rectangle_triangles",
    "boundary_nodes",
]


def rectangle_triangles(length_x, length_y, nx, ny, pattern="alternating", distortion=0.0, seed=0):
    """Triangulated rectangle [0, length_x] × [0, length_y] in the plane z = 0.

    pattern: 'right' (all diagonals one way), 'alternating' (diagonal flips cell by cell,
    a symmetric union-jack-like mesh). distortion: interior nodes moved randomly by up to
    this fraction of the cell size (0 = regular). Returns points (n, 3) [m], triangles (n_el, 3).
    """
    x = np.linspace(0.0, length_x, nx + 1)
    y = np.linspace(0.0, length_y, ny + 1)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    points = np.column_stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)])
    if distortion:
        rng = np.random.default_rng(seed)
        inner = np.zeros(xx.shape, dtype=bool)
        inner[1:-1, 1:-1] = True
        inner = inner.ravel()
        shift = rng.uniform(-distortion, distortion, (inner.sum(), 2))
        points[inner, 0] += shift[:, 0] * length_x / nx
        points[inner, 1] += shift[:, 1] * length_y / ny
    index = np.arange(xx.size).reshape(nx + 1, ny + 1)
    n00, n10 = index[:-1, :-1], index[1:, :-1]
    n11, n01 = index[1:, 1:], index[:-1, 1:]
    if pattern == "right":
        flip = np.zeros((nx, ny), dtype=bool)
    elif pattern == "alternating":
        flip = (np.add.outer(np.arange(nx), np.arange(ny)) % 2).astype(bool)
    else:
        raise ValueError(f"pattern must be 'right' or 'alternating', got {pattern!r}")
    first = np.where(flip[..., None], np.stack([n00, n10, n01], -1), np.stack([n00, n10, n11], -1))
    second = np.where(flip[..., None], np.stack([n10, n11, n01], -1), np.stack([n00, n11, n01], -1))
    triangles = np.concatenate([first.reshape(-1, 3), second.reshape(-1, 3)])
    return points, triangles


def cylindrical_panel_triangles(radius, angle, length, n_arc, n_axial, pattern="alternating"):
    """Cylindrical shell patch: mid-surface r = radius, arc θ ∈ [−angle/2, angle/2] [rad],
    axis y ∈ [0, length] [m]; the crown is at (0, y, 0), curvature towards −z.

    Points x = R sin θ, y, z = R (cos θ − 1). Returns points (n, 3), triangles (n_el, 3).
    """
    points, triangles = rectangle_triangles(angle, length, n_arc, n_axial, pattern)
    theta = points[:, 0] - angle / 2.0
    mapped = np.column_stack(
        [radius * np.sin(theta), points[:, 1], radius * (np.cos(theta) - 1.0)]
    )
    return mapped, triangles


def cylindrical_panel_solid(radius, angle, length, thickness, n_arc, n_axial, layers,
                            kind="hex2"):
    """The same panel as a curved quadratic scikit-fem solid mesh, ``layers`` elements through
    the thickness (radius ± thickness/2). kind: 'hex2' (MeshHex2) or 'tet2' (MeshTet2,
    six tetrahedra per cell). Every geometry node is mapped exactly onto the cylinder.
    """
    import skfem

    cells = skfem.MeshHex1.init_tensor(
        np.linspace(-angle / 2.0, angle / 2.0, n_arc + 1),
        np.linspace(0.0, length, n_axial + 1),
        np.linspace(-thickness / 2.0, thickness / 2.0, layers + 1),
    )
    if kind == "hex2":
        cls, quadratic = skfem.MeshHex2, skfem.MeshHex2.from_mesh(cells)
    elif kind == "tet2":
        cls, quadratic = skfem.MeshTet2, skfem.MeshTet2.from_mesh(cells.to_meshtet())
    else:
        raise ValueError(f"kind must be 'hex2' or 'tet2', got {kind!r}")
    theta, y, offset = quadratic.doflocs
    r = radius + offset
    doflocs = np.vstack([r * np.sin(theta), y, r * np.cos(theta) - radius])
    return cls(doflocs=doflocs, t=quadratic.t)


def gmsh_rectangle_triangles(length_x, length_y, size, algorithm=6):
    """Unstructured Gmsh triangle mesh of [0, length_x] × [0, length_y] (z = 0), target
    element size ``size`` [m]; algorithm 6 = Frontal-Delaunay. Returns points, triangles."""
    with gmsh_session() as gmsh:    # the process-wide lock, headless and seeded like every mesh
        gmsh.model.occ.addRectangle(0.0, 0.0, 0.0, length_x, length_y)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMin", size)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.Algorithm", algorithm)
        gmsh.model.mesh.generate(2)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        _, _, connectivity = gmsh.model.mesh.getElements(2)
    index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    triangles = index[np.asarray(connectivity[0], dtype=np.int64).reshape(-1, 3)]
    used = np.unique(triangles)  # drop geometry-only nodes, renumber compactly
    compact = np.full(len(tags), -1, dtype=np.int64)
    compact[used] = np.arange(len(used))
    return coords.reshape(-1, 3)[used], compact[triangles]


def boundary_nodes(triangles):
    """Nodes on the free boundary of a triangle mesh (edges used by one triangle only)."""
    triangles = np.asarray(triangles)
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    return np.unique(unique[counts == 1])
