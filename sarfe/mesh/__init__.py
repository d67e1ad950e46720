"""sarfe.mesh: shell meshes of panels — data structure, geometry, file loading, generators.

`PanelMesh` (frozen, SI) and `load_mesh(path, length_unit)`; parametric gmsh geometries live in
`sarfe.mesh.generators.<rattle_rig|squeak_rig|door_trim|instrument_panel>.generate(...)`.
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
