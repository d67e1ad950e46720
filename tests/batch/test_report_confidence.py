"""Confidence statements of the batch report: Wilson score interval, DKW band, and the report page."""
import numpy as np
import pandas as pd
import pytest

from sarfe.batch.batch_report import (dkw_epsilon, evaluate_gate, quantile_band, rattle_probability, wilson_interval,
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


def test_unrelated_cases_get_a_per_case_table_not_statistics(tmp_path):
    """Two unrelated case files (issue 31: door trim + squeak rig gave a mean of 67.9 dB(A) with a
    95 % CI of −300.8 … 436.7 dB(A)): a per-case table, no distribution, no P(rattle)."""
    rows = []
    for v, (source, level, contact) in enumerate((("cases/door_trim.yaml", 97.0, "lower_1"),
                                                  ("cases/squeak_rig.yaml", 38.9, "rub"))):
        for f, drop in ((40.0, 5.0), (60.0, 0.0)):
            rows.append({"variant_index": v, "variant_id": f"v{v}", "source": source,
                         "status": "ok", "error": None, "frequency_hz": f,
                         "erp_db": level + 3 - drop, "erp_dba": level - drop,
                         f"{contact}.max_penetration_m": 1e-5})
    summary = write_report(pd.DataFrame(rows), tmp_path)
    assert summary["sample"] == "per case"
    assert "max_erp_dba" not in summary and "rattle_probability" not in summary
    assert [(c["source"], c["max_erp_dba"], c["frequency_at_max_hz"]) for c in summary["cases"]] \
        == [("cases/door_trim.yaml", 97.0, 60.0), ("cases/squeak_rig.yaml", 38.9, 60.0)]
    html = (tmp_path / "report.html").read_text()
    assert 'id="cases-table"' in html and 'id="distribution-table"' not in html
    assert not (tmp_path / "erp_histogram.png").exists()


def test_variants_of_one_case_keep_statistics_and_few_are_dots(tmp_path):
    """Two μ values of one study: still one sample (statistics kept), drawn as dots, not bars."""
    rows = [{"variant_index": v, "variant_id": f"v{v}", "source": "mu_study", "status": "ok",
             "error": None, "contacts[name=rub].friction_coefficient": mu, "frequency_hz": 100.0,
             "erp_db": 40.0 + v, "erp_dba": 30.0 + v} for v, mu in enumerate((0.15, 0.3))]
    table = pd.DataFrame(rows)
    table.attrs["parameters"] = ["contacts[name=rub].friction_coefficient"]
    summary = write_report(table, tmp_path)
    assert summary["sample"] == "one case"
    assert summary["max_erp_dba"]["count"] == 2 and summary["max_erp_dba"]["mean"] == pytest.approx(30.5)
    assert "erp_histogram.png" in summary["plots"]


def test_preloaded_squeak_contact_slips_but_does_not_rattle(tmp_path):
    """A preloaded squeak contact always penetrates (preload) but never opens: P(rattle) counts
    opening-and-impact (impacts_per_period > 0), P(slip) counts sliding (slip_fraction > 0)."""
    rows = []
    for v, slip in enumerate((0.0, 0.0, 0.4, 0.6)):
        rows.append({"variant_index": v, "variant_id": f"v{v}", "source": "mu_study", "status": "ok",
                     "error": None, "frequency_hz": 100.0, "erp_db": 40.0, "erp_dba": 30.0,
                     "rub.max_penetration_m": 2e-5, "rub.impacts_per_period": 0,
                     "rub.slip_fraction": slip, "rub.open_fraction": 0.0,
                     "clip.max_penetration_m": 1e-6 * v, "clip.impacts_per_period": int(v >= 2),
                     "clip.slip_fraction": 0.0})
    summary = write_report(pd.DataFrame(rows), tmp_path)
    assert summary["rattle_probability"] == {"rub": 0.0, "clip": 0.5}
    assert summary["slip_probability"] == {"rub": 0.5, "clip": 0.0}


def test_gate_speaks_dba():
    """--fail-above-dba: the gate compares each variant's loudest A-weighted level."""
    rows = [{"variant_index": i, "variant_id": f"v{i}", "source": "s", "status": "ok", "error": None,
             "frequency_hz": 67.0, "erp_db": dba + 20.0, "erp_dba": dba} for i, dba in enumerate((88.0, 93.0))]
    table = pd.DataFrame(rows)
    gate = evaluate_gate(table, 90.0, weighted=True)
    assert not gate.passed and len(gate.offenders) == 1 and "93.00 dB(A) > 90 dB(A)" in gate.message
    assert evaluate_gate(table, 95.0, weighted=True).passed
    assert not evaluate_gate(table, 95.0).passed        # unweighted: 108, 113 dB > 95 dB
