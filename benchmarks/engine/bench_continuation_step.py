"""Continuation ``max_step`` vs curve accuracy and point count → results/continuation_step.md|json.

Cases: NLvib example 03 and the 1-DOF Jenkins oscillator (benchmarks/peer/*.yaml),
cases/lumped_rattle.yaml and cases/rattle_rig.yaml, each swept by ``sarfe solve`` (error estimate
and stability off: they do not change the curve) with ``solver.continuation.max_step`` 0.1 (the
default), 0.15 and 0.25, and a dense reference with max_step 0.02 (same H, N). The curve is the
first-harmonic amplitude a of the first excited DOF over ω (response.h5). Reported per run:
points, CPU s of the whole process, whether the sweep completed by continuation, the peak (largest
a among the points, and its ω) relative to the dense reference's, and the curve distance: the
largest distance of a dense-reference point from the run's polyline in the plane
(ω / band width, a / reference peak) — a fraction of the peak amplitude, valid through folds.

Criterion for a larger default cap (issue 13, task "peer2"): on every case the sweep completes as
it does with 0.1, the peak within 0.1 % of the dense reference, the curve distance ≤ 1 % (the
amplitude budget of the default accuracy 'balanced').

Run: OPENBLAS_NUM_THREADS=1 python benchmarks/engine/bench_continuation_step.py [case ...]
"""
import json
import os
import pathlib
import resource
import subprocess
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
from benchlib import ENV, ROOT, read_case, write_case, write_results  # noqa: E402

import numpy as np

CASES = {"nlvib03": "benchmarks/peer/nlvib03.yaml", "jenkins": "benchmarks/peer/jenkins.yaml",
         "lumped_rattle": "cases/lumped_rattle.yaml", "rattle_rig": "cases/rattle_rig.yaml"}
STEPS = (0.1, 0.15, 0.25)
DENSE_STEP = 0.02


def sweep(case, max_step, directory):
    """(ω [rad/s], first-harmonic amplitude [m], CPU s, sweep_complete) of one ``sarfe solve``."""
    import h5py
    data = read_case(case)
    solver = data.setdefault("solver", {})
    solver.update(error_estimate=False, stability=False)
    solver.setdefault("continuation", {})["max_step"] = max_step
    path = str(write_case(data, case))   # next to the case file: its relative paths resolve
    output = pathlib.Path(directory) / f"{pathlib.Path(case).stem}_{max_step}"
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        done = subprocess.run([sys.executable, "-m", "sarfe.cli", "solve", path, "-o", str(output),
                               "--quiet", "--force"], env=ENV, cwd=ROOT, capture_output=True,
                              text=True)
    finally:
        os.unlink(path)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode not in (0, 3):
        raise RuntimeError(f"{case} max_step {max_step}: {done.stderr[-1500:]}")
    summary = json.loads((output / "summary.json").read_text())
    with h5py.File(output / "response.h5") as f:
        u = f["excitation/displacement_m"][:, :, 0]
        omega = f["omega_rad_s"][:]
    return (omega, np.hypot(u[:, 1], u[:, 2]), after.ru_utime - before.ru_utime,
            summary.get("sweep_complete"))


def curve_distance(reference_omega, reference_amplitude, omega, amplitude, width, peak):
    """Largest distance of the reference points from the polyline (omega, amplitude) in the plane
    (ω / width, a / peak) → (distance, ω of that reference point)."""
    points = np.column_stack([reference_omega / width, reference_amplitude / peak])
    line = np.column_stack([omega / width, amplitude / peak])
    start, segment = line[:-1], np.diff(line, axis=0)
    length = np.maximum(np.einsum("sk,sk->s", segment, segment), 1e-300)
    t = np.clip(np.einsum("psk,sk->ps", points[:, None] - start[None], segment) / length, 0, 1)
    gap = points[:, None] - (start[None] + t[..., None] * segment[None])
    distance = np.sqrt(np.einsum("psk,psk->ps", gap, gap)).min(axis=1)
    return float(distance.max()), float(reference_omega[distance.argmax()])


def measure(name, directory):
    omega_ref, amp_ref, cpu_ref, complete_ref = sweep(CASES[name], DENSE_STEP, directory)
    peak_ref = int(amp_ref.argmax())
    width = float(np.ptp(omega_ref))
    row = {"dense": {"max_step": DENSE_STEP, "points": int(omega_ref.size), "cpu_s": cpu_ref,
                     "complete": complete_ref, "peak": float(amp_ref[peak_ref]),
                     "peak_omega": float(omega_ref[peak_ref])}, "steps": {}}
    for step in STEPS:
        omega, amp, cpu, complete = sweep(CASES[name], step, directory)
        k = int(amp.argmax())
        distance, where = curve_distance(omega_ref, amp_ref, omega, amp, width, amp_ref.max())
        row["steps"][str(step)] = {
            "points": int(omega.size), "cpu_s": cpu, "complete": complete,
            "peak": float(amp[k]), "peak_omega": float(omega[k]),
            "peak_vs_dense": float(amp[k] / amp_ref[peak_ref] - 1),
            "peak_omega_vs_dense": float(omega[k] / omega_ref[peak_ref] - 1),
            "curve_distance": distance, "curve_distance_at_omega": where}
        print(name, step, row["steps"][str(step)], flush=True)
    return row


def write(results):
    write_results("continuation_step", results)
    lines = ["# Continuation max_step vs curve accuracy", "",
             "Dense reference: max_step 0.02, same H and N. Peak = largest first-harmonic amplitude "
             "among the points; curve distance = largest distance of a reference point from the "
             "run's polyline in (ω / band, a / peak), as a fraction of the peak. Criterion for a "
             "larger default: complete as with 0.1, peak within 0.1 %, curve distance ≤ 1 %.", "",
             "| case | max_step | points | CPU s | complete | peak vs dense | peak ω vs dense | "
             "curve distance (at ω rad/s) |", "|---|---|---|---|---|---|---|---|"]
    for name, row in results.items():
        d = row["dense"]
        lines.append(f"| {name} | {d['max_step']} (reference) | {d['points']} | {d['cpu_s']:.2f} | "
                     f"{d['complete']} | peak {d['peak']:.6g} at ω {d['peak_omega']:.5g} | | |")
        for step, r in row["steps"].items():
            lines.append(f"| {name} | {step} | {r['points']} | {r['cpu_s']:.2f} | {r['complete']} | "
                         f"{r['peak_vs_dense']:+.4%} | {r['peak_omega_vs_dense']:+.4%} | "
                         f"{r['curve_distance']:.3%} ({r['curve_distance_at_omega']:.4g}) |")
    write_results("continuation_step", markdown=lines)
    print("\n".join(lines))


def main():
    names = sys.argv[1:] or list(CASES)
    with tempfile.TemporaryDirectory() as directory:
        write({name: measure(name, directory) for name in names})


if __name__ == "__main__":
    main()
