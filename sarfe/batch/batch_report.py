"""Batch summary: per-variant maxima, statistics (summary.json), plots, report.html and the CI gate.

Reads the merged table of ``sarfe.batch.store.records_table``. Per variant the level is the maximum
over its frequency points of the ERP level [dB] (and A-weighted [dB(A)]).

Confidence statements (95 % unless said otherwise), n variants:
- the empirical distribution F_n of the max level per variant lies within ε = √(ln(2/α)/(2n)) of
  the true one with probability 1 − α everywhere (Dvoretzky–Kiefer–Wolfowitz, Massart's constant);
  the band F_n ± ε is drawn around the ECDF, and the percentiles' bands are read off it;
- the mean's interval is mean ± t_{n−1, 1−α/2} s/√n;
- a rattle probability p̂ = k/m (k of m variants in a bin of a scattered parameter) has the Wilson
  score interval (p̂ + z²/2m ± z √(p̂(1−p̂)/m + z²/4m²)) / (1 + z²/m), z = 1.96.
"""
from __future__ import annotations

import json
import math
import pathlib
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from sarfe.batch import store
from sarfe.results.report import data_uri, environment

GATE_EXIT_CODE = 4
# columns of CaseResult.rows (sarfe.pipeline.run): total ERP level [dB re 1 pW], A-weighted [dB(A)]
ERP_DB, ERP_DBA, FREQUENCY = "erp_db", "erp_dba", "frequency_hz"


def erp_column(table):
    return ERP_DB if ERP_DB in table.columns else None


def erp_a_column(table):
    return ERP_DBA if ERP_DBA in table.columns else None


def frequency_column(table):
    return FREQUENCY if FREQUENCY in table.columns else None


_CASE_SECTIONS = ("name", "description", "model", "damping", "reduction", "contacts", "excitation",
                  "solver", "erp", "output")
# per-contact columns of CaseResult.rows: "<contact>.<quantity>"; maxima over frequency per variant
CONTACT_MAXIMA = ("max_penetration_m", "peak_normal_force_N", "peak_friction_force_N")
RATTLE_COLUMN = "max_penetration_m"  # fallback: a contact rattles when it closes: penetration > 0
IMPACT_COLUMN = "impacts_per_period"  # a contact rattles when it opens and impacts (> 0 per period)
SLIP_COLUMN = "slip_fraction"        # a contact squeaks (slips) when part of the period slides


def parameter_columns(table) -> list[str]:
    """Varied-input columns (``table.attrs['parameters']``, else paths into a case section)."""
    if "parameters" in table.attrs:
        return [c for c in table.attrs["parameters"] if c in table.columns]
    return [c for c in table.columns if c not in store.VARIANT_COLUMNS
            and ("[" in c or c.split(".")[0] in _CASE_SECTIONS and "." in c)]


def contact_columns(table, quantity: str) -> dict[str, str]:
    """{contact name: column} of ``<contact>.<quantity>`` result columns."""
    parameters = set(parameter_columns(table))
    suffix = "." + quantity
    return {c[: -len(suffix)]: c for c in table.columns if c.endswith(suffix) and c not in parameters}


