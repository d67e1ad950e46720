"""``sarfe compare RESULT_A RESULT_B … -o DIR``: compare design variants' solve results.

Writes DIR/compare.json and DIR/compare.html (+ PNGs): the headline of every variant and each
one's ``delta_dba`` against the first (per point, contact, band; :mod:`sarfe.compare.deltas`),
overlaid sweeps, contributions side by side and a difference ERP map where the meshes agree.
Exit codes: 0 written; 2 an argument is not a sarfe solve result or the output folder is refused
(one line on stderr); 1 internal error.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from sarfe.case.errors import EXIT_CASE_ERROR, CaseError
from sarfe import compare    # its exports load on first use: h5py, matplotlib only when it runs

HELP = "compare solve results of design variants (deltas in dB(A) against the first)"
EPILOG = "exit codes: 0 written, 2 a folder is not a sarfe result or the output is refused, 1 internal error"
OUTPUT_NAMES = {"compare.json", "compare.html", "compare_sweeps.png", "compare_contributions.png"}


def _check_output(folder: Path, inputs: list[Path]) -> None:
    """The output folder may be absent, empty, or an earlier comparison (only its own files)."""
    if folder.exists() and not folder.is_dir():
        raise CaseError(f"{folder}: output exists and is not a folder", source=str(folder))
    if any(folder.resolve() == p.resolve() for p in inputs):
        raise CaseError(f"{folder}: the output folder is one of the compared results",
                        source=str(folder))
    if folder.is_dir():
        foreign = sorted(p.name for p in folder.iterdir()
                         if p.name not in OUTPUT_NAMES and not p.name.startswith("compare_map_"))
        if foreign:
            raise CaseError(f"{folder}: output folder holds files sarfe compare did not write "
                            f"({', '.join(foreign[:3])}{', …' if len(foreign) > 3 else ''})",
                            source=str(folder))


def run(args: argparse.Namespace) -> int:
    """Handler of ``sarfe compare``; returns the exit code."""
    inputs = [Path(p) for p in args.results]
    try:
        results = [compare.read_result(p) for p in inputs]
        output = Path(args.output)
        _check_output(output, inputs)
    except CaseError as error:
        print(f"sarfe compare: {error}", file=sys.stderr)
        return EXIT_CASE_ERROR
    data = compare.write_comparison(results, output)
    if not getattr(args, "quiet", False):
        for h, c in zip(data["headlines"], [None] + data["comparisons"]):
            delta = "reference" if c is None else f"Δ {c['worst_delta_dba']:+.2f} dB(A)"
            print(f"{h['case'][:28]:28s} {h['level_dba']:6.1f} dB(A) at {h['frequency_hz']:g} Hz  "
                  f"{delta}")
    print(f"comparison: {output / 'compare.html'}")
    return 0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("results", nargs="+", metavar="RESULT",
                        help="result folders of `sarfe solve` (the first is the reference)")
    parser.add_argument("--output", "-o", metavar="DIR", required=True,
                        help="folder for compare.html and compare.json")
    parser.add_argument("--quiet", action="store_true", help="print only the output path")


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``compare`` subcommand to ``sarfe``'s subparsers (handler in defaults ``func``)."""
    parser = subparsers.add_parser("compare", help=HELP, description=HELP + ".", epilog=EPILOG)
    add_arguments(parser)
    parser.set_defaults(func=run)
    return parser
