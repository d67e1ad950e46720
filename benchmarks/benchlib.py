"""The one helper module of sarfe's benchmarks: paths, one BLAS thread, the machine, whole-process
timing, results files and case files.

A benchmark script (``benchmarks/<group>/bench_<name>.py``) starts with

    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))   # benchmarks/: benchlib
    import benchlib  # noqa: E402

Importing this module puts the repository root on ``sys.path`` after the trees PYTHONPATH names and
before the installed packages: the ``sarfe`` measured is PYTHONPATH's when set (the scripts that
compare two trees start one child per tree with ``PYTHONPATH=TREE``), else this tree's. It sets one
BLAS/OpenMP thread and the Agg backend for this process unless the caller set them (on 2 shared
cores oversubscribed BLAS threads cost 75×). What it gives:

- paths: ``ROOT`` (the repository), ``BENCHMARKS``, ``RESULTS`` (benchmarks/results/, where every
  benchmark writes ``<name>.json`` and ``<name>.md``), ``CASES``;
- ``ENV`` / :func:`child_env`: the environment of a child process (one thread each, this tree on
  PYTHONPATH or another tree's);
- :func:`machine`: platform, cores, Python, load average — the lines a results file opens with;
- :func:`run_timed`: wall and CPU seconds (user + system) of one whole child process;
  :func:`cpu_seconds`: this process's CPU seconds; :func:`peak_rss_gb`: its peak RSS;
  :func:`process_tree`, :func:`tree_cpu_seconds`, :func:`pss_gb`, :func:`tree_pss_gb`: a running
  process tree's CPU seconds and PSS from /proc (forked workers share pages: PSS counts them once);
- :func:`write_results` / :func:`read_results`: results/<name>.json (+ .md);
- :func:`read_case` / :func:`write_case`: a case file as a dict, and a variant of it written as YAML
  next to the original (so that its relative paths — meshes, decks — still resolve).
"""
from __future__ import annotations

import json
import os
import pathlib
import platform
import resource
import subprocess
import sys
import tempfile
import time

import yaml

BENCHMARKS = pathlib.Path(__file__).resolve().parent
ROOT = BENCHMARKS.parent
RESULTS = BENCHMARKS / "results"
CASES = ROOT / "cases"
THREADS = {name: "1" for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}

if str(ROOT) not in sys.path:       # before the standard library and site-packages
    _installed = [i for i, p in enumerate(sys.path) if p.startswith((sys.base_prefix, sys.prefix))]
    sys.path.insert(_installed[0] if _installed else len(sys.path), str(ROOT))
for _name, _value in {**THREADS, "MPLBACKEND": "Agg"}.items():
    os.environ.setdefault(_name, _value)


def child_env(tree=ROOT, **extra) -> dict:
    """Environment of a child process: one BLAS/OpenMP thread, the Agg backend, ``tree`` (a sarfe
    source tree) on PYTHONPATH, and ``extra`` variables."""
    return dict(os.environ, **THREADS, MPLBACKEND="Agg", PYTHONPATH=str(tree), **extra)


ENV = child_env()


def machine() -> dict:
    """The machine a result was measured on."""
    return {"machine": platform.platform(), "processor": platform.machine(),
            "cpu_count": os.cpu_count(), "python": platform.python_version(),
            "load_average": list(os.getloadavg())}


def machine_line() -> str:
    """One line: platform, cores, Python, load average now, one BLAS thread."""
    m = machine()
    return (f"Machine: {m['machine']}, {m['cpu_count']} cores, Python {m['python']}, load average "
            f"{m['load_average'][0]:.2f}; OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")