def variant_levels(table: pd.DataFrame) -> pd.DataFrame:
    """One row per variant: status, error, varied inputs, max ERP dB / dB(A) and where."""
    erp, erp_a, freq = erp_column(table), erp_a_column(table), frequency_column(table)
    keep = ["variant_index", "variant_id", "source", "status", "error"] + parameter_columns(table)
    levels = table.groupby("variant_index", sort=True)[keep].first().reset_index(drop=True)
    levels.attrs["parameters"] = parameter_columns(table)
    if erp is not None:
        values = pd.to_numeric(table[erp], errors="coerce")
        levels["max_erp_db"] = values.groupby(table["variant_index"]).max().to_numpy()
        if freq is not None:
            where = values.fillna(-np.inf).groupby(table["variant_index"]).idxmax()
            levels["frequency_at_max_hz"] = table.loc[where.to_numpy(), freq].to_numpy()
    if erp_a is not None:
        values = pd.to_numeric(table[erp_a], errors="coerce")
        levels["max_erp_dba"] = values.groupby(table["variant_index"]).max().to_numpy()
    for quantity in CONTACT_MAXIMA:
        for contact, column in contact_columns(table, quantity).items():
            values = pd.to_numeric(table[column], errors="coerce")
            levels[column] = values.groupby(table["variant_index"]).max().to_numpy()
    impacts = contact_columns(table, IMPACT_COLUMN)
    for contact, column in contact_columns(table, RATTLE_COLUMN).items():
        if contact in impacts:   # rattle = the contact opens and impacts (any law, preloaded too)
            values = pd.to_numeric(table[impacts[contact]], errors="coerce")
        else:                    # records without impact counts: closes at all (penetration > 0)
            values = pd.to_numeric(table[column], errors="coerce")
        if values.notna().any():  # contacts without a normal direction (pure squeak) have NaN
            levels[f"{contact}.rattles"] = (values.fillna(0) > 0).groupby(table["variant_index"]).any().to_numpy()
    for contact, column in contact_columns(table, SLIP_COLUMN).items():
        values = pd.to_numeric(table[column], errors="coerce")
        if values.notna().any():
            levels[f"{contact}.slips"] = (values.fillna(0) > 0).groupby(table["variant_index"]).any().to_numpy()
    return levels


#: fewer variants than this are drawn as dots (strip plot), not as a histogram
STRIP_BELOW = 10


def _stats(values) -> dict:
    values = np.asarray(pd.to_numeric(pd.Series(values), errors="coerce").dropna(), float)
    if values.size == 0:
        return {"count": 0}
    p5, p50, p95 = np.percentile(values, [5, 50, 95])
    out = {"count": int(values.size), "mean": float(values.mean()), "std": float(values.std(ddof=0)),
           "min": float(values.min()), "p5": float(p5), "median": float(p50), "p95": float(p95),
           "max": float(values.max())}
    if values.size >= 2:
        from scipy.stats import t

        half = float(t.ppf(0.975, values.size - 1) * values.std(ddof=1) / np.sqrt(values.size))
        out["mean_ci95"] = [out["mean"] - half, out["mean"] + half]
        for name, q in (("p5", 0.05), ("median", 0.5), ("p95", 0.95)):
            out[f"{name}_ci95"] = [v if math.isfinite(v) else None   # None: not bounded by n
                                   for v in quantile_band(values, q)]
    return out


def dkw_epsilon(n: int, confidence: float = 0.95) -> float:
    """Half-width ε = √(ln(2/α)/(2n)) of the DKW confidence band of an ECDF of n samples."""
    return float(np.sqrt(np.log(2.0 / (1.0 - confidence)) / (2.0 * max(int(n), 1))))


def quantile_band(values, q: float, confidence: float = 0.95) -> tuple:
    """(low, high) of the q-quantile read off the DKW band: the sample quantiles at q ∓ ε
    (−inf / +inf where the band leaves [0, 1]: too few variants to bound that side)."""
    values = np.sort(np.asarray(values, dtype=float))
    eps = dkw_epsilon(values.size, confidence)
    low = float(np.quantile(values, q - eps)) if q - eps >= 0 else -math.inf
    high = float(np.quantile(values, q + eps)) if q + eps <= 1 else math.inf
    return low, high


def wilson_interval(successes, trials, z: float = 1.96):
    """Wilson score interval (low, high) of a binomial proportion k/m (arrays broadcast)."""
    k = np.asarray(successes, dtype=float)
    m = np.maximum(np.asarray(trials, dtype=float), 1e-300)
    p = k / m
    centre = (p + z * z / (2 * m)) / (1 + z * z / m)
    half = z * np.sqrt(p * (1 - p) / m + z * z / (4 * m * m)) / (1 + z * z / m)
    return centre - half, centre + half


@dataclass(frozen=True)
class GateResult:
    passed: bool
    threshold_db: float | None
    offenders: list            # [{variant_id, reason, ...}]
    message: str               # readable, one line per offending variant


def _describe(row, parameters) -> str:
    values = ", ".join(f"{p}={_short_value(row[p])}" for p in parameters if not _missing(row[p]))
    return f"{row['variant_id']} [{row['source']}]" + (f" {values}" if values else "")


