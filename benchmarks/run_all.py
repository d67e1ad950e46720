"""Run sarfe's benchmarks: every ``bench_*.py`` under benchmarks/ (any folder), in turn.

    python benchmarks/run_all.py                 every benchmark (``make bench``; some take hours)
    python benchmarks/run_all.py hbm peer/       only those whose path (e.g. engine/bench_hbm.py)
                                                 contains one of the words
    python benchmarks/run_all.py --list [WORD…]  list them, run nothing

The rule: a benchmark is a file named ``bench_*.py`` anywhere below benchmarks/; run with no
arguments it measures what it is for and writes benchmarks/results/<name>.json and .md. The
folders group them — engine/ (harmonic balance on small models), linear/ (mesh, FE, reduction,
decks), pipeline/ (whole ``sarfe solve`` runs: cost per point, outputs, workers, batch),
accuracy/ (errors against converged references), peer/ (sarfe beside pyHarm) — and tools/ holds
the helpers that are not benchmarks (compare_outputs.py, stage_cpu.py, stability_counts.py).
Each runs as its own process (its arguments are its own, its peak memory its own), with one
BLAS thread; a failing benchmark is reported and the others still run (exit code 1 at the end).
"""
from __future__ import annotations

import argparse
import pathlib
import subprocess
import sys
import time

from benchlib import BENCHMARKS, child_env


def benchmarks(words=()) -> list[pathlib.Path]:
    """Every bench_*.py below benchmarks/ whose relative path contains one of ``words`` (all when
    none), sorted by path."""
    found = sorted(BENCHMARKS.rglob("bench_*.py"))
    return [p for p in found
            if not words or any(w in p.relative_to(BENCHMARKS).as_posix() for w in words)]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("words", nargs="*", help="run only benchmarks whose path contains one")
    parser.add_argument("--list", action="store_true", help="list the benchmarks, run nothing")
    args = parser.parse_args(argv)
    scripts = benchmarks(args.words)
    if not scripts:
        print(f"no benchmark matches {args.words}", file=sys.stderr)
        return 2
    if args.list:
        for script in scripts:
            print(script.relative_to(BENCHMARKS).as_posix())
        return 0
    failed = []
    for script in scripts:
        name = script.relative_to(BENCHMARKS).as_posix()
        start = time.perf_counter()
        print(f"== {name}", flush=True)
        code = subprocess.run([sys.executable, str(script)], env=child_env()).returncode
        print(f"== {name} {'done' if code == 0 else f'FAILED (exit {code})'} in "
              f"{time.perf_counter() - start:.1f} s", flush=True)
        if code:
            failed.append(name)
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
