"""sarfe.mesh.generators: parametric, deterministic gmsh (OpenCASCADE) geometries.

Each module has `generate(mesh_size=..., path=None, **params) -> PanelMesh` (metres; writes a
Gmsh 4.1 `.msh` to `path` if given):

* `rattle_rig`        cantilever strip with tip striker over a clamped plate
* `squeak_rig`        cantilever strip with a spherical-cap pad resting on a clamped plate
* `door_trim`         curved carrier + ribs + clip towers + map pocket with contact spots
* `instrument_panel`  curved IP top + ribs + clip towers + trim strip with contact spots
"""
GENERATORS = ("rattle_rig", "squeak_rig", "door_trim", "instrument_panel")
