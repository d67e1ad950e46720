"""Warnings for inputs far outside the model's range (printed one line each and kept in
summary.json `warnings`), and progress reporting (a bar on a terminal, a line per stage in logs)."""
import json
import os
import sys
from pathlib import Path

import pytest

from sarfe.cli import main

ROOT = Path(__file__).resolve().parents[3]
FAR = """\
name: far
model:
  fe:
    generator: {name: rattle_rig, mesh_size_m: 0.02, params: {gap: 1.0e-3}}
    materials:
      part_plate: {E_Pa: 2.2e+9, nu: 0.37, rho_kg_m3: 1050}
      part_beam: {E_Pa: 2.1e+11, nu: 0.3, rho_kg_m3: 7850}
    thickness_m: {part_plate: 2.5e-3, part_beam: 1.5e-3}
    fixed: [clamp_plate, clamp_beam]
contacts:
  - {name: tip, type: rattle, between: [contact_tip_a, contact_tip_b],
     normal_stiffness_N_m: 2.0e+5, gap_m: 1000.0}
excitation:
  forces: [{group: excite_beam, direction: z, force_N: 0.05}]
  frequency_hz: 3000.0
solver: {harmonics: 3}
reduction: {cutoff_hz: 5000.0}
output: {files: [summary]}
"""


@pytest.fixture
def far_case(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SARFE_MESH_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "far.yaml"
    path.write_text(FAR)
    return path


def warning_lines(err):
    return [line for line in err.splitlines() if line.startswith("sarfe: warning: ")]


def test_far_inputs_warn_in_validate_and_summary(far_case, capsys):
    assert main(["validate", str(far_case)]) == 0
    lines = warning_lines(capsys.readouterr().err)
    assert len(lines) == 3
    assert "the mesh resolves" in lines[0] and "9000 Hz" in lines[0]
    assert "gap_m = 1000 m is larger than the structure" in lines[1]
    assert "reduction.cutoff_hz = 5000 Hz" in lines[2]
    assert main(["solve", str(far_case), "--output", "res", "--quiet"]) == 0
    assert warning_lines(capsys.readouterr().err) == lines
    summary = json.loads(Path("res/summary.json").read_text())
    assert summary["warnings"] == [line[len("sarfe: warning: "):] for line in lines]


def test_shipped_rig_case_has_no_warnings(far_case, capsys):
    text = (ROOT / "cases" / "squeak_rig.yaml").read_text()
    far_case.write_text(text)
    assert main(["validate", str(far_case)]) == 0
    assert warning_lines(capsys.readouterr().err) == []


def test_log_gets_one_line_per_stage(far_case, capsys):
    assert main(["solve", str(far_case), "--output", "res"]) == 0
    err = [line for line in capsys.readouterr().err.splitlines()      # (the accuracy check's
           if "warning" not in line and not line.startswith("sarfe: accuracy:")]   # own line)
    # the run's cost, said once after the checks and before the work (issue 30 item 4)
    assert [i for i, line in enumerate(err) if line.startswith("sarfe: cost: H ")] == [1]
    err = [line for line in err if not line.startswith(("sarfe: cost: ", "      "))]
    assert err == ["sarfe: checking the case: mesh, groups, quality …", "sarfe: linear stage: mesh …", "sarfe: linear stage: assembly …",
                   "sarfe: linear stage: reduction …", "sarfe: Craig-Bampton mode blocks …",
                   "sarfe: linear stage: contacts, loads, ERP map …",
                   "sarfe: frequencies (1 point) …", "sarfe: ERP and error estimates (1 point) …",
                   "sarfe: writing results …"]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="pseudo-terminal test")
def test_terminal_gets_live_bars(far_case):
    """In a 30 x 120 pseudo-terminal the stages show as tqdm bars (percent and counts)."""
    import fcntl
    import pty
    import select
    import struct
    import termios

    pid, fd = pty.fork()
    if pid == 0:  # child: the CLI on the terminal
        os.environ["PYTHONPATH"] = str(ROOT)
        os.execv(sys.executable, [sys.executable, "-m", "sarfe.cli", "solve", str(far_case),
                                  "--output", "res"])
    fcntl.ioctl(fd, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 120, 0, 0))
    out = b""
    while select.select([fd], [], [], 300)[0]:
        try:
            data = os.read(fd, 65536)
        except OSError:
            break
        if not data:
            break
        out += data
    _, status = os.waitpid(pid, 0)
    text = out.decode(errors="replace")
    assert os.WEXITSTATUS(status) == 0, text
    assert "linear stage: assembly:" in text and "frequencies:" in text and "%|" in text
    assert "sarfe: frequencies" not in text          # no log lines on a terminal


@pytest.mark.parametrize("cells", [10, 20])
def test_mesh_resolution_limit_separates_accurate_from_inaccurate_modes(cells):
    """Simply supported square plate (closed form f_mn = (π/2)(m² + n²)/a² √(D/ρt)): every FE mode
    below the warning's limit (6 longest edges per bending wavelength) is within 4 % of the exact
    frequency; past the limit the error grows beyond 10 % within the first 60 modes."""
    import numpy as np

    from sarfe.fe import fixed_dofs, natural_frequencies, shell_matrices
    from sarfe.fe.reference_meshes import boundary_nodes, rectangle_triangles
    from sarfe.pipeline.checks.case_checks import bending_resolution_hz

    a, t, E, nu, rho = 0.3, 2.5e-3, 2.2e9, 0.35, 1050.0
    wave_speed = np.sqrt(E * t ** 3 / (12 * (1 - nu ** 2)) / (rho * t))
    m, n = np.meshgrid(np.arange(1, 30), np.arange(1, 30))
    exact = np.sort((np.pi / 2 * (m ** 2 + n ** 2) / a ** 2 * wave_speed).ravel())[:60]
    points, triangles = rectangle_triangles(a, a, cells, cells)
    k, mass = shell_matrices(points, triangles, t, E, nu, rho)
    fe = natural_frequencies(k, mass, 60, fixed_dofs(boundary_nodes(triangles), "translations"))
    limit = np.median(bending_resolution_hz(points, triangles, t, E, nu, rho))
    error = np.abs(fe / exact - 1)
    below = exact <= limit
    assert below.sum() >= 3 and not below.all()
    assert error[below].max() < 0.04
    assert error[~below].max() > 0.10
