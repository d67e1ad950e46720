"""Case-file errors: one line naming the file and key path, exit code 2, no traceback, no output."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from sarfe.cli import main
from sarfe.case.read import load_case
from sarfe.case.errors import CaseError

LUMPED = """\
name: tiny
model:
  matrices:
    mass: [[1.0]]
    stiffness: [[3.9e3]]
contacts:
  - name: stop
    type: rattle
    normal_dof: 0
    gap_m: 1.0
    normal_stiffness_N_m: 1.0e5
excitation:
  forces: [{dof: 0, force_N: 1.0}]
  frequency_hz: 8.0
solver: {harmonics: 2, samples_per_period: 16}
"""

FE = """\
name: rig
model:
  fe:
    generator: {name: rattle_rig, mesh_size_m: 0.02}
    materials:
      part_plate: {E_Pa: 2.2e9, nu: 0.37, rho_kg_m3: 1050}
      part_beam: {E_Pa: 2.1e11, nu: 0.3, rho_kg_m3: 7850}
    thickness_m: {part_plate: 2.5e-3, part_beam: 1.5e-3}
    fixed: [clamp_plate, clamp_beam]
contacts:
  - name: tip
    type: rattle
    between: [contact_tip_a, contact_tip_b]
    normal_stiffness_N_m: 2.0e5
excitation:
  forces: [{group: excite_beam, direction: z, force_N: 0.05}]
  frequency_hz: 30.0
