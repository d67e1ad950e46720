"""The loudest point is the converged, not unstable point of highest dB(A) (issue 13, item 4), and
every artefact "at the loudest point" uses that same point; motionless levels read "-"."""
import dataclasses
import json
import re

import numpy as np

import sarfe.pipeline.run as solve_module
from sarfe import results as outputs
from sarfe.results.summary import level_text, loudest_lines
from sarfe.pipeline import solve_case
from sarfe.pipeline.write.result_files import results_table
from sarfe.pipeline.post.records import loudest_point


def _point(index, dba, converged=True, stable=True):
    return {"index": index, "converged": converged, "stable": stable,
            "erp": {"level_dba": dba, "level_db": dba + 10}}


def test_loudest_point_skips_unconverged_and_unstable_points():
    points = [_point(0, 80.0), _point(1, 95.0, converged=False), _point(2, 90.0, stable=False),
              _point(3, 85.0, stable=None), _point(4, -np.inf)]
    assert loudest_point(points) == 3            # not 1 (not converged), not 2 (unstable)
    assert loudest_point([_point(0, 70.0, converged=False)]) is None


def test_every_artefact_uses_the_loudest_converged_stable_point(lumped_case, tmp_path,
                                                                monkeypatch):
    """Solve, then mark the loudest-by-dB(A) point as not converged and the next one unstable:
    the headline, summary, table, spectrum, contact plots, third-octave, contributions and report
    all name the third-loudest point."""
    real = solve_module.solve_points_pruned
    chosen = {}

    def tampered(solver, excitation, nl, progress=False, measure=None):
        solutions, report = real(solver, excitation, nl, progress=progress, measure=measure)
        from sarfe.pipeline.post.records import point_erp as _erp

        dba = [_erp(_case[0].config.erp, _stage[0], s.displacement, s.omega)[0]
               .level_total_a_db for s in solutions]
        order = np.argsort(dba)[::-1]
        solutions[order[0]] = dataclasses.replace(solutions[order[0]], converged=False,
                                                  reason="tampered by the test")
        solutions[order[1]] = dataclasses.replace(solutions[order[1]], stable=False,
                                                  stability_job=None)   # (not deferred: final)
        chosen["index"] = int(order[2])
        chosen["frequency_hz"] = float(solutions[order[2]].omega) / (2 * np.pi)
        return solutions, report

    _stage, _case = [], []
    real_build = solve_module.build_linear_model

    def build(case, progress=False):
        stage = real_build(case, progress=progress)
        _stage.append(stage)
        _case.append(case)
        return stage

    monkeypatch.setattr(solve_module, "build_linear_model", build)
    monkeypatch.setattr(solve_module, "solve_points_pruned", tampered)
    titles = {}
    for name in ("plot_erp_spectrum", "plot_contact_forces", "plot_third_octave",
                 "plot_friction", "plot_contributions"):
        original = getattr(outputs, name)

        def spy(*args, _original=original, _name=name, **kwargs):
            titles[_name] = kwargs.get("title")
            return _original(*args, **kwargs)
        monkeypatch.setattr(outputs, name, spy)
    result = solve_case(lumped_case, output_dir=tmp_path / "out")
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    worst = summary["worst"]
    assert worst["index"] == chosen["index"]
    at = f"{chosen['frequency_hz']:.1f} Hz"
    assert set(titles) == {"plot_erp_spectrum", "plot_contact_forces", "plot_third_octave",
                           "plot_friction", "plot_contributions"}
    for name, title in titles.items():
        assert at in title, (name, title)
    headline = loudest_lines(result.summary["worst"])
    assert f"at {chosen['frequency_hz']:.2f} Hz" in headline[0]
    assert headline[1].strip().startswith("panel_bracket: ")          # the ranking follows
    html = (tmp_path / "out" / "report.html").read_text()
    assert re.search(rf"at {chosen['frequency_hz']:.2f} Hz", html)
    assert f"(index {chosen['index']})" in html
    assert summary["points"][worst["index"]]["contributions"]["ranking"][0] == worst["ranking"][0]


def test_motionless_levels_read_as_dash():
    assert level_text(-187.3) == "-" and level_text(float("-inf")) == "-"
    assert level_text(None) == "-" and level_text(93.14, unit="dB(A)") == "93.1 dB(A)"
    rows = [{"frequency_hz": 30.0, "converged": True, "stable": True, "iterations": 1,
             "erp_db": -187.0, "erp_dba": -np.inf, "linear_erp_db": 60.0}]
    line = results_table(rows).splitlines()[-1]
    assert "-187" not in line and "-inf" not in line and "60.0" in line
    assert line.split()[4:6] == ["-", "-"]
    assert loudest_lines({"index": 0, "erp_level_dba": -190.0, "erp_level_db": -170.0,
                          "frequency_hz": 30.0})[0] == "loudest point: - (-) at 30.00 Hz"
