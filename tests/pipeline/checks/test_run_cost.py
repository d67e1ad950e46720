"""The cost said before the run (issue 30 item 4, :mod:`sarfe.pipeline.checks.run_cost`): the
Weyl mode count against a closed-form plate spectrum, the disk estimate against the bytes a run
writes (±30 %), the range growing with the points and H and with a stiff contact's own frequency
(the raised N, the points, the impact check), and the line in validate and solve."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from sarfe import cli
from sarfe.case.read import load_case
from sarfe.pipeline import solve_case
from sarfe.pipeline.checks.case_checks import check_case
from sarfe.accuracy.harmonic_truncation import extended_harmonics
from sarfe.hbm.continuation import MAX_SAMPLES_FACTOR, MAX_STALL_FACTOR, most_samples
from sarfe.pipeline.checks.run_cost import (HARD_RATIO, POINTS_EXPONENT, SAMPLES_PER_IMPACT,
                                            ModelSize, RunCost, contact_frequency, cost_lines,
                                            impact_check_seconds, plate_bending, run_cost,
                                            stiffness_ratio, weyl_mode_density)
from sarfe.pipeline.solve.mesh_error import mesh_error_reason
from tests.small_cases import TINY, coarse_rig

CASES = Path(__file__).resolve().parents[3] / "cases"
DISK_TOLERANCE = 0.30       # estimated bytes within ±30 % of the written ones (listed points)


def test_weyl_density_counts_a_simply_supported_plate():
    """Simply supported a × b plate: f_mn = (π/2) √(D/ρt) ((m/a)² + (n/b)²), m, n ≥ 1 — the
    exact count below f against N ≈ f Σ (A/2) √(ρt/D) (the leading term; the edge term
    −P k/(4π) of this boundary makes the exact count lower by ≈ that, measured here)."""
    a, b, t, E, nu, rho = 0.6, 0.4, 2e-3, 2e9, 0.35, 1000.0
    x, y = np.meshgrid(np.linspace(0, a, 31), np.linspace(0, b, 21), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    index = np.arange(x.size).reshape(x.shape)
    q = np.stack([index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]], -1).reshape(-1, 4)
    triangles = np.vstack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    D = E * t ** 3 / (12 * (1 - nu ** 2))
    density = weyl_mode_density(points, triangles, rho * t, plate_bending(t, E, nu))
    assert density == pytest.approx(a * b / 2 * np.sqrt(rho * t / D), rel=1e-12)
    m = np.arange(1, 400)
    f = np.pi / 2 * np.sqrt(D / (rho * t)) * ((m[:, None] / a) ** 2 + (m[None, :] / b) ** 2)
    f_top = 20e3
    exact = np.count_nonzero(f <= f_top)
    k = np.sqrt(2 * np.pi * f_top * np.sqrt(rho * t / D))
    edge = 2 * (a + b) * k / (4 * np.pi)
    assert density * f_top - edge == pytest.approx(exact, rel=0.03)
    assert exact < density * f_top < 1.5 * exact


def _written(folder: Path) -> dict:
    sizes = {}
    for f in folder.rglob("*"):
        if f.is_file() and not f.name.startswith(".sarfe"):
            rel = f.relative_to(folder)
            kind = ("animation" if rel.parts[0] == "animation" else "ERP maps (VTU)"
                    if rel.parts[0] == "erp" or f.name == "erp.vtu" else "plots (PNG)"
                    if f.suffix == ".png" else "sound.wav" if f.suffix == ".wav" else f.name)
            sizes[kind] = sizes.get(kind, 0) + f.stat().st_size
    return sizes


def test_disk_estimate_matches_a_written_fe_run(tmp_path):
    """The coarse rattle rig at 2 listed frequencies, every default file (maps, animation,
    report, sound): the bytes the run writes against the estimate it said — in total and for
    the files written from their layout (VTU maps, animation frames) within ±30 %."""
    path = tmp_path / "rig.yaml"
    path.write_text(coarse_rig([30.0, 33.0], "{harmonics: 5, samples_per_period: 64, "
                               "error_estimate: false, stability: false, resolution: fixed}"))
    result = solve_case(path, output_dir=tmp_path / "out")
    estimate = result.summary["cost_estimate"]
    sizes = _written(tmp_path / "out")
    low, high = estimate["bytes"]
    assert low == high                       # listed frequencies: one number
    assert low == pytest.approx(sum(sizes.values()), rel=DISK_TOLERANCE)
    for kind in ("ERP maps (VTU)", "animation", "sound.wav"):
        assert estimate["files"][kind][0] == pytest.approx(sizes[kind], rel=DISK_TOLERANCE), kind
    assert estimate["points"] == [2, 2]
    assert estimate["harmonics"] == [5, 5]


def test_disk_estimate_matches_a_written_matrices_run(tmp_path):
    """The 2-DOF case with every default file of a matrices model: total within ±30 %."""
    path = tmp_path / "tiny.yaml"
    path.write_text(TINY.replace("output: {files: [summary, table]}\n", "")
                    .replace("frequency_hz: [20.0]", "frequency_hz: [15.0, 20.0, 25.0]"))
    result = solve_case(path, output_dir=tmp_path / "out")
    estimate = result.summary["cost_estimate"]
    written = sum(_written(tmp_path / "out").values())
    assert estimate["bytes"][0] == pytest.approx(written, rel=DISK_TOLERANCE)
    assert estimate["modes"] is None and estimate["cutoff_hz"] is None


def _with(case, **solver):
    config = case.config
    return dataclasses.replace(case, config=dataclasses.replace(
        config, solver=dataclasses.replace(config.solver, **solver)))


def test_more_points_or_harmonics_cost_more():
    """Monotone: 30 listed frequencies cost more CPU and disk than 3; H = 20 more than H = 5."""
    case = load_case(CASES / "squeak_rig.yaml")
    size = check_case(case, write=False).size
    few = run_cost(case, size)
    config = case.config
    many = run_cost(dataclasses.replace(case, config=dataclasses.replace(
        config, excitation=dataclasses.replace(
            config.excitation, frequency_hz=tuple(np.linspace(50, 150, 30))))), size)
    assert many.points == (30, 30) and few.points == (3, 3)
    assert many.cpu_s[0] > few.cpu_s[0] and many.bytes[0] > few.bytes[0]
    low, high = (run_cost(_with(case, harmonics=h, samples_per_period=256), size)
                 for h in (5, 20))
    assert high.cpu_s[0] > low.cpu_s[0] and high.bytes[0] > low.bytes[0]
    bigger = dataclasses.replace(size, dofs=10 * size.dofs)
    assert run_cost(case, bigger).cpu_s[0] > few.cpu_s[0]


def test_sweep_states_a_range():
    """A continuation's point count is not known before it runs: a range, and so are CPU s and
    bytes; resolution auto states the H range the cost is given for."""
    case = load_case(CASES / "lumped_rattle.yaml")
    cost = run_cost(case, ModelSize(dofs=3, radiating_nodes=1, contacts=2, contact_rows=2))
    assert cost.points[0] < 234 < cost.points[1]        # the run's 234 points (estimate.md)
    assert cost.bytes[0] < cost.bytes[1] and cost.cpu_s[0] < cost.cpu_s[1]
    auto = run_cost(_with(case, resolution="auto"), ModelSize(dofs=3, contacts=2,
                                                              contact_rows=2))
    assert auto.auto and auto.harmonics[0] < auto.harmonics[1]
    assert "(auto)" in cost_lines(auto)[0]


def test_validate_and_solve_print_the_cost(tmp_path, capsys):
    """validate prints the cost line(s) (≤ 80 columns); solve prints them once on stderr before
    the work, and not with --quiet."""
    assert cli.main(["validate", str(CASES / "squeak_rig.yaml"), "-o", str(tmp_path / "v")]) == 0
    out = capsys.readouterr().out.splitlines()
    cost = [line for line in out if line.startswith("cost: ")]
    assert len(cost) == 1 and "H 32, N 256, cutoff 1125 Hz" in cost[0]
    at = out.index(cost[0])
    assert all(len(line) <= 80 for line in out[at:])
    assert "s CPU" in "".join(out[at:]) and "MB written" in "".join(out[at:])
    path = tmp_path / ("a_case_folder_whose_name_is_long_" * 2) / "tiny.yaml"  # > 80 columns
    path.parent.mkdir()
    path.write_text(TINY)
    assert cli.main(["solve", str(path), "-o", str(tmp_path / "s")]) == 0
    out, err = capsys.readouterr()
    lines = out.splitlines()       # 80 columns; a path longer than that gets a line of its own
    assert all(len(line) <= 80 for line in lines if str(tmp_path) not in line)
    assert lines[0].endswith("solving tiny") and lines[1].strip() == f"({path})"
    assert err.count("sarfe: cost: H 3, N ") == 1
    assert cli.main(["solve", str(path), "-o", str(tmp_path / "q"), "--quiet"]) == 0
    assert "cost:" not in capsys.readouterr().err


def test_deck_and_generator_state_the_same_model_size():
    """The rattle rig read from its Nastran deck (mm-t-s, PSHELL/MAT1 → ρ t and D per triangle)
    and generated from its YAML (SI) are one model: the same free DOFs, radiating nodes and
    Weyl modal density."""
    cases = [load_case(CASES / f"{name}.yaml") for name in ("rattle_rig", "rattle_rig_deck")]
    generated, deck = (check_case(case, write=False).size for case in cases)
    assert deck.dofs == generated.dofs and deck.contact_rows == generated.contact_rows == 1
    assert deck.radiating_nodes == generated.radiating_nodes
    assert deck.mode_density_per_hz == pytest.approx(generated.mode_density_per_hz, rel=1e-6)
    # only the generated mesh has coarser meshes for the mesh term (its cost is estimated)
    assert mesh_error_reason(cases[0]) is None and mesh_error_reason(cases[1]) is not None


def test_cost_line_wraps_within_its_width():
    """A 1 M DOF auto sweep: every line within the width (solve gives 73: after 'sarfe: '),
    each item whole, the run's items on a line of their own."""
    cost = RunCost((8, 24), (128, 512), 1500.0, 437, (100, 360), (34, 177), (14e6, 37e6),
                   auto=True, dofs=1140102)
    for width in (40, 73, 80):
        lines = cost_lines(cost, width)
        assert all(len(line) <= width for line in lines)
        assert lines[0].startswith("cost: H 8–24 (auto), N 128–512")
        assert any(line.startswith("  100–360 points") for line in lines)
        assert "1140102 DOFs" in "".join(lines) and "≈ 14–37 MB written" in lines[-1]


