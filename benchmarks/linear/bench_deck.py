"""Reading + assembling a ~200k-DOF Nastran deck, beside the Gmsh path on the same mesh.

A flat 0.9 m × 0.9 m, 2.5 mm ABS panel of 181 × 181 CQUAD4 (33,124 GRIDs, 198,744 DOF) with
PSHELL/MAT1, SPC1 on one edge, 24 grounded CBUSH clips, 4 RBE2 spiders and 8 CONM2 masses is
written in small-field Nastran format; the same quads, split in triangles, as a Gmsh MSH 4.1
file. Each path runs in its own process so that its peak memory (ru_maxrss) is its own:
  nastran: read_nastran (pyNastran parse + cross-reference + DeckModel) → assemble_deck
  gmsh:    load_mesh (gmsh API) → shell_matrices (the isotropic facet shell)
Writes benchmarks/results/deck.md and deck.json.  Run: python benchmarks/linear/bench_deck.py
"""
from __future__ import annotations

import json
import os
import pathlib
import platform
import subprocess
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import child_env, write_results  # noqa: E402

N_QUADS = 181
WIDTH = 0.9


def _field(value):
    if isinstance(value, str):
        return f"{value:<8}"
    if isinstance(value, (int,)):
        return f"{value:<8d}"
    text = f"{value:.5g}"
    if "." not in text and "e" not in text:
        text += "."
    return f"{text:<8}"[:8]


def _card(*fields):
    return "".join(_field(f) for f in fields).rstrip() + "\n"


def write_deck(path: pathlib.Path):
    n = N_QUADS + 1
    h = WIDTH / N_QUADS
    with open(path, "w") as out:
        out.write("BEGIN BULK\n")
        out.write(_card("PSHELL", 1, 1, 0.0025, 1))
        out.write(_card("MAT1", 1, 2.2e9, "", 0.35, 1050.0))
        out.write(_card("PBUSH", 2, "K", 2e5, 2e5, 5e5, 10.0, 10.0, 10.0))
        for j in range(n):
            for i in range(n):
                out.write(_card("GRID", j * n + i + 1, "", i * h, j * h, 0.0))
        for j in range(N_QUADS):
            for i in range(N_QUADS):
                a = j * n + i + 1
                out.write(_card("CQUAD4", j * N_QUADS + i + 1, 1, a, a + 1, a + n + 1, a + n))
        edge = [j * n + 1 for j in range(n)]
        for start in range(0, len(edge), 6):
            out.write(_card("SPC1", 1, 123456, *edge[start:start + 6]))
        eid = N_QUADS**2 + 1
        clips = [(j * n + i + 1) for j in range(10, n, 40) for i in range(40, n, 40)]
        for node in clips[:24]:
            out.write(_card("CBUSH", eid, 2, node, "", "", "", "", 0))
            eid += 1
        for k, (ci, cj) in enumerate([(60, 60), (120, 60), (60, 120), (120, 120)]):
            hub = n * n + k + 1
            out.write(_card("GRID", hub, "", ci * h, cj * h, 0.02))
            ring = [(cj + dj) * n + ci + di + 1 for di, dj in ((-3, 0), (3, 0), (0, -3), (0, 3))]
            out.write(_card("RBE2", eid, hub, 123456, *ring))
            out.write(_card("CONM2", eid + 1, hub, "", 0.15))
            out.write(_card("CONM2", eid + 2, ring[0], "", 0.05))
            eid += 3
        out.write("ENDDATA\n")
    return 6 * (n * n + 4)


def write_msh(path: pathlib.Path):
    import meshio
    import numpy as np

    n = N_QUADS + 1
    h = WIDTH / N_QUADS
    x, y = np.meshgrid(np.arange(n) * h, np.arange(n) * h)
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(n * n)])
    i, j = np.meshgrid(np.arange(N_QUADS), np.arange(N_QUADS))
    a = (j * n + i).ravel()
    triangles = np.vstack([np.column_stack([a, a + 1, a + n + 1]),
                           np.column_stack([a, a + n + 1, a + n])])
    meshio.write(str(path), meshio.Mesh(points, [("triangle", triangles)]),
                 file_format="gmsh", binary=False)


_NASTRAN = """
import resource, time, json, sys
start = time.perf_counter()
from sarfe.mesh.formats.nastran import read_nastran
from sarfe.fe.deck_assembly import assemble_deck
deck = read_nastran(sys.argv[1])
read = time.perf_counter() - start
start = time.perf_counter()
system = assemble_deck(deck)
assembly = time.perf_counter() - start
print(json.dumps(dict(read_s=read, assembly_s=assembly, dof=system.n_dofs,
                      nnz=int(system.stiffness.nnz),
                      peak_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)))
"""

_GMSH = """
import resource, time, json, sys
start = time.perf_counter()
from sarfe.mesh import load_mesh
from sarfe.fe import shell_matrices
mesh = load_mesh(sys.argv[1])
read = time.perf_counter() - start
start = time.perf_counter()
k, m = shell_matrices(mesh.points, mesh.triangles, 0.0025, 2.2e9, 0.35, 1050.0)
assembly = time.perf_counter() - start
print(json.dumps(dict(read_s=read, assembly_s=assembly, dof=k.shape[0], nnz=int(k.nnz),
                      peak_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)))
"""


def _run(code, path):
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True,
                         text=True, env=child_env(), check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        deck = pathlib.Path(folder) / "panel.bdf"
        msh = pathlib.Path(folder) / "panel.msh"
        write_deck(deck)
        write_msh(msh)
        sizes = dict(deck_mb=deck.stat().st_size / 2**20, msh_mb=msh.stat().st_size / 2**20)
        rows = [dict(path="nastran (pyNastran → DeckModel → assemble_deck)", **_run(_NASTRAN, deck)),
                dict(path="gmsh (load_mesh → shell_matrices)", **_run(_GMSH, msh))]
    for row in rows:
        print(row, flush=True)
    write_results("deck", dict(files=sizes, runs=rows))
    lines = ["# Reading + assembling a 200k-DOF deck", "",
             f"{N_QUADS}×{N_QUADS} CQUAD4 panel (2.5 mm ABS) with SPC1, 24 CBUSH, 4 RBE2, 8 CONM2; "
             f"deck {sizes['deck_mb']:.1f} MB, same mesh as MSH {sizes['msh_mb']:.1f} MB. "
             f"One process per path (peak = ru_maxrss of that process, includes Python and "
             f"imports), one BLAS thread, {platform.machine()}, load average at end "
             f"{os.getloadavg()[0]:.1f} (shared machine: times are upper bounds).", "",
             "| path | DOF | nnz(K) | read [s] | assemble [s] | total [s] | peak memory [MB] |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['path']} | {r['dof']} | {r['nnz']} | {r['read_s']:.1f} | "
                     f"{r['assembly_s']:.1f} | {r['read_s'] + r['assembly_s']:.1f} | "
                     f"{r['peak_mb']:.0f} |")
    write_results("deck", markdown=lines)


if __name__ == "__main__":
    main()
