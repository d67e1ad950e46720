"""CPU seconds of each stage of one whole ``sarfe solve`` process (the breakdown in
benchmarks/results/peer.md): ``python stage_breakdown.py CASE.yaml -o DIR`` prints one JSON line
{stage: CPU s}.

Stages are timed by wrapping the pipeline's functions where the pipeline calls them (inclusive
CPU time, ``time.process_time``, so other processes on the machine do not count); a function that
does not exist (renamed) is simply not reported. 'start' is the interpreter's own start-up and
the standard library before this script runs; 'imports' what ``sarfe solve`` imports before it
works (the CLI, the pipeline; libraries a stage imports on first use count in that stage, e.g.
matplotlib in 'figures').
"""
import collections
import importlib
import json
import sys
import time

START = time.process_time()          # CPU of the interpreter start-up so far

STAGES = {   # reported name: (module, function), inclusive of what it calls
    "sweep (continuation, all points)": ("sarfe.pipeline.solve.pruned_points", "solve_points_pruned"),
    "  of which Hill stability": ("sarfe.hbm.solve", "stability"),
    "error estimates": ("sarfe.pipeline.post.records", "error_estimates"),
    "point records (ERP, baseline, contributions)": ("sarfe.pipeline.post.records", "point_record"),
    "figures (incl. matplotlib import)": ("sarfe.pipeline.write.figures", "point_figures"),
    "report.html": ("sarfe.results.report", "write_report_html"),
    "response.h5 (incl. h5py import)": ("sarfe.results.response_h5", "write_response_h5"),
    "summary.json": ("sarfe.results.summary", "write_summary_json"),
    "solve_case (all stages)": ("sarfe.pipeline.run", "solve_case"),
}


def main(argv):
    seconds = collections.OrderedDict(start=START)
    clock = time.process_time()
    import sarfe.cli as cli
    import sarfe.pipeline                                          # noqa: F401
    import sarfe.pipeline.checks.case_checks                                   # noqa: F401
    seconds["imports"] = time.process_time() - clock

    def timed(name, function):
        def wrapper(*args, **kwargs):
            begin = time.process_time()
            try:
                return function(*args, **kwargs)
            finally:
                seconds[name] = seconds.get(name, 0.0) + time.process_time() - begin
        return wrapper

    for name, (module_name, attribute) in STAGES.items():
        try:
            module = importlib.import_module(module_name)
        except ImportError:
            continue
        function = getattr(module, attribute, None)
        if function is None:
            continue
        wrapper = timed(name.strip(), function)
        for other in list(sys.modules.values()):    # every sarfe module that bound the function
            space = getattr(other, "__dict__", None)
            if (isinstance(space, dict) and getattr(other, "__name__", "").startswith("sarfe")
                    and space.get(attribute) is function):
                setattr(other, attribute, wrapper)
    code = cli.main(["solve"] + list(argv) + ["--quiet"])
    seconds["process total"] = time.process_time()
    print(json.dumps({k: round(v, 3) for k, v in seconds.items()}))
    return code


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
