"""sarfe.mesh: shell meshes of panels — data structure, geometry, file loading, generators.

Modules: mesh (``PanelMesh``, frozen, SI, named node and element groups), io (``load_mesh(path,
length_unit)``), geometry (areas, normals, contact frames, connectivity), quality (checks naming
bad elements), cache (generated meshes kept on disk), laminate (classical lamination theory),
gmsh_model (one headless, seeded gmsh session); generators/ (parametric gmsh geometries:
``sarfe.mesh.generators.<rattle_rig|squeak_rig|door_trim|instrument_panel>.generate(...)``);
formats/ (Nastran and Abaqus decks → ``DeckModel``).
"""
from sarfe.mesh.geometry import (
    contact_frames,
    connected_components,
    facet_normals,
    nodal_areas,
    node_normals,
    orient_triangles,
    orphan_nodes,
    triangle_areas,
)
from sarfe.mesh.io import LENGTH_UNITS, MeshError, load_mesh
from sarfe.mesh.mesh import GroupError, PanelMesh

__all__ = [
    "PanelMesh", "GroupError", "MeshError", "load_mesh", "LENGTH_UNITS",
    "contact_frames", "connected_components", "facet_normals", "nodal_areas", "node_normals",
    "orient_triangles", "orphan_nodes", "triangle_areas",
]
