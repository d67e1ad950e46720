"""Workers die with their parent, on SIGKILL too (issue 32, item 6; sarfe.util.parent_watch).

Before: SIGKILL of `sarfe solve` during a parallel stage left its 2 pool workers alive (150 MB
each, blocked on their task pipe, still there after 4 min), 5 times out of 5. Now the kernel's
parent-death signal (Linux) and a watchdog thread end every child within a few seconds: the
process-pool workers, the stream worker and the background worker of sarfe.util.workers, and the pyvista render child
of sarfe.results.render. (The Dask workers of `sarfe batch` already died with it, within 1 s.)
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import psutil
import pytest
from small_cases import coarse_rig

ROOT = Path(__file__).resolve().parents[2]
GONE_WITHIN_S = 5.0     # the watchdog polls every second; the kernel signal is immediate
ENV = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
           MKL_NUM_THREADS="1", MPLBACKEND="Agg")


def alive(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def wait_for_children(parent: subprocess.Popen, count: int, timeout_s: float = 120.0) -> list:
    """The pids of ``count`` children of ``parent`` once they all exist (each is then reaped or
    checked by the test)."""
    clock = time.monotonic()
    while time.monotonic() - clock < timeout_s:
        assert parent.poll() is None, parent.stderr.read() if parent.stderr else parent.returncode
        children = [c.pid for c in psutil.Process(parent.pid).children()]
        if len(children) >= count:
            return children
        time.sleep(0.05)
    pytest.fail(f"no {count} children after {timeout_s} s")


def kill_and_watch(parent: subprocess.Popen, children: list) -> float:
    """SIGKILL ``parent``; seconds until every child is gone (a zombie counts as gone), or fail
    after GONE_WITHIN_S (then the children are killed here, so that no test leaves one)."""
    parent.send_signal(signal.SIGKILL)
    parent.wait()
    clock = time.monotonic()
    while any(alive(pid) for pid in children):
        if time.monotonic() - clock > GONE_WITHIN_S:
            left = [pid for pid in children if alive(pid)]
            for pid in left:
                os.kill(pid, signal.SIGKILL)
            pytest.fail(f"children {left} outlived their parent by {GONE_WITHIN_S} s")
        time.sleep(0.05)
    return time.monotonic() - clock


BLOCKED_POOL = """
import time
from sarfe.util import workers

def forever(x):
    time.sleep(3600)

workers.map_points(forever, range(4), 2)
"""

BLOCKED_STREAM = """
import time
from sarfe.util import workers

def forever(x):
    time.sleep(3600)

with workers.Stream(forever) as stream:
    stream.submit(0, 0)
    time.sleep(3600)
"""


BLOCKED_BACKGROUND = """
import time
from sarfe.util import workers

def forever():
    time.sleep(3600)

background = workers.Background(forever, lambda state, message: state)
time.sleep(3600)
"""


@pytest.mark.parametrize("script", [BLOCKED_POOL, BLOCKED_STREAM, BLOCKED_BACKGROUND],
                         ids=["pool", "stream", "background"])
def test_pool_and_stream_workers_die_with_a_killed_parent(script):
    parent = subprocess.Popen([sys.executable, "-c", script], env=ENV, stderr=subprocess.PIPE)
    children = wait_for_children(parent, 2 if script is BLOCKED_POOL else 1, timeout_s=60)
    time.sleep(0.5)                      # the initializer has run
    assert kill_and_watch(parent, children) < GONE_WITHIN_S


WATCHDOG_ONLY = """
import sys, time
from sarfe.util import parent_watch
parent_watch._set_parent_death_signal = lambda signum: False     # as where there is no prctl
pid = __import__("os").fork()
if pid == 0:
    parent_watch.die_with_parent(int(sys.argv[1]), period_s=0.2)
    time.sleep(3600)
time.sleep(3600)
"""


def test_watchdog_alone_ends_the_child():
    """The portable guard (a thread polling os.getppid()) without the kernel's signal."""
    parent = subprocess.Popen([sys.executable, "-c", "import os, subprocess, sys; "
                               "exec(sys.argv[1].replace('int(sys.argv[1])', str(os.getpid())))",
                               WATCHDOG_ONLY], env=ENV)
    children = wait_for_children(parent, 1, timeout_s=60)
    time.sleep(0.5)
    assert kill_and_watch(parent, children) < 2.0


def test_render_child_dies_with_a_killed_solve(tmp_path):
    """The render child (python -m sarfe.results.render) blocked on its input (a FIFO that is
    never written) ends when the process that started it is killed."""
    fifo = tmp_path / "never.npz"
    os.mkfifo(fifo)
    script = textwrap.dedent(f"""
        import os, subprocess, sys, time
        from sarfe.results.render import PARENT_ENV
        env = dict(os.environ, **{{PARENT_ENV: str(os.getpid())}})
        subprocess.Popen([sys.executable, "-m", "sarfe.results.render", {str(fifo)!r}], env=env)
        time.sleep(3600)
    """)
    parent = subprocess.Popen([sys.executable, "-c", script], env=ENV)
    children = wait_for_children(parent, 1, timeout_s=60)
    time.sleep(2.0)                      # the child has imported sarfe and armed the watch
    assert kill_and_watch(parent, children) < GONE_WITHIN_S


FAST_RIG = coarse_rig([26, 28, 30, 32, 34, 36, 38, 40],
                      "{harmonics: 5, samples_per_period: 64, workers: 2}")


def test_a_killed_solve_leaves_no_worker(tmp_path):
    """`sarfe solve` with solver.workers: 2, killed with SIGKILL while its workers run: every
    child is gone within a few seconds (before: 2 workers alive after 4 min)."""
    case = tmp_path / "fast_rig.yaml"
    case.write_text(FAST_RIG)
    env = dict(ENV, SARFE_MESH_CACHE=str(tmp_path / "cache"))
    parent = subprocess.Popen([sys.executable, "-m", "sarfe", "solve", str(case), "--output",
                               str(tmp_path / "out"), "--quiet"], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    process = psutil.Process(parent.pid)
    clock = time.monotonic()
    children = []
    while time.monotonic() - clock < 240 and parent.poll() is None:
        forked = []
        for child in process.children():
            try:
                if child.cmdline() == process.cmdline():   # a fork of the solve: a worker
                    forked.append(child.pid)
            except psutil.Error:                           # ended meanwhile
                pass
        if len(forked) >= 2:
            children = forked
            break
        time.sleep(0.02)
    if not children:
        pytest.skip("the solve finished before its workers were seen")
    assert kill_and_watch(parent, children) < GONE_WITHIN_S
    assert not (tmp_path / "out").exists()