def test_mode_estimate_keeps_the_reductions_minimum(tmp_path):
    """The rattle rig's 400 Hz cutoff holds ≈ 4 Weyl modes; the reduction keeps
    reduction.min_mode_count = 10 (its solve's summary: 10 modes, benchmarks/results/estimate.md),
    and the estimate says the same rule's count."""
    case = load_case(CASES / "rattle_rig.yaml")
    size = check_case(case, write=False).size
    cost = run_cost(case, size)
    assert size.mode_density_per_hz * cost.cutoff_hz < case.config.reduction.min_mode_count
    assert cost.modes == case.config.reduction.min_mode_count == 10


def _stiff(case, k_n):
    config = case.config
    contacts = tuple(dataclasses.replace(c, params=dict(c.params, normal_stiffness_N_m=k_n))
                     if c.params.get("normal_stiffness_N_m") else c for c in config.contacts)
    return dataclasses.replace(case, config=dataclasses.replace(config, contacts=contacts))


def test_contact_mass_is_the_normal_rows_mass():
    """lumped_rattle's rattle row w = u0 − u1 between 0.2 and 0.5 kg: m_c = 1 / (g M⁻¹ gᵀ) is the
    two masses in series (0.2 · 0.5 / 0.7 kg), so ω_c = √(k_n / m_c) and ρ₁ = (ω_c / 2π f)² at
    the band's lowest f (30 Hz); the seal (no normal row) has none. An FE rattle side moves
    33/140 of its part (rattle rig: the steel strip ρ t L w in series with the ABS plate)."""
    case = load_case(CASES / "lumped_rattle.yaml")
    size = check_case(case, write=False).size
    m_c = 0.2 * 0.5 / 0.7
    assert size.contact_mass_kg[0] == pytest.approx(m_c, rel=1e-12)
    assert np.isnan(size.contact_mass_kg[1])
    assert contact_frequency(case.config, size) == pytest.approx(np.sqrt(1e6 / m_c), rel=1e-12)
    assert stiffness_ratio(case.config, size) == pytest.approx(
        1e6 / m_c / (2 * np.pi * 30.0) ** 2, rel=1e-12)
    rig = load_case(CASES / "rattle_rig.yaml")
    strip = 7850 * 1.5e-3 * 0.2 * 0.02              # the strip's own mass, 47 g
    plate = 1050 * 2.5e-3 * 0.15 * 0.15             # the plate's, 59 g
    share = 33 / 140
    expected = 1 / (1 / (share * strip) + 1 / (share * plate))
    assert check_case(rig, write=False).size.contact_mass_kg[0] == pytest.approx(expected, rel=0.1)