"""


def run_cli(tmp_path, text, *extra, command="solve", capsys=None):
    case = tmp_path / "case.yaml"
    case.write_text(text)
    out = tmp_path / "out"
    code = main([command, str(case), *(["--output", str(out)] if command == "solve" else []),
                 "--quiet", *extra])
    err = capsys.readouterr().err if capsys else ""
    return code, err, out


def edit(text, old, new):
    assert old in text, old
    return text.replace(old, new, 1)


CASES = [
    # (description, text transformation, expected fragments)
    ("malformed YAML", lambda t: t.replace("    mass: [[1.0]]", "    mass: [[1.0]"),
     ["malformed YAML at line"]),
    ("unknown key", lambda t: edit(t, "gap_m: 1.0", "gap_mm: 1.0"),
     ["contacts[0].gap_mm: unknown key", "did you mean 'gap_m'"]),
    ("missing key", lambda t: edit(t, "    normal_stiffness_N_m: 1.0e5\n", ""),
     ["contacts[0].normal_stiffness_N_m: missing required key"]),
    ("wrong type", lambda t: edit(t, "force_N: 1.0", "force_N: strong"),
     ["excitation.forces[0].force_N: expected a number, got 'strong'"]),
    ("negative frequency", lambda t: edit(t, "frequency_hz: 8.0", "frequency_hz: -8.0"),
     ["excitation.frequency_hz: must be > 0"]),
    ("negative stiffness", lambda t: edit(t, "normal_stiffness_N_m: 1.0e5", "normal_stiffness_N_m: -1.0e5"),
     ["contacts[0].normal_stiffness_N_m: must be > 0"]),
    ("H < 1", lambda t: edit(t, "harmonics: 2", "harmonics: 0"),
     ["solver.harmonics: must be >= 1"]),
    ("N < 2H+1", lambda t: edit(t, "samples_per_period: 16", "samples_per_period: 4"),
     ["solver.samples_per_period: must be >= 2H+1 = 5"]),
    ("DOF out of range", lambda t: edit(t, "normal_dof: 0", "normal_dof: 3"),
     ["contacts[0].normal_dof.dof: DOF 3 out of range"]),
    ("missing matrix file", lambda t: edit(t, "mass: [[1.0]]", "mass: nowhere.npz"),
     ["model.matrices.mass: matrix file not found"]),
    ("duplicate key", lambda t: edit(t, "    gap_m: 1.0\n", "    gap_m: 1.0\n    gap_m: 2.0\n"),
     ["contacts[0].gap_m: duplicate key"]),
    ("not a mapping", lambda t: "- just\n- a list\n", ["must be a mapping"]),
    ("both fe and matrices missing", lambda t: edit(t, "  matrices:", "  matrix:"),
     ["model.matrix: unknown key"]),
]


@pytest.mark.parametrize("description, change, fragments", CASES, ids=[c[0] for c in CASES])
def test_error_is_one_line_exit_2_no_output(tmp_path, capsys, description, change, fragments):
    code, err, out = run_cli(tmp_path, change(LUMPED), capsys=capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    assert str(tmp_path / "case.yaml") in lines[0]
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out")]  # no temp dir left


@pytest.mark.parametrize("field, value, message", [
    ("E_Pa: 2.2e9", "E_Pa: -2.2e9", "model.fe.materials.part_plate.E_Pa: must be > 0"),
    ("rho_kg_m3: 1050", "rho_kg_m3: 0", "model.fe.materials.part_plate.rho_kg_m3: must be > 0"),
    ("nu: 0.37", "nu: 0.5", "model.fe.materials.part_plate.nu: must be < 0.5"),
])
def test_unphysical_material(field, value, message):
    import yaml

    from sarfe.case.read import CaseLoader
    with pytest.raises(CaseError) as info:
        load_case(yaml.load(edit(FE, field, value), Loader=CaseLoader))
    assert message in str(info.value)


def test_node_group_not_in_mesh_lists_available(tmp_path, capsys):
    code, err, out = run_cli(tmp_path, edit(FE, "contact_tip_b]", "clip_99]"), command="validate",
                             capsys=capsys)
    assert code == 2
    line = err.strip()
    assert "\n" not in line
    assert "contacts[0].between[1]: node group 'clip_99' not in mesh (available: " in line
    assert "contact_tip_a" in line and "clamp_plate" in line


def test_unpairable_contact(tmp_path, capsys):
    text = edit(FE, "    normal_stiffness_N_m: 2.0e5",
                "    normal_stiffness_N_m: 2.0e5\n    pairing_tolerance_m: 1.0e-5")
    code, err, _ = run_cli(tmp_path, text, command="validate", capsys=capsys)
    assert code == 2
    assert "contacts[0].between: 1 of 1 nodes of 'contact_tip_a' have no point of the surface of " \
           "'contact_tip_b' within pairing_tolerance_m" in err


def test_missing_mesh_file_and_units(tmp_path, capsys):
    text = edit(FE, "generator: {name: rattle_rig, mesh_size_m: 0.02}", "mesh: panel.msh")
    code, err, _ = run_cli(tmp_path, text, command="validate", capsys=capsys)
    assert code == 2 and "model.fe.mesh: mesh file not found" in err
    text = edit(FE, "generator: {name: rattle_rig, mesh_size_m: 0.02}",
                "generator: {name: rattle_rig, mesh_size_m: 0.02}\n    mesh_units: mm")
    code, err, _ = run_cli(tmp_path, text, command="validate", capsys=capsys)
    assert code == 2 and "model.fe.mesh_units: generated meshes are in metres" in err


def test_unreadable_mesh_file(tmp_path, capsys):
    (tmp_path / "panel.msh").write_text("this is not a mesh\n")
    text = edit(FE, "generator: {name: rattle_rig, mesh_size_m: 0.02}", "mesh: panel.msh")
    code, err, _ = run_cli(tmp_path, text, command="validate", capsys=capsys)
    assert code == 2 and "model.fe.mesh: " in err and len(err.strip().splitlines()) == 1


def test_thickness_in_mm_by_mistake(tmp_path, capsys):
    text = edit(FE, "part_plate: 2.5e-3, part_beam: 1.5e-3", "part_plate: 2.5, part_beam: 1.5")
    code, err, _ = run_cli(tmp_path, text, capsys=capsys)
    assert code == 2 and "model.fe.thickness_m.part_plate: thickness 2.5 m is not small" in err
    code, err, _ = run_cli(tmp_path, text, command="validate", capsys=capsys)
    assert code == 2 and "given in mm?" in err and len(err.strip().splitlines()) == 1


def test_debug_shows_traceback(tmp_path, capsys):
    code, err, _ = run_cli(tmp_path, edit(LUMPED, "gap_m: 1.0", "gap_mm: 1.0"), "--debug",
                           capsys=capsys)
    assert code == 2 and "Traceback" in err


def test_subprocess_error_and_version(tmp_path):
    case = tmp_path / "bad.yaml"
    case.write_text(edit(LUMPED, "frequency_hz: 8.0", "frequency_hz: 0"))
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    proc = subprocess.run([sys.executable, "-m", "sarfe", "solve", str(case), "--output",
                           str(tmp_path / "out")], capture_output=True, text=True, env=env,
                          timeout=300)
    assert proc.returncode == 2
    assert proc.stderr.strip() == (f"sarfe: error: {case}: excitation.frequency_hz: must be > 0, "
                                   "got 0 (line 14)")
    assert not (tmp_path / "out").exists()
    proc = subprocess.run([sys.executable, "-m", "sarfe", "--version"], capture_output=True,
                          text=True, env=env, timeout=300)
    assert proc.returncode == 0 and proc.stdout.startswith("sarfe ")
