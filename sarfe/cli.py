"""Command line: ``sarfe solve | verify | validate CASE.yaml`` and ``sarfe --version``.

Exit codes: 0 success; 2 a problem in the case file (one line on stderr naming the key, no
traceback unless ``--debug``), or of the system met reading or writing (a full disk, a read-only
file system, no permission, a busy mount point: one line naming the path,
:func:`sarfe.results.folder.os_error`); 4 ``output.target_dba`` exceeded at the loudest converged
point; 3 the run finished but some frequency point did not converge (see summary.json
``non_converged_points``) — 4 before 3 (:mod:`sarfe.case.errors`); 1 an unexpected internal error;
130 interrupted.
Subcommands ``study`` (``sarfe.tradeoff.cli``), ``batch`` (``sarfe.batch.cli``) and ``compare``
(``sarfe.compare.cli``) are added by their
``register(subparsers)`` functions.
"""
from __future__ import annotations

import argparse
import sys
import textwrap
import time
import traceback

import numpy as np

from sarfe import __version__
from sarfe.batch import cli as batch_cli
from sarfe.case.errors import EXIT_CASE_ERROR, EXIT_NOT_CONVERGED, CaseError
from sarfe.compare import cli as compare_cli
from sarfe.pipeline import build_linear_model, load_case, nonlinear_model, solve_case
from sarfe.pipeline.checks.case_checks import check_case, output_target
from sarfe.pipeline.checks.run_cost import cost_lines, run_cost
from sarfe.pipeline.verify import format_rows, verify_point
from sarfe.results.console import WIDTH, quiet_line, summary_lines
from sarfe.results.folder import os_error
from sarfe.results.summary import pruning_line, stability_line
from sarfe.tradeoff import cli as tradeoff_cli


def _say(args, text):
    if not getattr(args, "quiet", False):
        print(text, flush=True)


def _warn(line):
    print(f"sarfe: warning: {line}", file=sys.stderr, flush=True)


def cmd_solve(args) -> int:
    case = load_case(args.case)
    output_target(case, args.output, args.force)   # before any work (solve_case checks it all)
    clock = time.perf_counter()
    _say(args, textwrap.fill(f"sarfe {__version__}: solving {case.name} ({args.case})", WIDTH,
                             subsequent_indent="  ", break_long_words=False,
                             break_on_hyphens=False))
    result = solve_case(case, output_dir=args.output, progress=not args.quiet, force=args.force,
                        warn=_warn)
    summary = result.summary
    if args.quiet:      # one result line and the path
        print(quiet_line(summary))
        print(f"results: {result.output_dir}")
    else:
        model = summary["model"]
        if model.get("kind") == "fe":
            residual = model.get("residual_vectors") or 0     # reduced = boundary + modes + these
            print(f"model: {model['nodes']} nodes, {model['free_dofs']} DOFs → "
                  f"{model['reduced_dofs']} ({model['boundary_dofs']} boundary + "
                  f"{model['modes']} modes" + (f" + {residual} residual)" if residual else ")"))
        pruning = pruning_line(summary.get("contact_pruning"))
        if pruning:
            print(pruning[:WIDTH])
        for line in summary_lines(summary, result.rows):
            print(line)
        if (summary.get("mesh_error") or {}).get("line"):
            print(textwrap.fill(summary["mesh_error"]["line"], WIDTH, subsequent_indent="  "))
        files = summary.get("files") or {}
        shown = ", ".join([files[k] for k in ("table", "report") if k in files]
                          + (["sound.wav"] if "sound" in files else []))
        print(f"results: {result.output_dir}  ({time.perf_counter() - clock:.1f} s)")
        if shown:
            print(f"  full table and every contact: {shown}")
    if summary["non_converged_points"]:
        print(f"sarfe: {len(summary['non_converged_points'])} point(s) did not converge: "
              f"{summary['non_converged_points']} (see summary.json)", file=sys.stderr)
    unresolved = stability_line(summary.get("points") or [])
    if unresolved:
        print(f"sarfe: {unresolved}", file=sys.stderr)
    if (summary.get("accuracy_check") or {}).get("warning"):
        print(f"sarfe: {summary['accuracy_check']['warning']}", file=sys.stderr)
    if summary.get("sweep_complete") is False:
        print(f"sarfe: {summary['sweep_stop_reason']}", file=sys.stderr)
    if summary.get("sweep_note"):
        print(f"sarfe: note: {summary['sweep_note']}", file=sys.stderr)
    return result.exit_code


def cmd_validate(args) -> int:
    """Every check `solve` makes before the heavy work (sarfe.pipeline.checks.case_checks); warnings on stderr."""
    case = load_case(args.case)
    checked = check_case(case, output_dir=args.output, force=args.force)
    for line in checked.warnings:
        _warn(line)
    info = checked.info
    text = f"{args.case}: valid"
    if info:
        pairs = ", ".join(f"{k} ({v} pairs)" for k, v in info["contact_pairs"].items())
        text += f" ({info['nodes']} nodes, {info['triangles']} triangles; contacts: {pairs or 'none'})"
        if info.get("ignored_cards"):   # deck cards named in model.fe.ignore_cards
            text += "\n  ignored cards: " + ", ".join(
                f"{card} ({count})" for card, count in sorted(info["ignored_cards"].items()))
        if info.get("coincident_node_pairs"):
            shown = ", ".join(f"{a}={b}" for a, b in info["coincident_nodes"][:10])
            text += (f"\n  note: {info['coincident_node_pairs']} pair(s) of coincident nodes that "
                     f"no element joins (node ids): {shown}")
    if checked.size is not None:      # what solve will cost (issue 30 item 4)
        text += "\n" + "\n".join(cost_lines(run_cost(case, checked.size)))
    _say(args, text)
    return 0


