"""Confidence statements of the batch report: Wilson score interval, DKW band, and the report page."""
import numpy as np
import pandas as pd
import pytest

from sarfe.batch.batch_report import (dkw_epsilon, quantile_band, rattle_probability, wilson_interval,
                                write_report)


def test_wilson_interval_closed_form_and_coverage():
    # textbook value: 0 successes in 10 trials → (0, 0.2775) at 95 %
    low, high = wilson_interval(0, 10)
    assert low == pytest.approx(0.0, abs=1e-12) and high == pytest.approx(0.2775, abs=1e-4)
    # 5 of 10: symmetric about 1/2, (0.2366, 0.7634)
    low, high = wilson_interval(5, 10)
    assert low == pytest.approx(0.2366, abs=1e-4) and high == pytest.approx(0.7634, abs=1e-4)
    # coverage by simulation: p = 0.3, m = 40 → close to 95 %
    rng = np.random.default_rng(1)
    k = rng.binomial(40, 0.3, 20000)
    lo, hi = wilson_interval(k, 40)
    coverage = np.mean((lo <= 0.3) & (0.3 <= hi))
    assert 0.93 < coverage < 0.97


def test_dkw_band_covers_the_true_distribution():
    assert dkw_epsilon(100) == pytest.approx(np.sqrt(np.log(40) / 200))
    rng = np.random.default_rng(2)
    hits = 0
    for _ in range(400):
        x = np.sort(rng.normal(size=50))
        ecdf = np.arange(1, 51) / 50
        from scipy.stats import norm

        hits += np.all(np.abs(ecdf - norm.cdf(x)) <= dkw_epsilon(50) + 1 / 50)
    assert hits / 400 >= 0.95                  # DKW is conservative
    low, high = quantile_band(np.arange(100.0), 0.5)
    assert low < 49.5 < high


def test_batch_report_page(tmp_path):
    rng = np.random.default_rng(3)
    rows = []
    for v in range(30):
        gap = rng.uniform(0.05e-3, 0.3e-3)
        for f in (40.0, 60.0):
            rows.append({"variant_index": v, "variant_id": f"v{v}", "source": "mc", "status": "ok",
                         "error": None, "contacts[name=clip].gap_m": gap, "frequency_hz": f,
                         "erp_db": 90 - 1e4 * gap + rng.normal(), "erp_dba": 70 - 1e4 * gap,
                         "clip.max_penetration_m": max(0.0, 0.15e-3 - gap)})
    table = pd.DataFrame(rows)
    table.attrs["parameters"] = ["contacts[name=clip].gap_m"]
    summary = write_report(table, tmp_path)
    html = (tmp_path / "report.html").read_text()
    assert summary["report"] == "report.html" and "rattle_probability.png" in summary["plots"]
    for marker in ('id="distribution-table"', 'id="rattle-table"', 'id="img-distribution"',
                   'id="img-rattle-probability"', 'id="loudest-table"', "data:image/png;base64,"):
        assert marker in html
    low, high = summary["rattle_probability_ci95"]["clip"]
    assert low < summary["rattle_probability"]["clip"] < high
    # rattling falls with the gap: the smallest-gap bin rattles, the largest does not
    p = rattle_probability(pd.read_csv(tmp_path / "variants.csv"), "contacts[name=clip].gap_m")
    assert p["clip"].iloc[0] == 1.0 and p["clip"].iloc[-1] == 0.0
