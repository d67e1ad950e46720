"""Shared steps of the gmsh generators: mesh options, groups, embedded nodes, output."""
from __future__ import annotations

import os

import numpy as np

from sarfe.mesh.gmsh_model import mesh_from_gmsh
from sarfe.mesh.mesh import PanelMesh


def set_mesh_size(gmsh, mesh_size: float) -> None:
    """Uniform target edge length `mesh_size` [m], Frontal-Delaunay triangles, deterministic."""
    if not mesh_size > 0:
        raise ValueError(f"mesh_size must be positive, got {mesh_size}")
    gmsh.option.setNumber("Mesh.MeshSizeMax", mesh_size)
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.3 * mesh_size)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    gmsh.option.setNumber("Mesh.ElementOrder", 1)
    gmsh.option.setNumber("Mesh.Optimize", 0)


def refine_ball(gmsh, centre, radius: float, size_in: float, size_out: float) -> None:
    """Target edge length `size_in` inside a ball (`centre`, `radius`), `size_out` elsewhere."""
    field = gmsh.model.mesh.field
    tag = field.add("Ball")
    field.setNumber(tag, "XCenter", centre[0])
    field.setNumber(tag, "YCenter", centre[1])
    field.setNumber(tag, "ZCenter", centre[2])
    field.setNumber(tag, "Radius", radius)
    field.setNumber(tag, "Thickness", radius)
    field.setNumber(tag, "VIn", size_in)
    field.setNumber(tag, "VOut", size_out)
    field.setAsBackgroundMesh(tag)


def add_group(gmsh, dim: int, tags, name: str) -> None:
    """Named physical group of the entities `tags` of dimension `dim`."""
    tags = [int(t) for t in np.atleast_1d(tags)]
    if not tags:
        raise ValueError(f"physical group {name!r} would be empty")
    gmsh.model.addPhysicalGroup(dim, tags, name=name)


def add_rig_clamps(gmsh, x_clamp: float, y: float, z: float, half_width: float, plate: int) -> None:
    """Test-rig supports: ``clamp_beam`` = the strip's edge curve at x = x_clamp (height z, within
    ±half_width of y), ``clamp_plate`` = every boundary curve of the plate surface."""
    eps = 1e-6
    clamp_beam = [t for _, t in gmsh.model.getEntitiesInBoundingBox(
        x_clamp - eps, y - half_width, z - eps, x_clamp + eps, y + half_width, z + eps, 1)]
    clamp_plate = [t for _, t in gmsh.model.getBoundary([(2, plate)], oriented=False)]
    add_group(gmsh, 1, clamp_beam, "clamp_beam")
    add_group(gmsh, 1, clamp_plate, "clamp_plate")


def embed_points(gmsh, surface: int, coordinates) -> list[int]:
    """Add points (k, 3) [m] and embed them in `surface` so they become mesh nodes.

    Must be called after `occ.synchronize()`; the nodes sit exactly at the given coordinates.
    """
    tags = [gmsh.model.occ.addPoint(*map(float, xyz)) for xyz in np.atleast_2d(coordinates)]
    gmsh.model.occ.synchronize()
    gmsh.model.mesh.embed(0, tags, 2, surface)
    return tags


def finish(gmsh, path=None) -> PanelMesh:
    """Mesh the surfaces, convert to `PanelMesh`, optionally write a binary Gmsh 4.1 `.msh` to `path`."""
    gmsh.model.mesh.generate(2)
    mesh = mesh_from_gmsh()
    if path is not None:
        path = os.fspath(path)
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 1)  # exact doubles: loading gives the same mesh
        gmsh.write(path)
    return mesh