def cmd_verify(args) -> int:
    """Time integration of one point against the harmonic balance: every harmonic up to H, contact
    and largest-DOF amplitudes, ERP total and dB(A), and the stability verdict (a perturbation of
    the HBM orbit decays or grows), each with its tolerance (:mod:`sarfe.pipeline.verify`)."""
    if not args.frequency_hz > 0:
        raise CaseError(f"--frequency-hz must be > 0, got {args.frequency_hz}", source=args.case)
    case = load_case(args.case)
    stage = build_linear_model(case, progress=not args.quiet)
    nl = nonlinear_model(case, stage)
    hbm, tim, check, rows = verify_point(case.config.solver, case.config.erp, stage, nl,
                                         2 * np.pi * args.frequency_hz, args.tolerance,
                                         args.tolerance_db)
    print(f"verify {case.name} at {args.frequency_hz:g} Hz: HBM (H={hbm.harmonics}, "
          f"N={hbm.samples_per_period}, converged={hbm.converged}) vs time integration "
          f"({tim.steps_per_period} steps/period, {tim.periods} periods, steady={tim.steady})"
          + ("" if check is None else f"; monodromy from {check.periods} perturbed periods"))
    for line in format_rows(rows):
        print(line)
    bad = [r.label for r in rows if not r.agree]
    print("agree: every comparison within its tolerance" if not bad
          else f"DIFFER: {len(bad)} of {len(rows)} comparisons outside tolerance")
    return 0 if not bad and hbm.converged else EXIT_NOT_CONVERGED


def output_options(parser) -> None:
    parser.add_argument("--output", "-o", metavar="DIR", default=None,
                        help="result directory (default: output.directory of the case, "
                        "results/<name>); must be absent, empty or an earlier sarfe result holding "
                        "only what sarfe wrote")
    parser.add_argument("--force", action="store_true",
                        help="replace an output folder holding files sarfe did not write, "
                        "deleting them (never the current, home or case file's folder)")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="sarfe", description="Squeak & rattle noise of car interior panels: FE + "
        "Craig–Bampton + harmonic balance with contact + equivalent radiated power.",
        epilog="exit codes: 0 ok, 2 case-file error, 4 output.target_dba exceeded at the loudest "
               "point, 3 a point did not converge or an incomplete sweep left part of its band "
               "without converged points (4 before 3), 1 internal error")
    parser.add_argument("--version", action="version", version=f"sarfe {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    def common(p):
        p.add_argument("case", metavar="CASE.yaml", help="case file")
        p.add_argument("--debug", action="store_true", help="show tracebacks")
        p.add_argument("--quiet", action="store_true", help="no progress bars or table; solve "
                       "prints one result line and the result path")

    p = sub.add_parser("solve", help="solve a case and write results")
    common(p)
    output_options(p)
    p.set_defaults(func=cmd_solve)
    p = sub.add_parser("verify", help="compare HBM with time integration at one frequency")
    common(p)
    p.add_argument("--frequency-hz", type=float, required=True, metavar="F")
    p.add_argument("--tolerance", type=float, default=0.05,
                   help="relative amplitude/ERP difference accepted (default 0.05)")
    p.add_argument("--tolerance-db", type=float, default=0.5,
                   help="ERP dB(A) difference accepted (default 0.5)")
    p.set_defaults(func=cmd_verify)
    p = sub.add_parser("validate", help="check a case file: everything `solve` checks before "
                       "the heavy work (schema, numbers, mesh quality, groups, contact pairing, "
                       "held structure, output folder)")
    common(p)
    output_options(p)
    p.set_defaults(func=cmd_validate)

    tradeoff_cli.register(sub)
    batch_cli.register(sub)
    compare_cli.register(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return EXIT_CASE_ERROR
    debug = getattr(args, "debug", False)
    try:
        return int(args.func(args) or 0)
    except CaseError as exc:
        if debug:
            traceback.print_exc()
        message = str(exc)
        case_file = getattr(args, "case", None)
        if case_file and exc.source is None:
            message = f"{case_file}: {message}"
        print(f"sarfe: error: {message}", file=sys.stderr)
        return EXIT_CASE_ERROR
    except KeyboardInterrupt:
        print("sarfe: interrupted", file=sys.stderr)
        return 130
    except OSError as exc:    # a full disk, a read-only file system …: one line, exit 2
        error = os_error(exc)
        if error is None:
            return _internal_error(exc, debug)
        if debug:
            traceback.print_exc()
        print(f"sarfe: error: {error}", file=sys.stderr)
        return EXIT_CASE_ERROR
    except Exception as exc:  # an internal error: one line unless --debug
        return _internal_error(exc, debug)


def _internal_error(exc, debug) -> int:
    if debug:
        traceback.print_exc()
    else:
        print(f"sarfe: internal error: {type(exc).__name__}: {exc} (rerun with --debug for "
              "the traceback)", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
