"""What a run says of points without an error bound (issue 29): an impact the harmonics do not
resolve is named with its duration against what H' resolves, in the accuracy warning and in the
headline's note; a re-solve that did not converge keeps its own wording (the shipped cases)."""
from __future__ import annotations

from sarfe.pipeline.solve.case_accuracy import unknown_text
from sarfe.pipeline.solve.impact_check import impact_check_point
from sarfe.results.summary import headline_notes

RESOLUTION = {"harmonics": 14, "ratio": 1780.0, "contact": "panel_bracket",
              "contact_frequency_hz": 42000.0, "impact_duration_s": 1.18e-5,
              "resolved_duration_s": 5.0e-4, "resolved": False, "needed_harmonics": 296}


def point(frequency_hz, resolution=None):
    estimate = {"amplitude_rel": float("inf"), "erp_db": float("inf"), "notes": []}
    if resolution is not None:
        estimate["contact_resolution"] = resolution
    return {"frequency_hz": frequency_hz, "error_estimate": estimate}


def test_unresolved_impacts_are_named_with_their_duration():
    text = unknown_text([point(71.5, RESOLUTION), point(75.6, RESOLUTION), point(50.0)])
    assert text.startswith("no error bound at 2 points (71.50–75.60 Hz): the impact of "
                           "panel_bracket lasts ≈ 11.8 µs")
    assert "500 µs H' = 14 resolves" in text and "needs H' ≥ 296" in text
    assert text.endswith("no error estimate at 50.00 Hz (its re-solve at more harmonics or "
                         "samples did not converge)")


def test_failed_re_solves_keep_their_wording():
    text = unknown_text([point(f) for f in (71.9, 72.45, 72.55, 72.6, 72.7)])
    assert text == ("no error estimate at 71.90, 72.45, 72.55 and 2 more Hz (its re-solve at "
                    "more harmonics or samples did not converge)")


def test_headline_says_why_it_has_no_bound():
    worst = {"erp_error_db": None, "error_estimated": True,
             "error_note": "no error bound: impact not resolved by H"}
    assert headline_notes(worst) == ["no error bound: impact not resolved by H"]
    assert headline_notes({"erp_error_db": None, "error_estimated": True}) == ["error unknown"]


def test_only_a_loudest_point_without_a_bound_for_its_impact_is_time_checked():
    """The time-integration check (sarfe.pipeline.solve.impact_check) runs at the loudest point
    only, and only when its estimate has no bound because of an unresolved impact — never on a
    point with a bound or whose re-solve alone failed (the shipped cases)."""
    def record(index, level, resolution=None, bound=float("inf")):
        p = point(60.0 + index, resolution)
        p["error_estimate"]["amplitude_rel"] = bound
        return dict(p, index=index, converged=True, stable=None, erp={"level_dba": level})

    flagged = [record(0, 80.0), record(1, 95.0, RESOLUTION), record(2, 90.0, RESOLUTION)]
    assert impact_check_point(flagged) == 1
    assert impact_check_point([record(0, 80.0), record(1, 95.0)]) is None           # re-solve
    assert impact_check_point([record(0, 99.0, bound=0.01), record(1, 95.0, RESOLUTION)]) is None