def test_stiff_contacts_raise_the_sweeps_cost():
    """The sweep's range against k_n (lumped_rattle, 1e6 … 1e12 N/m): the shipped stiffness keeps
    the 16 N turns and the base rule's points; harder contacts raise N to 64 N (ρ₁ > HARD_RATIO)
    or 8 · 2√ρ₁ samples a period (a power of 2) up to most_samples, the points as
    (ρ₁ / HARD_RATIO)^0.15, and the CPU range's ends never fall; the time-integration check of an unresolved impact enters the high end when
    ρ(H') > 4 at the band's lowest frequency and the low end when at its highest too."""
    case = load_case(CASES / "lumped_rattle.yaml")
    size = check_case(case, write=False).size
    N = case.config.solver.samples_per_period
    shipped = run_cost(case, size)
    soft = run_cost(case, dataclasses.replace(size, contact_mass_kg=()))    # m_c unknown
    assert shipped.samples == (N, MAX_SAMPLES_FACTOR * N) == soft.samples
    assert shipped.points == soft.points and shipped.cpu_s == soft.cpu_s
    previous = shipped
    for k_n in (1e7, 1e8, 1e9, 1e10, 1e11, 1e12):
        stiff = _stiff(case, k_n)
        cost = run_cost(stiff, size)
        rho = stiffness_ratio(stiff.config, size)
        need = 2 ** int(np.ceil(np.log2(SAMPLES_PER_IMPACT * 2 * np.sqrt(rho))))
        turns = (MAX_STALL_FACTOR if rho > HARD_RATIO else MAX_SAMPLES_FACTOR) * N
        assert cost.samples[1] == min(most_samples(N, 2), max(turns, need))
        hard = max(1.0, rho / HARD_RATIO) ** POINTS_EXPONENT
        assert cost.points[1] == pytest.approx(min(400 * hard, 2000), abs=1)
        assert cost.cpu_s[0] >= previous.cpu_s[0] and cost.cpu_s[1] > previous.cpu_s[1]
        assert cost.samples[1] >= previous.samples[1] and cost.points[1] >= previous.points[1]
        H_ext = extended_harmonics(case.config.solver.harmonics)
        low, high = impact_check_seconds(stiff.config, size, case.config.solver.harmonics)
        assert (high > 0) == (stiffness_ratio(stiff.config, size, H_ext, 0) > 4)
        assert (low > 0) == (stiffness_ratio(stiff.config, size, H_ext, 1) > 4)
        previous = cost
    assert previous.samples[1] == most_samples(N, 2)          # the cap: N × rows ≤ 2^17


