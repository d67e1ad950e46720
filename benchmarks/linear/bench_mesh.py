"""Mesh generation benchmark: time and size of every generator at production sizes.

Writes benchmarks/results/mesh.md and mesh.json.  Run: python benchmarks/linear/bench_mesh.py
"""
from __future__ import annotations

import importlib
import os
import pathlib
import platform
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import write_results  # noqa: E402

RUNS = [("rattle_rig", 0.005), ("squeak_rig", 0.005), ("instrument_panel", 0.01),
        ("instrument_panel", 0.005), ("door_trim", 0.01), ("door_trim", 0.005)]


def main() -> None:
    import gmsh

    rows = []
    for name, size in RUNS:
        module = importlib.import_module(f"sarfe.mesh.generators.{name}")
        start = time.perf_counter()
        mesh = module.generate(mesh_size=size)
        seconds = time.perf_counter() - start
        pairs = len(mesh.contact_pairs())
        clips = len(mesh.group_names("clip_")) + len(mesh.group_names("clamp_"))
        rows.append(dict(generator=name, mesh_size_mm=size * 1e3, nodes=mesh.n_nodes,
                         dof=6 * mesh.n_nodes, triangles=mesh.n_triangles, contact_pairs=pairs,
                         supports=clips, seconds=round(seconds, 2)))
        print(rows[-1], flush=True)
    write_results("mesh", rows)
    lines = ["# Mesh generation (sarfe.mesh.generators)", "",
             f"gmsh {gmsh.__version__}, one thread, {platform.machine()}, load average at end "
             f"{os.getloadavg()[0]:.1f} (shared machine: times are upper bounds).", "",
             "| generator | mesh size [mm] | nodes | DOF (6/node) | triangles | contact pairs | supports | time [s] |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['generator']} | {r['mesh_size_mm']:g} | {r['nodes']} | {r['dof']} | "
                     f"{r['triangles']} | {r['contact_pairs']} | {r['supports']} | {r['seconds']} |")
    write_results("mesh", markdown=lines)


if __name__ == "__main__":
    main()
