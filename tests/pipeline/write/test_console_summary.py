"""The end-of-run console summary (issue 30): a 966-point sweep prints a few rows that fit 80
columns — the band's ends and the loudest points, the loudest level among them — and names
table.txt, which keeps every point; a short run shows all its points."""
import numpy as np

from sarfe.pipeline.write.result_files import results_table
from sarfe.results.console import points_table, summary_lines


def _rows(n):
    f = np.linspace(20.0, 200.0, n)
    level = (90.0 + 18.0 * np.exp(-((f - 65.3) / 3.0) ** 2)      # loudest 108 dB(A) at 65.3 Hz
             + 6.0 * np.exp(-((f - 150.0) / 2.0) ** 2))           # a second peak, 96 dB(A)
    return [{"frequency_hz": float(fi), "converged": True, "stable": True, "iterations": 3,
             "erp_db": float(li + 2), "erp_dba": float(li), "linear_erp_db": float(li - 1),
             "linear_erp_dba": float(li - 1), "erp_error_db": 0.03,
             "front_1_rattle_spot.max_penetration_m": 1e-5,
             "end_left_squeak_spot.max_penetration_m": 0.0,
             "end_left_squeak_spot.slip_fraction": 0.25} for fi, li in zip(f, level)]


def test_a_long_sweep_fits_80_columns_and_points_to_table_txt():
    rows = _rows(966)
    lines = summary_lines({"worst": {}}, rows)           # what `sarfe solve` prints
    table = points_table(rows).splitlines()
    assert all(line in lines for line in table)
    assert max(len(line) for line in lines) <= 80
    assert len(table) <= 2 + 12 + 1 and "966 points" in table[-1] and "table.txt" in table[-1]
    text = "\n".join(table)
    loudest = max(rows, key=lambda r: r["erp_dba"])
    assert f"{loudest['frequency_hz']:.2f}" in text and f"{loudest['erp_dba']:.1f}" in text
    assert "20.00" in text and "200.00" in text                  # the band's ends
    assert "96.0" in text                                         # the second peak
    assert len(results_table(rows, max_contacts=100).splitlines()) == 2 + 966   # table.txt's


def test_a_short_run_shows_every_point():
    rows = _rows(5)
    lines = points_table(rows).splitlines()
    assert max(len(line) for line in lines) <= 80
    assert len([line for line in lines if line.strip()[:1].isdigit()]) == 5