def _missing(value) -> bool:
    return value is None or (isinstance(value, float) and math.isnan(value))


def _short_value(value) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def evaluate_gate(table: pd.DataFrame, fail_above_db: float | None = None,
                  allow_nonconverged: bool = False, weighted: bool = False) -> GateResult:
    """CI gate: a variant fails when its max ERP level > ``fail_above_db`` [dB, or dB(A) when
    ``weighted``: the A-weighted level the review speaks], when it did not
    converge (unless ``allow_nonconverged``), or when it failed with an error.
    Exit code of a failed gate: ``GATE_EXIT_CODE`` (4)."""
    levels = variant_levels(table) if len(table) else pd.DataFrame()
    parameters = parameter_columns(table)
    column, unit = ("max_erp_dba", "dB(A)") if weighted else ("max_erp_db", "dB")
    offenders, lines = [], []
    for _, row in levels.iterrows():
        reason = None
        if row["status"] == "failed":
            reason = f"failed: {row['error']}"
        elif row["status"] == "nonconverged" and not allow_nonconverged:
            reason = "did not converge (use --allow-nonconverged to accept)"
        elif fail_above_db is not None and column in row and row[column] > fail_above_db:
            at = f" at {row['frequency_at_max_hz']:.6g} Hz" if "frequency_at_max_hz" in row and not weighted else ""
            reason = f"ERP {row[column]:.2f} {unit}{at} > {fail_above_db:g} {unit}"
        if reason is not None:
            offenders.append({"variant_id": row["variant_id"], "variant_index": int(row["variant_index"]),
                              "reason": reason})
            lines.append(f"  {_describe(row, parameters)}: {reason}")
    total = len(levels)
    if offenders:
        if fail_above_db is not None:
            head = f"gate failed: {len(offenders)} of {total} variants (threshold {fail_above_db:g} {unit})"
        else:
            head = f"{len(offenders)} of {total} variants failed or did not converge"
        message = "\n".join([head + ":"] + lines)
    else:
        message = f"gate passed: {total} variants" + (f" at or below {fail_above_db:g} {unit}" if fail_above_db is not None else "")
    return GateResult(passed=not offenders, threshold_db=fail_above_db, offenders=offenders, message=message)


def rattle_probability(levels: pd.DataFrame, gap_column: str, bins: int = 8) -> pd.DataFrame:
    """P(contact rattles) per gap value (grid/list) or gap bin (Monte Carlo).

    Columns: gap_low, gap_high, gap_mid [m], count, then one probability column per contact.
    """
    flags = [c for c in levels.columns if c.endswith(".rattles")]
    data = levels[levels["status"] != "failed"]
    gaps = pd.to_numeric(data[gap_column], errors="coerce")
    data, gaps = data[gaps.notna()], gaps[gaps.notna()]
    unique = np.unique(gaps.dropna())
    if unique.size == 0:
        return pd.DataFrame(columns=["gap_low", "gap_high", "gap_mid", "count"])
    if unique.size <= bins:
        labels = np.searchsorted(unique, gaps)
        low, high = unique, unique
    else:
        edges = np.linspace(unique[0], unique[-1], bins + 1)
        labels = np.clip(np.searchsorted(edges, gaps, side="right") - 1, 0, bins - 1)
        low, high = edges[:-1], edges[1:]
    out = []
    for label, members in data.groupby(np.asarray(labels)):
        row = {"gap_low": float(low[label]), "gap_high": float(high[label]),
               "gap_mid": 0.5 * float(low[label] + high[label]), "count": int(len(members)),
               **{f[: -len(".rattles")]: float(members[f].mean()) for f in flags}}
        for f in flags:
            lo, hi = wilson_interval(members[f].sum(), len(members))
            row[f"{f[: -len('.rattles')]}.ci95_low"] = float(lo)
            row[f"{f[: -len('.rattles')]}.ci95_high"] = float(hi)
        out.append(row)
    return pd.DataFrame(out)


