"""``sarfe batch``: run case files and study files, optionally through a Dask cluster.

Exit codes (as ``sarfe solve`` where they overlap): 0 every variant finished and converged, or
the gate passed; 2 unusable study/case file or a package of the ``batch`` extra missing (nothing
run); 3 no gate asked and some variant did not
converge (unless ``--allow-nonconverged``); 4 gate failed (``--fail-above-db``: a variant above the
level, a non-converged one unless ``--allow-nonconverged``, or a failed one); 5 no gate asked and
some variants failed with an error (each recorded in the table); 1 internal error.
"""
from __future__ import annotations

import argparse
import importlib.util
import sys

from sarfe import batch    # its exports load on first use: pandas and dask only when a batch runs
from sarfe.case.errors import EXIT_NOT_CONVERGED, CaseError

EXIT_VARIANTS_FAILED = 5
# The optional dependencies of ``sarfe batch`` (pyproject extra ``batch``); the solve never imports
# them. distributed (Dask) only runs the variants in parallel: ``--workers 0`` needs none of it.
BATCH_EXTRA = "batch"
TABLE_PACKAGES = ("pandas", "pyarrow")
CLUSTER_PACKAGES = ("distributed",)
HELP = "run many cases or a study (grid / list / Monte Carlo variations) in parallel"
EPILOG = ("exit codes: 0 all variants finished and converged, or the gate passed; 2 bad study or case "
          "file or missing batch extra; 3 some variant did not converge (no gate); 4 gate failed (offending variants listed on "
          "stderr); 5 some variants failed with an error (no gate); 1 internal error")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("inputs", nargs="+", metavar="CASE_OR_STUDY",
                        help="case files (.yaml) and/or study files (with a base_case key)")
    parser.add_argument("--scheduler", metavar="ADDRESS", default=None,
                        help="address of a running Dask scheduler, e.g. tcp://10.0.0.5:8786")
    parser.add_argument("--workers", type=int, default=2, metavar="N",
                        help="local worker processes when no --scheduler (default 2; 0 = in this process, no Dask)")
    parser.add_argument("--output", metavar="DIR", default=None,
                        help="output folder (default results/<study name>); re-running resumes there")
    parser.add_argument("--fail-above-db", type=float, default=None, metavar="X",
                        help=f"CI gate: exit 4 if any variant's max ERP level exceeds X dB, "
                             "did not converge, or failed")
    parser.add_argument("--fail-above-dba", type=float, default=None, metavar="X",
                        help="CI gate in the review's unit: exit 4 if any variant's max A-weighted "
                             "ERP level exceeds X dB(A), did not converge, or failed")
    parser.add_argument("--allow-nonconverged", action="store_true",
                        help="non-converged variants do not fail the gate")
    parser.add_argument("--write-variant-outputs", action="store_true",
                        help="also write each variant's own output folder (variant_outputs/<id>/)")
    parser.add_argument("--retry-failed", action="store_true",
                        help="run variants that failed in an earlier run again")
    parser.add_argument("--force", action="store_true",
                        help="write into an output folder that is not a sarfe batch folder or holds "
                             "files the batch did not write (nothing is deleted; never the current "
                             "folder or one holding an input file)")
    parser.add_argument("--no-cache", action="store_true",
                        help="do not read/write linear stages in <output>/.cache")


def missing_packages(workers: int, scheduler: str | None) -> list[str]:
    """The packages of the ``batch`` extra this run needs and cannot import (Dask only when it runs
    on workers or a scheduler)."""
    needed = TABLE_PACKAGES + (CLUSTER_PACKAGES if workers > 0 or scheduler else ())
    return [name for name in needed if importlib.util.find_spec(name) is None]


def run(args: argparse.Namespace) -> int:
    """Handler of ``sarfe batch``; returns the exit code."""
    missing = missing_packages(args.workers, args.scheduler)
    if missing:
        print(f"sarfe batch: needs the optional package{'s' if len(missing) > 1 else ''} "
              f"{', '.join(missing)}: install them with pip install 'sarfe[{BATCH_EXTRA}]' "
              f"(from a source tree: pip install -e '.[{BATCH_EXTRA}]')", file=sys.stderr)
        return 2
    if args.fail_above_db is not None and getattr(args, "fail_above_dba", None) is not None:
        print("sarfe batch: give one of --fail-above-db and --fail-above-dba", file=sys.stderr)
        return 2
    if args.workers < 0:
        print("sarfe batch: --workers must be >= 0", file=sys.stderr)
        return 2
    try:
        output = args.output
        if output is None:
            output = batch.default_output_dir(batch.collect_variants(args.inputs))
        table = batch.run_study(args.inputs, workers=args.workers, scheduler=args.scheduler, output_dir=output,
                          write_variant_outputs=args.write_variant_outputs, retry_failed=args.retry_failed,
                          cache_linear_stages=not args.no_cache, progress=True,
                          force=getattr(args, "force", False))
    except (batch.StudyError, CaseError) as error:
        print(f"sarfe batch: {error}", file=sys.stderr)
        return 2
    summary = table.attrs.get("summary", {})
    print(_summary_line(summary, output))
    weighted = getattr(args, "fail_above_dba", None) is not None
    threshold = args.fail_above_dba if weighted else args.fail_above_db
    gate = batch.evaluate_gate(table, threshold, args.allow_nonconverged, weighted=weighted)
    if threshold is not None or not gate.passed:
        print(f"sarfe batch: {gate.message}", file=sys.stderr if not gate.passed else sys.stdout)
    if threshold is not None:
        return 0 if gate.passed else batch.GATE_EXIT_CODE
    if summary.get("failed"):
        return EXIT_VARIANTS_FAILED
    return EXIT_NOT_CONVERGED if summary.get("nonconverged") and not args.allow_nonconverged else 0


def _summary_line(summary: dict, output) -> str:
    run = summary.get("run", {})
    level = summary.get("max_erp_db", {})
    text = (f"{summary.get('variants', 0)} variants: {summary.get('ok', 0)} ok, "
            f"{summary.get('nonconverged', 0)} non-converged, {summary.get('failed', 0)} failed "
            f"({run.get('skipped', 0)} from an earlier run); "
            f"linear stages built {run.get('linear_stages_built', 0)}, cached {run.get('linear_stages_from_cache', 0)}")
    if level.get("count"):
        text += f"; max ERP {level['min']:.1f}…{level['max']:.1f} dB (median {level['median']:.1f})"
    return text + f"; results in {output}"


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``batch`` subcommand to ``sarfe``'s subparsers (handler in defaults ``func``)."""
    parser = subparsers.add_parser("batch", help=HELP, description=HELP + ".", epilog=EPILOG)
    add_arguments(parser)
    parser.set_defaults(func=run, handler=run)
    return parser


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="sarfe batch", description=HELP + ".", epilog=EPILOG)
    add_arguments(parser)
    return run(parser.parse_args(argv))
