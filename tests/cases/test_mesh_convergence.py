"""Issue 29: the radiated level belongs to the design, not to the mesh. A user changes only
``model.fe.generator.mesh_size_m`` (and the frequency): neighbouring meshes agree within 1 dB(A)
and the finest within 1 dB(A) of a stored converged reference (tests/cases/data/
mesh_convergence_reference.json, how it was made written in it). Before the contacts came from the
geometry, the squeak rig's level jumped by up to 13.7 dB between meshes (one node's leaning mesh
normal let the pad's sliding into the plate); benchmarks/accuracy/bench_mesh_convergence.py
measures both ladders before and after (benchmarks/results/mesh_convergence.md)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from sarfe.pipeline import load_case, solve_case

CASES = Path(__file__).resolve().parents[2] / "cases"
REFERENCE = json.loads((Path(__file__).parent / "data" / "mesh_convergence_reference.json")
                       .read_text())


def level_dba(tmp_path, name, mesh_m, frequency_hz, **solver):
    """dB(A) and the run's own ± of the shipped case at one frequency on a mesh of `mesh_m`."""
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
@pytest.mark.parametrize("name, ladder", [
    ("squeak_rig", (0.012, 0.010, 0.009, 0.008, 0.007, 0.006, 0.005, 0.004)),
    ("door_trim", (0.014, 0.010, 0.007, 0.005)),
])
def test_mesh_ladder_converges_to_the_stored_reference(name, ladder, tmp_path):
    """Neighbouring meshes within 1 dB(A); the finest within 1 dB(A) of the reference."""
    ref = REFERENCE[name]
    levels = [level_dba(tmp_path, name, m, ref["frequency_hz"])[0] for m in ladder]
    steps = [abs(b - a) for a, b in zip(levels, levels[1:])]
    assert max(steps) < 1.0, dict(zip(ladder, levels))
    assert abs(levels[-1] - ref["level_dba"]) < 1.0, dict(zip(ladder, levels))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["squeak_rig", "door_trim"])
def test_stored_reference_is_what_the_fine_mesh_gives(name, tmp_path):
    """The stored reference is reproduced (its 'how': the same mesh and solver settings)."""
    ref = REFERENCE[name]
    level, _ = level_dba(tmp_path, name, ref["mesh_m"], ref["frequency_hz"], **ref["solver"])
    assert level == pytest.approx(ref["level_dba"], abs=0.05)
