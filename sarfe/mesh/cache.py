"""On-demand generation of the large generated meshes with a file cache keyed by parameters.

`cached_mesh("door_trim", mesh_size=0.005)` returns the mesh from
``<cache_dir>/door_trim-<key>.msh`` if present, otherwise generates it (binary Gmsh 4.1, exact
doubles, so a cached mesh equals a freshly generated one bit for bit) and stores it.
The key hashes generator name, mesh size, parameters, `CACHE_VERSION` and the gmsh version.
Cache directory: argument, else $SARFE_MESH_CACHE, else ~/.cache/sarfe/meshes.
"""
from __future__ import annotations

import hashlib
import importlib
import json
import os
import tempfile
from pathlib import Path

from .generators import GENERATORS
from .io import load_mesh
from .mesh import PanelMesh

CACHE_VERSION = 1  # bump when a generator's geometry changes


def cache_key(generator: str, mesh_size: float, params: dict) -> str:
    """Hex key (16 chars) of everything the generated mesh depends on."""
    import gmsh

    payload = json.dumps({"generator": generator, "mesh_size": float(mesh_size),
                          "params": {k: params[k] for k in sorted(params)},
                          "version": CACHE_VERSION, "gmsh": gmsh.__version__},
                         sort_keys=True, default=float)
    return hashlib.sha256(payload.encode()).hexdigest()[:16]


def default_cache_dir() -> Path:
    env = os.environ.get("SARFE_MESH_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "sarfe" / "meshes"


def cached_mesh(generator: str, mesh_size: float, cache_dir=None, **params) -> PanelMesh:
    """Mesh of `sarfe.mesh.generators.<generator>` for these parameters, generated at most once."""
    if generator not in GENERATORS:
        raise ValueError(f"unknown generator {generator!r}; available: {', '.join(GENERATORS)}")
    directory = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    path = directory / f"{generator}-{cache_key(generator, mesh_size, params)}.msh"
    if path.is_file():
        return load_mesh(path)
    directory.mkdir(parents=True, exist_ok=True)
    module = importlib.import_module(f"sarfe.mesh.generators.{generator}")
    handle, partial = tempfile.mkstemp(suffix=".msh", dir=directory)
    os.close(handle)
    try:
        mesh = module.generate(mesh_size=mesh_size, path=partial, **params)
        os.replace(partial, path)  # atomic: concurrent workers never see half a file
    finally:
        if os.path.exists(partial):
            os.remove(partial)
    return mesh