def run_timed(command, cwd=None, env=None, ok=(0, 3)):
    """(wall s, CPU s of the child (user + system), stdout) of one whole process; RuntimeError with
    the end of its stderr when its exit code is not in ``ok`` (3: a sarfe run with a point that did
    not converge)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, env=ENV if env is None else env, cwd=cwd, capture_output=True,
                          text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode not in ok:
        raise RuntimeError(f"{command} failed ({done.returncode}): {done.stderr[-2000:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), done.stdout


def cpu_seconds() -> float:
    """CPU seconds (user + system) of this process and its waited-for children."""
    own, children = (resource.getrusage(who) for who in (resource.RUSAGE_SELF,
                                                          resource.RUSAGE_CHILDREN))
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def peak_rss_gb() -> float:
    """Peak resident memory of this process [GB] (Linux ru_maxrss is in kB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6


_TICK = os.sysconf("SC_CLK_TCK")


def _children(pid) -> list[int]:
    try:
        out = []
        for task in pathlib.Path(f"/proc/{pid}/task").iterdir():
            out += [int(x) for x in (task / "children").read_text().split()]
        return out
    except OSError:
        return []


def process_tree(pid) -> list[int]:
    """pid and all its descendants (alive now)."""
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        todo += _children(p)
    return out


def tree_cpu_seconds(pids, root) -> float:
    """user + system seconds of ``pids`` plus the waited-for children of ``root`` (/proc/<pid>/stat)."""
    total = 0.0
    for p in pids:
        try:
            fields = pathlib.Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        total += int(fields[11]) + int(fields[12])            # utime, stime
        if p == root:
            total += int(fields[13]) + int(fields[14])        # cutime, cstime
    return total / _TICK


def pss_gb(pids) -> float:
    """Proportional set size of ``pids`` [GB] (/proc/<pid>/smaps_rollup)."""
    total = 0
    for p in pids:
        try:
            for line in pathlib.Path(f"/proc/{p}/smaps_rollup").read_text().splitlines():
                if line.startswith("Pss:"):
                    total += int(line.split()[1])
                    break
        except OSError:
            continue
    return total / 1024 ** 2


def tree_pss_gb(pid) -> float | None:
    """PSS of the tree of ``pid`` [GB]; None when a process started or ended while the files were
    read (a fork between two reads counts the shared pages once in full and again in shares)."""
    pids = process_tree(pid)
    value = pss_gb(pids)
    return value if set(process_tree(pid)) == set(pids) else None


def write_results(name: str, data=None, markdown: str | list | None = None, default=float,
                  indent: int = 1) -> pathlib.Path:
    """Write results/<name>.json (``data``; ``default`` for what JSON cannot hold) and/or
    results/<name>.md (``markdown``: text or a list of lines); returns the last path written."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = None
    if data is not None:
        path = RESULTS / f"{name}.json"
        path.write_text(json.dumps(data, indent=indent, default=default))
    if markdown is not None:
        path = RESULTS / f"{name}.md"
        path.write_text(markdown if isinstance(markdown, str) else "\n".join(markdown) + "\n")
    return path


def read_results(name: str, default=None):
    """The data of results/<name>.json, or ``default`` when there is none yet."""
    path = RESULTS / f"{name}.json"
    return json.loads(path.read_text()) if path.is_file() else default


def read_case(path) -> dict:
    """A case file (relative to the repository or absolute) as a plain dict (YAML)."""
    path = pathlib.Path(path)
    return yaml.safe_load((path if path.is_absolute() else ROOT / path).read_text())


def write_case(data: dict, beside, directory=None) -> pathlib.Path:
    """Write the case ``data`` as YAML into a new file next to the case file ``beside`` (or into
    ``directory``), so that its relative paths still resolve; the caller removes it."""
    beside = pathlib.Path(beside)
    folder = pathlib.Path(directory) if directory is not None else \
        (beside if beside.is_absolute() else ROOT / beside).parent
    handle, path = tempfile.mkstemp(suffix=".yaml", prefix=".bench-", dir=folder)
    os.close(handle)
    pathlib.Path(path).write_text(yaml.safe_dump(data))
    return pathlib.Path(path)
