"""Write the meshes of the shipped cases.

Shipped in git (small, regenerate with this script after a generator change):
    meshes/rattle_rig.msh, meshes/squeak_rig.msh           (5 mm, default parameters)
Generated on demand, cached by parameters (sarfe.mesh.cache.cached_mesh), not in git:
    door_trim (10 mm and 5 mm), instrument_panel (10 mm)   → $SARFE_MESH_CACHE or ~/.cache/sarfe/meshes

Usage:  python meshes/generate.py            # rigs into meshes/
        python meshes/generate.py --all      # also warm the cache with the panels
"""
from __future__ import annotations

import argparse
import pathlib
import time

from sarfe.mesh.cache import cached_mesh
from sarfe.mesh.generators import rattle_rig, squeak_rig

HERE = pathlib.Path(__file__).resolve().parent
SHIPPED = {"rattle_rig.msh": (rattle_rig, 0.005), "squeak_rig.msh": (squeak_rig, 0.005)}
ON_DEMAND = [("door_trim", 0.01), ("door_trim", 0.005), ("instrument_panel", 0.01)]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--all", action="store_true", help="also generate the cached panel meshes")
    args = parser.parse_args(argv)
    for name, (module, size) in SHIPPED.items():
        start = time.perf_counter()
        mesh = module.generate(mesh_size=size, path=HERE / name)
        print(f"{name}: {mesh.n_nodes} nodes, {mesh.n_triangles} triangles, "
              f"{time.perf_counter() - start:.1f} s")
    if args.all:
        for generator, size in ON_DEMAND:
            start = time.perf_counter()
            mesh = cached_mesh(generator, size)
            print(f"{generator} @ {size * 1e3:g} mm (cache): {mesh.n_nodes} nodes, "
                  f"{time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
