"""Write a comparison folder: compare.json, compare.html and its PNGs (``sarfe compare``).

    write_comparison(results, output_dir) -> dict    (compare.json's content)

compare.json: ``reference`` (label of the first result), ``headlines`` (per variant: loudest
level [dB(A)], its error bound [dB], frequency [Hz], top contact), ``comparisons`` (per further
variant: ``worst_delta_dba`` and per common frequency point ``delta_dba`` of the total, of each
contact, band and contribution source; see :mod:`sarfe.compare.deltas`) and ``maps`` (the
difference ERP map's statistics, or why there is none). Non-finite numbers are written as null
with a note (``sarfe.results.summary.write_summary_json``).
"""
from __future__ import annotations

from pathlib import Path

from sarfe import __version__
from sarfe.compare.compare_figures import plot_contributions, plot_map_difference, plot_sweeps
from sarfe.compare.deltas import compare_all
from sarfe.compare.map_difference import map_difference
from sarfe.results.report import environment
from sarfe.results.summary import write_summary_json


def write_comparison(results: list, output_dir) -> dict:
    """Compute every delta against ``results[0]``, draw the figures, write the JSON and the HTML."""
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    data = compare_all(results)
    data["sarfe_version"] = __version__
    reference = results[0]
    images = {"sweeps": plot_sweeps(out / "compare_sweeps.png", results).name}
    images["contributions"] = plot_contributions(out / "compare_contributions.png", results).name
    maps = []
    for k, other in enumerate(results[1:], start=1):
        difference, reason = map_difference(reference, other)
        entry = {"variant": other.label}
        if difference is None:
            entry["available"], entry["reason"] = False, reason
        else:
            name = f"compare_map_{k}.png"
            plot_map_difference(out / name, difference,
                                f"{other.label} − {reference.label} at {difference.frequency_hz:g} Hz")
            entry.update(available=True, image=name, **difference.stats())
        maps.append(entry)
    data["maps"] = maps
    write_summary_json(out / "compare.json", data)
    html = environment().get_template("compare.html.j2").render(data=data, images=images,
                                                                 version=__version__)
    (out / "compare.html").write_text(html, encoding="utf-8")
    return data
