"""The mesh term of the ± (sarfe.pipeline.solve.mesh_error, issue 29 item 4): on cases whose level
converges with the mesh (contacts from the geometry, issue 29 items 1-3) — the door trim at 67 Hz
(97.00 / 96.52 / 95.96 / 95.69 / 95.56 dB(A) at 14 / 10 / 7 / 5 / 3.5 mm) and the squeak rig at
50 Hz — the ± with the term (the loudest point re-solved on √2 and 2 times the element size, a grid
convergence index of the three levels) covers the difference to a converged fine mesh (the stored references of tests/cases/data/
mesh_convergence_reference.json, how each was made written in it); the ± shown (console,
table.txt, report, summary.json) includes it; decks and given meshes say "not estimated".
With two workers the coarser models are built in the background from the start of the run
(issue 30) and give the serial path's term within 1e-12, also when that worker died."""
import json
import math
import os
import signal
import time
from pathlib import Path

import pytest

from sarfe.case.errors import CaseError
from sarfe.cli import main
from sarfe.pipeline import load_case, solve_case
from sarfe.pipeline import run as pipeline_run
from sarfe.pipeline.solve import mesh_error
from sarfe.pipeline.solve.mesh_error import mesh_error_reason
from sarfe.results.report import render_report_html

CASES = Path(__file__).resolve().parents[3] / "cases"
REFERENCE = Path(__file__).resolve().parents[2] / "cases" / "data" / "mesh_convergence_reference.json"


def one_point(name, frequency_hz, mesh_size_m=None, **solver):
    case = load_case(CASES / f"{name}.yaml")
    if mesh_size_m is not None:
        case = case.with_generator(mesh_size_m=mesh_size_m)
    data = case.data
    data["excitation"].pop("sweep", None)
    data["excitation"]["frequency_hz"] = [frequency_hz]
    data["solver"].update(solver)
    return data


@pytest.mark.timeout(300)
@pytest.mark.parametrize("name, mesh_size_m", [
    pytest.param("door_trim", 0.014, marks=pytest.mark.slow),      # ≈ 10-20 s
    ("squeak_rig", 0.012), ("squeak_rig", 0.006)])
def test_mesh_term_covers_the_error_against_a_converged_mesh(name, mesh_size_m):
    """The ± (its mesh term: three meshes h, √2h, 2h, GCI) covers the error against the converged
    reference, and the mesh term is not absurd. Measured (2026-11-28, benchmarks/results/
    mesh_cover.md): door trim 14 mm 97.00 dB(A), term 5.46 dB (19.8 / 28 mm: 99.4 / 101.4, not
    in the asymptotic range: 1.25 × their range) against a true error of 1.44; squeak rig 12 mm
    30.83, term 2.54 (p = 5.8 > 2: 1.25 × range) against 1.49; 6 mm 29.88, term 0.49 (monotone,
    p = 1.77), ± 0.72 against 0.54. (The earlier two-mesh estimate read 0.18 at the squeak rig's
    10 mm against 0.79: its ± 0.57 did not cover; now 1.51, ± 1.90.)"""
    reference = json.loads(REFERENCE.read_text())[name]
    result = solve_case(one_point(name, reference["frequency_hz"], mesh_size_m, stability=False),
                        write=False)
    term = result.summary["mesh_error"]
    assert term["estimated"] and term["method"] == "three meshes"
    assert term["coarse_mesh_sizes_m"] == pytest.approx([2 ** 0.5 * mesh_size_m, 2 * mesh_size_m])
    assert term["coarse_mesh_size_m"] == pytest.approx(2 * mesh_size_m)
    level = result.summary["points"][0]["erp"]["level_dba"]
    true_error = abs(level - reference["level_dba"])
    assert true_error > 0.3
    assert term["mesh_db"] <= 5 * true_error                # not absurdly
    estimate = result.summary["points"][0]["error_estimate"]
    assert estimate["mesh_db"] == pytest.approx(term["mesh_db"])
    assert estimate["erp_db"] >= term["mesh_db"]            # the ± includes it
    assert estimate["erp_db"] >= true_error                 # and covers the true error
    assert result.summary["worst"]["erp_error_db"] == pytest.approx(estimate["erp_db"])


