"""The mesh term's coarser models built in the background (issue 30: door_trim_p1's mesh term
41 s → the Newton solves only): with two workers the coarser linear stages are built on a
process forked before the fine linear stage (sarfe.pipeline.solve.mesh_error.start_coarse_levels)
and give the same term as the serial path (one worker: built after the sweep in this process),
within 1e-12; a background worker that died leaves the term to the after-sweep path, same
numbers. The rattle rig at 20 mm, one point (each solve ≈ 2 s)."""
import math
from pathlib import Path

import pytest

from sarfe.pipeline import load_case, solve_case
from sarfe.pipeline import run as pipeline_run
from sarfe.pipeline.solve import mesh_error
CASES = Path(__file__).resolve().parents[3] / "cases"
FIELDS = ("mesh_db", "level_db", "level_dba", "coarse_level_db", "coarse_level_dba", "order")


def one_point(name, frequency_hz, mesh_size_m=None, **solver):
    case = load_case(CASES / f"{name}.yaml")
    if mesh_size_m is not None:
        case = case.with_generator(mesh_size_m=mesh_size_m)
    data = case.data
    data["excitation"].pop("sweep", None)
    data["excitation"]["frequency_hz"] = [frequency_hz]
    data["solver"].update(solver)
    return data


def _term(workers, monkeypatch=None, kill=False):
    data = one_point("rattle_rig", 31.0, 0.02, stability=False, workers=workers)
    data["model"]["fe"]["generator"].pop("path", None)
    started = []
    if monkeypatch is not None:
        def start(case):
            background = mesh_error.start_coarse_levels(case)
            started.append(background)
            if kill and background is not None:
                background._process.kill()
                background._process.join()
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
