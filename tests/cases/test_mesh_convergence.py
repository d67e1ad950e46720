"""Issue 29: the radiated level belongs to the design, not to the mesh. A user changes only
``model.fe.generator.mesh_size_m`` (and the frequency): neighbouring meshes agree within 1 dB(A)
and the finest within 1 dB(A) of a stored converged reference (tests/cases/data/
mesh_convergence_reference.json, how it was made written in it), and every mesh lies within its
own reported ± (mesh term included) of that reference. Before the contacts came from the
geometry, the squeak rig's level jumped by up to 13.7 dB between meshes (one node's leaning mesh
normal let the pad's sliding into the plate); benchmarks/accuracy/bench_mesh_convergence.py
measures both ladders before and after (benchmarks/results/mesh_convergence.md);
benchmarks/accuracy/bench_mesh_cover.py each mesh's ± against its error (mesh_cover.md)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from sarfe.pipeline import load_case, solve_case

CASES = Path(__file__).resolve().parents[2] / "cases"
REFERENCE = json.loads((Path(__file__).parent / "data" / "mesh_convergence_reference.json")
                       .read_text())


def level_dba(tmp_path, name, mesh_m, frequency_hz, **solver):
    """dB(A) and the run's own ± (its mesh term included where ``solver.mesh_error`` is on, the
    default) of the shipped case at one frequency on a mesh of `mesh_m`."""
    data = load_case(CASES / f"{name}.yaml").data
    data["model"]["fe"]["generator"]["mesh_size_m"] = mesh_m
    data["excitation"].pop("sweep", None)
    data["excitation"]["frequency_hz"] = [frequency_hz]
    data["solver"].update(solver)
    data["output"]["files"] = ["summary"]
    result = solve_case(data, output_dir=tmp_path / f"{name}_{mesh_m * 1e3:g}mm")
    point = result.summary["points"][0]
    assert point["converged"] and result.exit_code == 0
    return point["erp"]["level_dba"], point["error_estimate"]["erp_db"]


def test_squeak_rig_level_does_not_depend_on_where_the_nodes_are(tmp_path):
    """12 and 9 mm: the old node normal leaned 2.4° / 2.5° in different directions and the two
    meshes read 28.7 / 15.7 dB(A) at 50 Hz; from the plate's surface normal, with the friction
    acting on the plate's face, they agree within 1 dB(A) (measured 30.8 / 30.3) and lie within
    2 dB(A) of the 1 mm reference (29.15; the mesh's own error is issue 29 item 4's ±)."""
    ref = REFERENCE["squeak_rig"]
    coarse, _ = level_dba(tmp_path, "squeak_rig", 0.012, ref["frequency_hz"], stability=False)
    other, _ = level_dba(tmp_path, "squeak_rig", 0.009, ref["frequency_hz"], stability=False)
    assert abs(coarse - other) < 1.0
    for level in (coarse, other):
        assert abs(level - ref["level_dba"]) < 2.0


@pytest.mark.slow
@pytest.mark.timeout(1800)      # door trim 14 → 5 mm with the mesh term's re-solves: ≈ 4 CPU min
@pytest.mark.parametrize("name, ladder", [
    ("squeak_rig", (0.012, 0.010, 0.009, 0.008, 0.007, 0.006, 0.005, 0.004)),
    ("door_trim", (0.014, 0.010, 0.007, 0.005)),
])
def test_mesh_ladder_converges_to_the_stored_reference(name, ladder, tmp_path):
    """Neighbouring meshes within 1 dB(A); the finest within 1 dB(A) of the reference; every mesh
    within its own reported ± (the run's whole ``error_estimate.erp_db`` at the defaults, its mesh
    term included) of the reference. Measured (benchmarks/results/mesh_cover.md, 2026-11-28):
    squeak rig 12 → 4 mm errors 1.49 / 0.79 / 0.95 / 0.69 / 0.82 / 0.54 / 0.21 / 0.40 dB against
    ± 2.87 / 1.90 / 3.87 / 3.35 / 1.95 / 0.72 / 1.23 / 0.83; door trim 14 → 5 mm 1.44 / 0.96 /
    0.40 / 0.13 against 5.55 / 4.75 / 1.37 / 0.67 (the two-mesh estimate before: the squeak rig's
    10 mm read ± 0.57 against 0.79)."""
    ref = REFERENCE[name]
    runs = [level_dba(tmp_path, name, m, ref["frequency_hz"]) for m in ladder]
    levels = [level for level, _ in runs]
    steps = [abs(b - a) for a, b in zip(levels, levels[1:])]
    assert max(steps) < 1.0, dict(zip(ladder, levels))
    assert abs(levels[-1] - ref["level_dba"]) < 1.0, dict(zip(ladder, levels))
    uncovered = {m: (round(level - ref["level_dba"], 2), round(abs(pm), 2))
                 for m, (level, pm) in zip(ladder, runs) if abs(level - ref["level_dba"]) > abs(pm)}
    assert not uncovered, uncovered                 # mesh → (level − reference, its own ±)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["squeak_rig", "door_trim"])
def test_stored_reference_is_what_the_fine_mesh_gives(name, tmp_path):
    """The stored reference is reproduced (its 'how': the same mesh and solver settings)."""
    ref = REFERENCE[name]
    level, _ = level_dba(tmp_path, name, ref["mesh_m"], ref["frequency_hz"], **ref["solver"])
    assert level == pytest.approx(ref["level_dba"], abs=0.05)
