"""sarfe.mesh.generators: parametric, deterministic gmsh (OpenCASCADE) geometries.

Each module has `generate(mesh_size=..., path=None, **params) -> PanelMesh` (metres; writes a
Gmsh 4.1 `.msh` to `path` if given):

* `rattle_rig`        cantilever strip with tip striker over a clamped plate
* `squeak_rig`        cantilever strip with a spherical-cap pad resting on a clamped plate
* `door_trim`         curved carrier + ribs + clip towers + map pocket with contact spots
* `instrument_panel`  curved IP top + ribs + clip towers + trim strip with contact spots
"""
GENERATORS = ("rattle_rig", "squeak_rig", "door_trim", "instrument_panel")


def parameter_names(name: str) -> tuple:
    """The ``params`` a generator takes: the keyword arguments of its ``generate`` other than
    mesh_size and path, plus those of its ``spec`` when ``generate`` passes **params on."""
    import importlib
    import inspect

    module = importlib.import_module(f"{__name__}.{name}")
    names = []
    for function in (module.generate, getattr(module, "spec", None)):
        if function is None:
            continue
        names += [p.name for p in inspect.signature(function).parameters.values()
                  if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)
                  and p.name not in ("mesh_size", "path")]
    return tuple(dict.fromkeys(names))