def test_listed_frequencies_keep_their_cost_and_validate_says_the_raised_N(tmp_path, capsys):
    """A listed case does not raise N: its range is the base rule's at any k_n below the impact
    check (squeak rig); validate prints a stiff sweep's raised N and points."""
    case = load_case(CASES / "squeak_rig.yaml")
    size = check_case(case, write=False).size
    assert run_cost(case, size).cpu_s == run_cost(case, dataclasses.replace(
        size, contact_mass_kg=())).cpu_s
    path = tmp_path / "stiff.yaml"
    path.write_text((CASES / "lumped_rattle.yaml").read_text().replace(
        "normal_stiffness_N_m: 1.0e6", "normal_stiffness_N_m: 1.0e11"))
    stiff = load_case(path)
    cost = run_cost(stiff, check_case(stiff, write=False).size)
    assert cost.samples[1] == most_samples(cost.samples[0], 2) > MAX_STALL_FACTOR * cost.samples[0]
    assert cli.main(["validate", str(path), "-o", str(tmp_path / "v")]) == 0
    text = " ".join(line.strip() for line in capsys.readouterr().out.splitlines())
    assert f"N {cost.samples[0]}–{cost.samples[1]}" in text
    assert f"{cost.points[0]}–{cost.points[1]} points" in text
