"""``sarfe study CASE.yaml``: the speed/accuracy trade of a case (see :mod:`sarfe.tradeoff.study`),
and ``--accuracy fast|balanced|fine|erp_db=0.5``: choose H, N (and the mode count) for a target."""
from __future__ import annotations

import time

from sarfe.case.errors import CaseError
from sarfe.pipeline.solve.case_accuracy import resolve_case_accuracy
from sarfe.tradeoff.study import KNOBS, run_study, study_table


def register(subparsers):
    p = subparsers.add_parser(
        "study", help="vary H, N, modes, mesh, penalty one at a time: error vs cost (table, CSV, "
        "JSON, Pareto PNG)")
    p.add_argument("case", metavar="CASE.yaml", help="case file")
    p.add_argument("--knobs", default=None,
                   help="comma-separated subset of harmonics,samples,modes,mesh,penalty")
    p.add_argument("--points", type=int, default=12, help="frequencies over the sweep (default 12)")
    p.add_argument("--output", "-o", metavar="DIR", default=None,
                   help="result directory (default <output.directory>/study)")
    p.add_argument("--no-estimate", action="store_true", help="skip the a-posteriori estimates")
    p.add_argument("--accuracy", default=None, metavar="TARGET",
                   help="instead of the study: choose H, N, modes for fast|balanced|fine|"
                   "erp_db=X|amplitude_rel=X at the loudest grid point")
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=cmd_study)
    return p


def cmd_study(args) -> int:
    knobs = None
    if args.knobs:
        knobs = [k.strip() for k in args.knobs.split(",") if k.strip()]
        bad = [k for k in knobs if k not in KNOBS]
        if bad:
            raise CaseError(f"--knobs: unknown {bad}; choose from {', '.join(KNOBS)}")
    if args.points < 1:
        raise CaseError(f"--points must be >= 1, got {args.points}")
    if args.accuracy:
        return cmd_accuracy(args)
    clock = time.perf_counter()
    say = (lambda text: None) if args.quiet else (lambda text: print(f"  {text}", flush=True))
    result = run_study(args.case, knobs=knobs, points=args.points, output_dir=args.output,
                       estimate=not args.no_estimate, progress=say)
    print(study_table(result.rows))
    print(f"study: {result.output_dir}  ({time.perf_counter() - clock:.1f} s)")
    return 0


def cmd_accuracy(args) -> int:
    try:
        report = resolve_case_accuracy(args.case, args.accuracy, points=args.points)
    except ValueError as exc:
        if isinstance(exc, CaseError):
            raise
        raise CaseError(f"--accuracy: {exc}") from exc
    print(report["text"])
    return 0 if report["met"] else 3
