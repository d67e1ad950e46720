"""sarfe.compare — ``sarfe compare``: design variants' solve results side by side.

    result_reader   read_result(folder) -> Result (summary.json, response.h5), read_erp_map (VTU)
    deltas          compare_all(results) -> dict: headlines and delta_dba vs the first result
                    per point, contact, band and contribution source
    map_difference  map_difference(a, b) -> (MapDifference | None, reason): ΔL per node [dB]
                    where the meshes agree
    compare_figures overlaid sweeps, contributions side by side, difference map (PNG)
    compare_report  write_comparison(results, dir): compare.json, compare.html (jinja2 template
                    sarfe/results/templates/compare.html.j2)
    cli             the ``compare`` subcommand
"""
from sarfe.util.lazy import lazy_exports

# exports load on first use (sarfe.util.lazy): h5py, matplotlib, jinja2 only when a comparison runs
_EXPORTS = {"read_result": ".result_reader", "Result": ".result_reader",
            "compare_all": ".deltas", "write_comparison": ".compare_report",
            "map_difference": ".map_difference"}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = ["read_result", "Result", "compare_all", "write_comparison", "map_difference"]