@pytest.mark.timeout(300)
def test_the_printed_plus_minus_includes_the_mesh_term(tmp_path, capsys):
    """Console, table.txt, report and summary.json of a coarse rattle rig (20 mm, one point)."""
    path = tmp_path / "rig.yaml"
    data = one_point("rattle_rig", 31.0, 0.02, stability=False)
    data["model"]["fe"]["generator"].pop("path", None)
    data["output"]["files"] = ["summary", "table"]
    import yaml
    path.write_text(yaml.safe_dump(data))
    # the generator mesh is relative to nothing: the case lives in tmp_path, outputs there too
    assert main(["solve", str(path), "--output", str(tmp_path / "out"), "--quiet"]) in (0, 3)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    term = summary["mesh_error"]
    assert term["estimated"] and term["mesh_db"] > 0
    bound = summary["worst"]["erp_error_db"]
    assert bound >= term["mesh_db"]
    assert term["line"] in (tmp_path / "out" / "table.txt").read_text()
    assert f"± {bound:.2f}" in (tmp_path / "out" / "table.txt").read_text() or \
        f"{bound:.2f}" in (tmp_path / "out" / "table.txt").read_text()
    assert 'id="mesh-error"' in render_report_html(summary)
    assert "mesh_db" in render_report_html(summary)
    capsys.readouterr()
    assert main(["solve", str(path), "--output", str(tmp_path / "out"), "--force"]) in (0, 3)
    out = capsys.readouterr().out
    assert f"± {bound:.2f} dB(A)" in out and "mesh error: ±" in out


def test_decks_and_given_meshes_say_not_estimated():
    deck = load_case(CASES / "rattle_rig_deck.yaml")
    assert "not estimated" in mesh_error_reason(deck) and "deck" in mesh_error_reason(deck)
    assert "matrices" in mesh_error_reason(load_case(CASES / "lumped_rattle.yaml"))
    off = load_case(CASES / "squeak_rig.yaml").with_solver(mesh_error=False)
    assert "solver.mesh_error: false" in mesh_error_reason(off)
    assert mesh_error_reason(load_case(CASES / "squeak_rig.yaml")) is None
    data = load_case(CASES / "rattle_rig_deck.yaml").data
    data["solver"]["mesh_error"] = True
    with pytest.raises(CaseError, match="mesh_error"):
        load_case(data, base_dir=CASES)


# ---- the coarser models built in the background (issue 30: door_trim_p1 41 s → the solves)
FIELDS = ("mesh_db", "level_db", "level_dba", "coarse_level_db", "coarse_level_dba", "order")


def _term(workers, monkeypatch=None, kill=False):
    data = one_point("rattle_rig", 31.0, 0.02, stability=False, workers=workers)
    data["model"]["fe"]["generator"].pop("path", None)
    started = []
    if monkeypatch is not None:
        def start(case):
            background = mesh_error.start_coarse_levels(case)
            started.append(background)
            if kill and background is not None:
                os.kill(background.pid, signal.SIGKILL)
                while background.alive():
                    time.sleep(0.01)
            return background
        monkeypatch.setattr(pipeline_run, "start_coarse_levels", start)
    result = solve_case(load_case(data), write=False)
    return result.summary["mesh_error"], result.summary["timings_s"], started


def _same(a, b):
    for key in FIELDS:
        x, y = float(a[key]), float(b[key])
        assert (math.isnan(x) and math.isnan(y)) or abs(x - y) <= 1e-12 * max(1.0, abs(x)), key
    assert a["coarse_levels_dba"] == pytest.approx(b["coarse_levels_dba"], rel=1e-12, abs=0)
    assert (a["method"], a.get("convergence")) == (b["method"], b.get("convergence"))


@pytest.mark.timeout(300)
def test_background_levels_give_the_serial_term(monkeypatch):
    serial, serial_times, _ = _term(1)
    assert serial["estimated"] and "mesh_error_build_s" not in serial_times
    background, times, started = _term(2, monkeypatch)
    assert started and started[0] is not None and not started[0].alive()   # used, then closed
    assert times["mesh_error_build_s"] > 0 and times["mesh_error_solve_s"] > 0
    _same(serial, background)
    died, died_times, started = _term(2, monkeypatch, kill=True)
    assert started[0] is not None and "mesh_error_build_s" not in died_times
    _same(serial, died)


def test_no_background_where_the_term_is_not_due():
    case = load_case(one_point("squeak_rig", 50.0))
    assert mesh_error.start_coarse_levels(case.with_solver(workers=1)) is None
    assert mesh_error.start_coarse_levels(case.with_solver(mesh_error=False, workers=2)) is None
    assert mesh_error.start_coarse_levels(case.with_solver(error_estimate=False, workers=2)) is None
