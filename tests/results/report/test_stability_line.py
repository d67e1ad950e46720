"""The console line for points without a stability verdict ('-' in the stable column)."""
from sarfe.results.summary import stability_line


def _point(f, converged=True, stable=True, note=""):
    return {"frequency_hz": f, "converged": converged, "stable": stable, "stability_note": note}


def test_unresolved_points_are_counted_and_the_first_note_is_named():
    note = "not resolved in H: 0 Floquet exponent(s) right of −1e-4·ω at H = 10, 1 at H = 7"
    points = [_point(30.0), _point(31.0, stable=None, note=note), _point(32.0, stable=False),
              _point(33.0, stable=None, note="the contact-row count finds 2 …"),
              _point(34.0, converged=False, stable=None, note="not converged")]
    line = stability_line(points)
    assert line.startswith("stability: not resolved at 2 of 4 converged points")
    assert "31.00 Hz: " + note in line and "sarfe verify" in line


def test_no_line_when_every_converged_point_has_a_verdict_or_stability_is_off():
    assert stability_line([_point(30.0), _point(31.0, stable=False),
                           _point(32.0, converged=False, stable=None, note="x")]) is None
    assert stability_line([_point(30.0, stable=None)]) is None     # stability: false (no note)
    assert stability_line([]) is None