def _probability_columns(table) -> list[str]:
    return [c for c in table.columns if c not in ("gap_low", "gap_high", "gap_mid", "count")
            and not c.endswith(".ci95_low") and not c.endswith(".ci95_high")]


def _level_column(levels):
    for column in ("max_erp_dba", "max_erp_db"):
        if column in levels and pd.to_numeric(levels[column], errors="coerce").notna().any():
            return column
    return None


def _numeric_parameters(levels) -> list[str]:
    out = []
    for p in parameter_columns(levels):
        values = pd.to_numeric(levels[p], errors="coerce") if p in levels else pd.Series([], dtype=float)
        if values.notna().sum() >= 2 and values.nunique() >= 2:
            out.append(p)
    return out


def _plots(levels: pd.DataFrame, output: pathlib.Path) -> list[str]:
    from matplotlib.figure import Figure  # no pyplot: no GUI backend, no global state

    written = []
    if "max_erp_db" in levels and levels["max_erp_db"].notna().any():
        figure = Figure(figsize=(6, 4))
        axis = figure.add_subplot()
        values = levels["max_erp_db"].dropna()
        if len(values) < STRIP_BELOW:    # too few for a histogram: every variant a dot
            axis.plot(values, np.zeros(len(values)), "o", color="tab:blue", alpha=0.7)
            axis.set_yticks([])
        else:
            axis.hist(values, bins=min(30, max(5, len(levels) // 4)), color="tab:blue")
            axis.set_ylabel("variants")
        axis.set_xlabel("max ERP level per variant [dB]")
        axis.set_title(f"ERP level over {int(levels['max_erp_db'].notna().sum())} variants")
        figure.tight_layout()
        figure.savefig(output / "erp_histogram.png", dpi=110)
        written.append("erp_histogram.png")
    column = _level_column(levels)
    if column is not None:
        values = np.sort(pd.to_numeric(levels[column], errors="coerce").dropna().to_numpy(float))
        n = values.size
        eps = dkw_epsilon(n)
        unit = "dB(A)" if column.endswith("dba") else "dB"
        figure = Figure(figsize=(7.5, 3.6))
        hist, cdf = figure.subplots(1, 2)
        hist.hist(values, bins=min(30, max(5, n // 4)), color="tab:blue")
        stats = _stats(values)
        if "mean_ci95" in stats:
            hist.axvspan(*stats["mean_ci95"], color="tab:orange", alpha=0.3,
                         label=f"mean {stats['mean']:.1f} {unit}, 95 % CI")
            hist.legend(fontsize="x-small")
        hist.set_xlabel(f"max ERP per variant [{unit}]")
        hist.set_ylabel("variants")
        ecdf = np.arange(1, n + 1) / n
        cdf.step(values, ecdf, where="post", color="tab:blue", label=f"ECDF, n = {n}")
        cdf.fill_between(values, np.clip(ecdf - eps, 0, 1), np.clip(ecdf + eps, 0, 1), step="post",
                         color="tab:blue", alpha=0.2, label=f"95 % band (DKW, ±{eps:.2f})")
        cdf.set_xlabel(f"max ERP per variant [{unit}]")
        cdf.set_ylabel("fraction of variants ≤ level")
        cdf.set_ylim(-0.02, 1.02)
        cdf.legend(fontsize="x-small", loc="lower right")
        for axis in (hist, cdf):
            axis.grid(True, alpha=0.3)
        figure.suptitle(f"distribution of the loudest level over {n} variants", fontsize="medium")
        figure.tight_layout()
        figure.savefig(output / "erp_distribution.png", dpi=110)
        written.append("erp_distribution.png")
    gaps = [c for c in parameter_columns(levels) if "gap" in c.lower()]
    has_flags = any(c.endswith(".rattles") for c in levels.columns)
    if gaps and has_flags:
        figure = Figure(figsize=(6, 4))
        axis = figure.add_subplot()
        for gap in gaps:
            table = rattle_probability(levels, gap)
            for contact in _probability_columns(table):
                axis.plot(table["gap_mid"] * 1e3, table[contact], "o-", label=f"{contact} vs {gap}")
        axis.set_xlabel("gap [mm]")
        axis.set_ylabel("probability that the contact rattles")
        axis.set_ylim(-0.02, 1.02)
        axis.legend(fontsize=7)
        figure.tight_layout()
        figure.savefig(output / "rattle_probability_vs_gap.png", dpi=110)
        written.append("rattle_probability_vs_gap.png")
    parameters = _numeric_parameters(levels)
    if parameters and has_flags:
        figure = Figure(figsize=(7.5, 3.0 * len(parameters)))
        for i, parameter in enumerate(parameters):
            axis = figure.add_subplot(len(parameters), 1, i + 1)
            table = rattle_probability(levels, parameter)
            for k, contact in enumerate(_probability_columns(table)):
                x = table["gap_mid"].to_numpy(float)
                axis.plot(x, table[contact], "o-", color=f"C{k}", label=contact)
                axis.fill_between(x, table[f"{contact}.ci95_low"], table[f"{contact}.ci95_high"],
                                  color=f"C{k}", alpha=0.2)
            axis.set_xlabel(parameter)
            axis.set_ylabel("P(rattle)")
            axis.set_ylim(-0.02, 1.02)
            axis.grid(True, alpha=0.3)
            axis.legend(fontsize="x-small", title="contact (band: 95 % Wilson)",
                        title_fontsize="x-small")
        figure.tight_layout()
        figure.savefig(output / "rattle_probability.png", dpi=110)
        written.append("rattle_probability.png")
    if parameters and column is not None:
        figure = Figure(figsize=(7.5, 3.0 * len(parameters)))
        for i, parameter in enumerate(parameters):
            axis = figure.add_subplot(len(parameters), 1, i + 1)
            x = pd.to_numeric(levels[parameter], errors="coerce")
            y = pd.to_numeric(levels[column], errors="coerce")
            axis.plot(x, y, "o", markersize=4)
            axis.set_xlabel(parameter)
            axis.set_ylabel(f"max ERP [{'dB(A)' if column.endswith('dba') else 'dB'}]")
            axis.grid(True, alpha=0.3)
        figure.tight_layout()
        figure.savefig(output / "erp_vs_parameters.png", dpi=110)
        written.append("erp_vs_parameters.png")
    return written


def write_batch_report_html(levels: pd.DataFrame, summary: dict, output: pathlib.Path,
                            images: list[str]) -> pathlib.Path:
    """``report.html`` of a batch: the distribution of the loudest level with its confidence
    bands, P(rattle) per contact vs each scattered parameter (Wilson bands), the loudest variants
    and the failures; self-contained (images as base64, CSS inline)."""
    column = _level_column(levels)
    loudest = []
    if column is not None:
        keep = ["variant_id", "source", "status", column] + [
            c for c in ("frequency_at_max_hz",) if c in levels] + parameter_columns(levels)
        top = levels.assign(_level=pd.to_numeric(levels[column], errors="coerce"))
        top = top.sort_values("_level", ascending=False).head(10)
        loudest = [{k: row[k] for k in keep if k in row} for _, row in top.iterrows()]
    probabilities = []
    for parameter in _numeric_parameters(levels):
        table = rattle_probability(levels, parameter) if any(
            c.endswith(".rattles") for c in levels.columns) else pd.DataFrame()
        for _, row in table.iterrows():
            for contact in _probability_columns(table):
                probabilities.append({"parameter": parameter, "low": row["gap_low"],
                                      "high": row["gap_high"], "count": int(row["count"]),
                                      "contact": contact, "p": row[contact],
                                      "ci_low": row[f"{contact}.ci95_low"],
                                      "ci_high": row[f"{contact}.ci95_high"]})
    env = environment()
    html = env.get_template("batch_report.html.j2").render(
        s=summary, column=column, loudest=loudest, probabilities=probabilities,
        parameters=parameter_columns(levels),
        images={name.rsplit(".", 1)[0]: data_uri(output / name) for name in images
                if (output / name).exists()})
    path = output / "report.html"
    store.atomic_write(path, html.encode("utf-8"))
    return path


def one_sample(levels: pd.DataFrame) -> bool:
    """True when every variant comes from one source (one study file, e.g. Monte-Carlo variants of
    one case): only then are their levels one statistical sample. Unrelated case files are not."""
    return "source" not in levels or levels["source"].nunique() <= 1


def per_case_rows(levels: pd.DataFrame) -> list[dict]:
    """One row per variant of a batch of unrelated cases: source, status, loudest level and where."""
    keep = [c for c in ("source", "variant_id", "status", "max_erp_dba", "max_erp_db",
                        "frequency_at_max_hz", "error") if c in levels]
    return [{k: (None if _missing(row[k]) else row[k]) for k in keep} for _, row in levels.iterrows()]


def summarize(table: pd.DataFrame, stats=None) -> dict:
    """Statistics of a merged batch table (the content of summary.json). Variants of one source
    (a study) are one sample: distribution, confidence intervals, P(rattle). Variants of
    unrelated case files are not: ``sample: "per case"`` and a per-case table ``cases`` instead."""
    levels = variant_levels(table) if len(table) else pd.DataFrame(columns=["status"])
    counts = levels["status"].value_counts().to_dict() if len(levels) else {}
    summary = {
        "variants": int(len(levels)),
        "ok": int(counts.get("ok", 0)),
        "nonconverged": int(counts.get("nonconverged", 0)),
        "failed": int(counts.get("failed", 0)),
        "rows": int(len(table)),
        "columns": {"erp_db": erp_column(table), "erp_dba": erp_a_column(table),
                    "frequency": frequency_column(table), "parameters": parameter_columns(table)},
    }
    summary["sample"] = "one case" if one_sample(levels) else "per case"
    if summary["sample"] == "per case":
        summary["cases"] = per_case_rows(levels)
        summary["failures"] = [{"variant_id": r["variant_id"], "error": r["error"]}
                               for _, r in levels.iterrows() if r["status"] == "failed"]
        if stats is not None:
            summary["run"] = asdict(stats)
        return summary
    if "max_erp_db" in levels:
        summary["max_erp_db"] = _stats(levels["max_erp_db"])
    if "max_erp_dba" in levels:
        summary["max_erp_dba"] = _stats(levels["max_erp_dba"])
    flags = [c for c in levels.columns if c.endswith(".rattles")]
    ok = levels[levels["status"] != "failed"] if len(levels) else levels
    if flags and len(ok):
        summary["rattle_probability"] = {f[: -len(".rattles")]: float(ok[f].mean()) for f in flags}
        summary["rattle_probability_ci95"] = {
            f[: -len(".rattles")]: [float(v) for v in wilson_interval(ok[f].sum(), len(ok))]
            for f in flags}
    slips = [c for c in levels.columns if c.endswith(".slips")]
    if slips and len(ok):
        summary["slip_probability"] = {f[: -len(".slips")]: float(ok[f].mean()) for f in slips}
        summary["slip_probability_ci95"] = {
            f[: -len(".slips")]: [float(v) for v in wilson_interval(ok[f].sum(), len(ok))]
            for f in slips}
    for parameter in parameter_columns(table):
        values = pd.to_numeric(levels[parameter], errors="coerce") if parameter in levels else pd.Series([], dtype=float)
        if values.notna().any():
            summary.setdefault("parameters", {})[parameter] = _stats(values)
    summary["failures"] = [{"variant_id": r["variant_id"], "error": r["error"]}
                           for _, r in levels.iterrows() if r["status"] == "failed"]
    if stats is not None:
        summary["run"] = asdict(stats)
    return summary


def write_report(table: pd.DataFrame, output, stats=None) -> dict:
    """Write summary.json, variants.csv (one row per variant), the PNGs and report.html; return the
    summary."""
    output = pathlib.Path(output)
    summary = summarize(table, stats)
    if len(table):
        levels = variant_levels(table)
        store.atomic_write(output / "variants.csv", levels.to_csv(index=False).encode())
        summary["plots"] = _plots(levels, output) if summary["sample"] == "one case" else []
        write_batch_report_html(levels, summary, output, summary["plots"])
        summary["report"] = "report.html"
    store.atomic_write(output / "summary.json", json.dumps(summary, indent=2, default=str).encode())
    return summary
