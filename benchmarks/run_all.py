"""Run every benchmarks/bench_*.py in turn; each writes its own results file in benchmarks/results/.

Usage: python benchmarks/run_all.py [name-filter]
"""
import pathlib
import runpy
import sys
import time

here = pathlib.Path(__file__).resolve().parent
pattern = sys.argv[1] if len(sys.argv) > 1 else ""
scripts = sorted(p for p in here.glob("bench_*.py") if pattern in p.stem)
if not scripts:
    sys.exit(f"no benchmark matches {pattern!r}")
(here / "results").mkdir(exist_ok=True)
for script in scripts:
    start = time.perf_counter()
    print(f"== {script.name}", flush=True)
    runpy.run_path(str(script), run_name="__main__")
    print(f"== {script.name} done in {time.perf_counter() - start:.1f} s", flush=True)
