"""The headline says how sure it is: the loudest point's level with its error bound
("97.0 ± 0.24 dB(A)"), and notes when its stability was not assessed or its bound is interpolated
between estimated sweep points (the table marks those with "~"), in the console and report.html."""
import math

from sarfe.results.summary import loudest_lines
from sarfe.results.report import render_report_html
from sarfe.pipeline.write.result_files import results_table
from sarfe.pipeline.post.records import loudest_point, worst_of


def point(index, f, dba, stable=True, estimate=None):
    return {"index": index, "frequency_hz": f, "converged": True, "stable": stable,
            "erp": {"level_dba": dba, "level_db": dba + 20.0, "power_W": 1.0},
            "error_estimate": estimate, "contacts": [],
            "linear": {"contacts": [], "erp_level_db": 60.0, "erp_level_dba": 40.0}}


def test_headline_carries_the_bound_of_the_loudest_point():
    points = [point(0, 40.0, 89.1, estimate={"erp_db": 0.38, "amplitude_rel": 0.004}),
              point(1, 67.0, 97.04, estimate={"erp_db": -0.24, "amplitude_rel": 0.005})]
    worst = worst_of(points)
    assert worst["index"] == 1 and math.isclose(worst["erp_error_db"], 0.24)
    assert loudest_lines(worst)[0] == "loudest point: 97.0 ± 0.24 dB(A) (117.0 dB re 1 pW) at 67.00 Hz"


def test_unassessed_stability_and_interpolated_bound_are_said():
    interpolated = {"erp_db": 3.06, "amplitude_rel": 0.02, "interpolated": True, "from_points": [0, 2]}
    points = [point(0, 30.0, 60.0, estimate={"erp_db": 1.0, "amplitude_rel": 0.01}),
              point(1, 31.0, 80.0, stable=None, estimate=interpolated),
              point(2, 32.0, 99.0, stable=False, estimate={"erp_db": 3.06, "amplitude_rel": 0.02})]
    assert loudest_point(points) == 1          # an unstable point is never the headline
    line = loudest_lines(worst_of(points))[0]
    assert line.startswith("loudest point: 80.0 ± 3.06 dB(A)")
    assert line.endswith("at 31.00 Hz (stability not assessed) (error interpolated)")


def test_missing_or_failed_estimate_is_said():
    no_estimate = worst_of([point(0, 50.0, 70.0)])
    assert loudest_lines(no_estimate)[0].endswith("70.0 dB(A) (90.0 dB re 1 pW) at 50.00 Hz "
                                                  "(error not estimated)")
    failed = worst_of([point(0, 50.0, 70.0, estimate={"erp_db": float("nan"), "failed": "x"})])
    assert loudest_lines(failed)[0].endswith("(error unknown)")


def test_table_marks_interpolated_bounds():
    rows = [{"frequency_hz": 30.0, "converged": True, "stable": True, "iterations": 3,
             "erp_db": 80.0, "erp_dba": 60.0, "linear_erp_db": 70.0, "erp_error_db": 0.35,
             "erp_error_interpolated": False},
            {"frequency_hz": 31.0, "converged": True, "stable": True, "iterations": 3,
             "erp_db": 81.0, "erp_dba": 61.0, "linear_erp_db": 70.0, "erp_error_db": 3.06,
             "erp_error_interpolated": True}]
    lines = results_table(rows).splitlines()
    assert "±dB" in lines[0]
    assert " 0.35 " in lines[2] and "~3.06" in lines[3]


def test_report_headline_has_the_bound_and_notes():
    interpolated = {"erp_db": 0.7, "amplitude_rel": 0.01, "interpolated": True, "from_points": [0]}
    points = [point(0, 40.0, 50.0, estimate={"erp_db": 0.2, "amplitude_rel": 0.01}),
              point(1, 67.0, 97.0, stable=None, estimate=interpolated)]
    summary = {"case": "demo", "points": points, "worst": worst_of(points),
               "model": {"kind": "fe", "nodes": 10, "free_dofs": 50, "reduced_dofs": 285,
                         "boundary_dofs": 36, "modes": 212, "residual_vectors": 37}}
    html = render_report_html(summary)
    assert "97.0 ± 0.70 dB(A)" in html
    assert "(stability not assessed)" in html and "(error interpolated)" in html
    assert "36 boundary +\n    212 modes + 37 residual vectors" in html
    assert "<td>0.20</td>" in html and "<td>~0.70</td>" in html      # the all-points table
