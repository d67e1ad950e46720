"""Linear stage of the door trim through the deck path against the generator path.

The door trim at 10 mm is written as a Nastran deck in mm-t-s (sarfe.mesh.formats.nastran_writer: CQUAD4 /
CTRIA3, PSHELL, MAT1, rigid clips as RBE2 + stiff CBUSH + CONM2, SPC1, SET1). Each path runs in a
fresh Python process (peak memory ru_maxrss is that path's alone): the generator case (mesh from the
cache, shell K, M, Craig–Bampton) and the deck case (pyNastran read, checks, deck assembly,
Craig–Bampton) with the same boundary (three contact pairs), cutoff and base excitation.

Writes benchmarks/results/deck_pipeline.md and .json.
Usage: python benchmarks/linear/bench_deck_pipeline.py [--size 0.01]
"""
from __future__ import annotations

import argparse
import json
import pathlib
import platform
import resource
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ROOT, write_results  # noqa: E402

sys.path.insert(0, str(ROOT / "tests" / "pipeline" / "model"))    # test_deck_door: the two cases


def run_one(kind: str, size: float, directory: str) -> dict:
    import numpy as np
    import test_deck_door as door

    from sarfe.pipeline import build_linear_model

    door.SIZE = size
    written = json.loads((pathlib.Path(directory) / "written.json").read_text())

    class Written:
        set_ids = written

    generator, deck = door.cases(pathlib.Path(directory), Written, contacts=True)
    case = generator if kind == "generator" else deck
    clock = time.perf_counter()
    stage = build_linear_model(case)
    seconds = time.perf_counter() - clock
    return {"kind": kind, "seconds": seconds, "timings": stage.timings,
            "peak_rss_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6,
            "nodes": stage.info["nodes"], "triangles": stage.info["triangles"],
            "free_dofs": stage.info["free_dofs"], "reduced_dofs": stage.info["reduced_dofs"],
            "first_modes_hz": np.asarray(stage.mode_frequencies_hz[:5]).tolist()}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=float, default=0.01)
    parser.add_argument("--one", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.one:
        print(json.dumps(run_one(args.one[0], args.size, args.one[1])))
        return
    from sarfe.mesh.cache import cached_mesh
    import test_deck_door as door
    from sarfe.mesh.formats.nastran_writer import ShellProperty, write_panel_deck

    directory = tempfile.mkdtemp(prefix="bench_deck_")
    mesh = cached_mesh("door_trim", args.size)
    properties = [ShellProperty("*", *door.PP, 2.5e-3), ShellProperty("part_ribs", *door.PP, 1.5e-3),
                  ShellProperty("part_bosses", *door.PP, 2.0e-3),
                  ShellProperty("part_map_pocket", *door.ABS, 2.0e-3)]
    groups = sorted(g for g in mesh.node_groups if g.startswith(("contact_", "excite_")))
    written = write_panel_deck(pathlib.Path(directory) / "door.bdf", mesh, properties,
                               clips=["clip_[0-9]*"], clamped=["clip_pocket_*"], node_sets=groups)
    (pathlib.Path(directory) / "written.json").write_text(json.dumps(written.set_ids))
    results = []
    for kind in ("generator", "deck", "generator", "deck"):
        out = subprocess.run([sys.executable, __file__, "--size", str(args.size), "--one", kind,
                              directory], capture_output=True, text=True)
        if out.returncode:
            raise SystemExit(f"{kind} run failed:\n{out.stderr[-3000:]}")
        results.append(json.loads(out.stdout.strip().splitlines()[-1]))
    best = {k: min((r for r in results if r["kind"] == k), key=lambda r: r["seconds"])
            for k in ("generator", "deck")}
    write_results("deck_pipeline", {"size_m": args.size, "machine": platform.platform(), "runs": results},
                  indent=2)
    g, d = best["generator"], best["deck"]
    lines = [
        "# Deck path vs generator path: door trim linear stage", "",
        f"Door trim at {args.size * 1e3:g} mm: {g['nodes']} nodes (deck: {d['nodes']} GRIDs with the "
        f"clip spiders), {g['triangles']} triangles; boundary = 3 contact pairs; cutoff 600 Hz + "
        "residual vectors; base excitation. Best of two fresh processes each, loaded 2-core machine "
        f"({platform.machine()}). `python benchmarks/linear/bench_deck_pipeline.py`.", "",
        "| path | linear stage [s] | read/mesh [s] | assembly [s] | reduction [s] | peak RSS [GB] | free DOFs | reduced DOFs | first modes [Hz] |",
        "|---|---|---|---|---|---|---|---|---|"]
    for r in (g, d):
        t = r["timings"]
        read = t.get("deck_s", t.get("mesh_s", float("nan")))
        lines.append(f"| {r['kind']} | {r['seconds']:.1f} | {read:.1f} | {t.get('assembly_s', 0):.1f} | "
                     f"{t.get('reduction_s', 0):.1f} | {r['peak_rss_gb']:.2f} | {r['free_dofs']} | "
                     f"{r['reduced_dofs']} | {', '.join(f'{f:.2f}' for f in r['first_modes_hz'])} |")
    write_results("deck_pipeline", markdown=lines)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
