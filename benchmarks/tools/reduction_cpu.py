"""The CPU seconds of a case's fine linear stage, part by part (the Craig–Bampton reduction's own
timings), and of the mesh term's coarser levels — the floor under a run's wall time on few cores.

    python benchmarks/tools/reduction_cpu.py CASE.yaml [--coarse] [OUT.json]

Builds the case's linear stage (``sarfe.pipeline.model.linear_stage.build_linear_model``, the
solve's own code: mesh, assembly, Craig–Bampton with the two-process spectrum slicing) in this
process and prints its CPU seconds by part: partition, K_ii factorization, constraint modes Ψ,
residual statics, normal modes (this process; the slicing worker's CPU from its own record),
residual modes, projection. ``--coarse`` builds the mesh term's two coarser levels too
(``sarfe.pipeline.solve.mesh_error.coarse_model``, one after the other, as the background process
of a solve does). A run whose whole CPU is C seconds cannot finish in less than C / cores of wall
time: the linear stages measured here are the part no point work can hide.
"""
from __future__ import annotations

import json
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
import benchlib  # noqa: E402,F401  (one BLAS thread, this tree first on sys.path)

from sarfe.case.read import load_case  # noqa: E402
from sarfe.pipeline.model.linear_stage import build_linear_model  # noqa: E402
from sarfe.pipeline.solve.mesh_error import coarse_model, coarse_sizes  # noqa: E402

PARTS = ("partition", "factorization", "constraint_modes", "residual_static", "normal_modes",
         "residual_modes", "projection")


def stage_cpu(build) -> dict:
    """{'wall_s', 'cpu_s' (this process), 'parts_cpu_s' {part: s}, 'slicing_worker_cpu_s',
    'modes', 'dofs'} of ``build()`` → a linear stage."""
    wall, cpu = time.perf_counter(), time.process_time()
    stage = build()
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    timings = stage.reduced.timings
    upper = (timings.get("slicing") or {}).get("upper") or {}
    return {"wall_s": wall, "cpu_s": cpu,
            "parts_cpu_s": {p: timings.get(p + "_cpu", 0.0) for p in PARTS},
            "slicing_worker_cpu_s": float(upper.get("cpu_s", 0.0)),
            "modes": int(stage.reduced.mode_count), "dofs": int(stage.reduced.full_dof_count)}


def main(argv) -> int:
    args = [a for a in argv if not a.startswith("--")]
    case = load_case(args[0])
    out = {"case": args[0], "load_average_start": list(benchlib.machine().get("load_average", [])),
           "fine": stage_cpu(lambda: build_linear_model(case))}
    if "--coarse" in argv:
        out["coarse"] = {f"{size * 1e3:.2f} mm": stage_cpu(lambda s=size: coarse_model(case, s)[0])
                         for size in coarse_sizes(case)}
    for name, level in [("fine", out["fine"])] + list(out.get("coarse", {}).items()):
        parts = ", ".join(f"{p} {s:.1f}" for p, s in level["parts_cpu_s"].items())
        print(f"{name}: {level['dofs']} DOFs, {level['modes']} modes, "
              f"wall {level['wall_s']:.1f} s, CPU {level['cpu_s']:.1f} s "
              f"+ slicing worker {level['slicing_worker_cpu_s']:.1f} s (reduction: {parts})")
    if len(args) > 1:
        pathlib.Path(args[1]).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
