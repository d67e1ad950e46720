"""Batch runner on the stand-in pipeline (tests/batch/batch_fake_pipeline.py): linear stage once per
linear model (counted in the worker processes too), failures isolated, the CI gate, resume after
SIGKILL, a dying worker retried. The same study on the real pipeline: test_lumped_study.py."""
import argparse
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import pandas as pd
import pytest

from sarfe.batch import GATE_EXIT_CODE, run_study
from sarfe.batch.cli import main, register

HERE = pathlib.Path(__file__).resolve().parent
FAKE = "batch_fake_pipeline"   # tests/batch/batch_fake_pipeline.py, on sys.path (conftest.py)
# none of these tests asserts the report's plots (conftest.py: no_batch_plots)
pytestmark = pytest.mark.usefixtures("no_batch_plots")


def study(tmp_path, variations, extra=""):
    (tmp_path / "case.yaml").write_text((HERE / "fake_case.yaml").read_text())
    path = tmp_path / "study.yaml"
    path.write_text(f"name: t\nbase_case: case.yaml\n{extra}variations:\n{variations}")
    return path


def test_linear_stage_once_per_linear_model_and_cached(tmp_path, fake_log, dask_client):
    path = study(tmp_path, """  grid:
    model.stiffness_N_m: [3.0e+4, 4.0e+4]
    contacts[0].gap_m: [1.0e-4, 2.0e-4, 4.0e-4]
    contacts[*].friction_coefficient: [0.2, 0.4]
""")
    table = run_study(path, client=dask_client, output_dir=tmp_path / "out", pipeline=FAKE)
    run = table.attrs["summary"]["run"]
    assert fake_log("build") == 2 and fake_log("solve") == 12
    assert run["linear_models"] == 2 and run["linear_stages_built"] == 2
    assert len(list((tmp_path / "out" / ".cache").glob("*.npz"))) == 2
    # a widened study in the same folder: old variants skipped, stages read from the cache
    path.write_text(path.read_text().replace("[0.2, 0.4]", "[0.2, 0.4, 0.6]"))
    table = run_study(path, workers=0, output_dir=tmp_path / "out", pipeline=FAKE)
    run = table.attrs["summary"]["run"]
    assert (run["skipped"], run["solved"], run["linear_stages_built"], run["linear_stages_from_cache"]) == (12, 6, 0, 2)
    assert fake_log("build") == 2 and fake_log("solve") == 18 and table["variant_id"].nunique() == 18


FAILING = """  list:
    - {'contacts[0].gap_m': 1.0e-4}
    - {'contacts[0].gap_m': -1.0e-4}
    - {'contacts[0].gap_m': 2.0e-4, fail: solver blew up}
    - {'contacts[0].gap_m': 3.0e-4, 'model.mass_kg': not-a-number}
    - {'contacts[0].gap_m': 4.0e-4}
"""


@pytest.mark.parametrize("mode", ["in-process", "dask"])
def test_failing_variants_are_recorded_and_others_finish(tmp_path, fake_log, mode, dask_client):
    kwargs = {"workers": 0} if mode == "in-process" else {"client": dask_client}
    table = run_study(study(tmp_path, FAILING), output_dir=tmp_path / "out", pipeline=FAKE, **kwargs)
    status = table.groupby("variant_index")["status"].first().tolist()
    errors = table.groupby("variant_index")["error"].first().tolist()
    assert status == ["ok", "failed", "failed", "failed", "ok"]
    assert "gap_m" in errors[1] and "must be >= 0" in errors[1]               # CaseError from load_case
    assert errors[2] == "RuntimeError: solver blew up"                        # exception in the solve
    assert errors[3].startswith("linear model: TypeError")                    # linear stage failed
    summary = table.attrs["summary"]
    assert summary["failed"] == 3 and len(summary["failures"]) == 3
    assert (table[table.status == "ok"].groupby("variant_index").size() == 3).all()
    if mode == "in-process":  # the CLI on the finished folder: exit 5, failures listed
        assert main(["--workers", "0", "--output", str(tmp_path / "out"), str(tmp_path / "study.yaml")]) == 5


def cli(capsys, *argv):
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_gate_exit_code_and_message(tmp_path, fake_log, capsys):
    path = study(tmp_path, """  list:
    - {'contacts[0].gap_m': 1.0e-3, 'contacts[1].gap_m': 1.0e-3}
    - {'contacts[0].gap_m': 1.0e-4}
    - {'contacts[0].gap_m': 1.0e-3, 'contacts[1].gap_m': 2.0e-3, nonconverged: true}
""")
    out = tmp_path / "out"
    table = run_study(path, workers=0, output_dir=out, pipeline=FAKE)  # the CLI runs below resume it
    levels = table.groupby("variant_index")["erp_db"].max().tolist()
    assert levels[0] < levels[1]
    threshold = 0.5 * (levels[0] + levels[1])
    ids = table.groupby("variant_index")["variant_id"].first().tolist()

    code, stdout, stderr = cli(capsys, "--workers", 0, "--output", out, "--fail-above-db", threshold, path)
    assert code == GATE_EXIT_CODE == 4
    assert "gate failed: 2 of 3 variants" in stderr
    lines = {line.split()[0]: line for line in stderr.splitlines()[1:]}
    assert set(lines) == {ids[1], ids[2]}
    assert f"> {threshold:g} dB" in lines[ids[1]] and "contacts[0].gap_m=0.0001" in lines[ids[1]]
    assert "did not converge" in lines[ids[2]]
    assert "3 variants" in stdout and "(3 from an earlier run)" in stdout

    code, stdout, stderr = cli(capsys, "--workers", 0, "--output", out, "--fail-above-db", threshold,
                               "--allow-nonconverged", path)
    assert code == 4 and ids[2] not in stderr and ids[1] in stderr
    code, stdout, _ = cli(capsys, "--workers", 0, "--output", out, "--fail-above-db", max(levels) + 1,
                          "--allow-nonconverged", path)
    assert code == 0 and "gate passed" in stdout
    assert cli(capsys, "--workers", 0, "--output", out, path)[0] == 3  # no gate: non-converged → 3
    assert cli(capsys, "--workers", 0, "--output", out, "--allow-nonconverged", path)[0] == 0


def test_cli_bad_study_is_exit_2_and_register_adds_subcommand(tmp_path, capsys):
    bad = study(tmp_path, "  grid: {'contacts[0].gap_m': [1]}\n", extra="sampels: 3\n")
    code, _, stderr = cli(capsys, "--workers", 0, bad)
    assert code == 2 and "unknown key" in stderr and "sampels" in stderr
    parser = argparse.ArgumentParser(prog="sarfe")
    register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["batch", "s.yaml", "--workers", "0", "--fail-above-db", "60"])
    assert args.func is args.handler and args.fail_above_db == 60.0 and args.inputs == ["s.yaml"]


def test_variant_outputs_only_on_request(tmp_path, fake_log):
    path = study(tmp_path, "  list: [{'contacts[0].gap_m': 1.0e-4}, {'contacts[0].gap_m': 2.0e-4}]\n")
    run_study(path, workers=0, output_dir=tmp_path / "a", pipeline=FAKE)
    assert not (tmp_path / "a" / "variant_outputs").exists()
    table = run_study(path, workers=0, output_dir=tmp_path / "b", pipeline=FAKE, write_variant_outputs=True)
    for variant_id in table["variant_id"].unique():
        assert (tmp_path / "b" / "variant_outputs" / variant_id / "summary.json").is_file()


KILL_SCRIPT = """
import sys
sys.path.insert(0, {here!r})
from sarfe.batch import run_study
run_study({study!r}, workers={workers}, output_dir={out!r}, pipeline={fake!r})
"""


@pytest.mark.parametrize("workers", [0, pytest.param(2, marks=pytest.mark.slow)])
def test_sigkill_midway_then_resume_loses_and_duplicates_nothing(tmp_path, fake_log, workers):
    n = 10
    path = study(tmp_path, f"""  monte_carlo:
    samples: {n}
    seed: 3
    parameters:
      contacts[0].gap_m: {{distribution: uniform, low: 0.0, high: 1.0e-3}}
""", extra="overrides: {sleep_s: 0.4}\n")
    out = tmp_path / "out"
    script = KILL_SCRIPT.format(here=str(HERE), study=str(path), workers=workers, out=str(out), fake=FAKE)
    process = subprocess.Popen([sys.executable, "-c", script], env=dict(os.environ))
    k = 3
    deadline = time.monotonic() + 120
    while len(list((out / "variants").glob("v*.json"))) < k:
        assert process.poll() is None, "batch ended before it could be killed"
        assert time.monotonic() < deadline
        time.sleep(0.05)
    process.send_signal(signal.SIGKILL)
    process.wait()
    finished = {p.stem for p in (out / "variants").glob("v*.json")}
    assert k <= len(finished) < n
    assert not list((out / "variants").glob("*.tmp"))  # (a temp file left by the kill would be ignored)
    solved_before = fake_log("solve")

    table = run_study(path, workers=0, output_dir=out, pipeline=FAKE)
    run = table.attrs["summary"]["run"]
    assert run["skipped"] == len(finished) and run["solved"] == n - len(finished)
    assert fake_log("solve") - solved_before == n - len(finished)       # finished ones not redone
    assert solved_before - len(finished) <= max(workers, 1)              # only in-flight ones lost
    assert table["variant_id"].nunique() == n and len(table) == 3 * n    # none lost, none duplicated
    assert (table.groupby("variant_id").size() == 3).all() and set(table.status) == {"ok"}


def test_worker_dying_midway_is_retried(tmp_path, fake_log, dask_client):
    marker = tmp_path / "died-once"
    path = study(tmp_path, f"""  list:
    - {{'contacts[0].gap_m': 1.0e-4}}
    - {{'contacts[0].gap_m': 2.0e-4, die_once: {str(marker)!r}}}
    - {{'contacts[0].gap_m': 3.0e-4}}
""")
    table = run_study(path, client=dask_client, output_dir=tmp_path / "out", pipeline=FAKE)
    assert marker.exists()  # the worker did die
    assert set(table["status"]) == {"ok"} and table["variant_id"].nunique() == 3


def test_existing_scheduler_by_address(tmp_path, fake_log, dask_client):
    path = study(tmp_path, "  grid: {'contacts[0].gap_m': [1.0e-4, 2.0e-4, 3.0e-4]}\n")
    table = run_study(path, scheduler=dask_client.scheduler.address, output_dir=tmp_path / "out", pipeline=FAKE)
    assert table.attrs["summary"]["run"]["mode"] == "dask" and set(table["status"]) == {"ok"}
    assert fake_log("build") == 1 and fake_log("solve") == 3


def test_cluster_failures_are_run_again_but_variant_failures_are_not(tmp_path, fake_log):
    from sarfe.batch.runner import failed_record
    from sarfe.batch.store import write_record
    from sarfe.batch.variants import collect_variants

    path = study(tmp_path, "  grid: {'contacts[0].gap_m': [1.0e-4, 2.0e-4, 3.0e-4]}\n")
    first, second, third = collect_variants(path)
    out = tmp_path / "out"
    write_record(out, failed_record(first, "worker: KilledWorker: …", transient=True))
    write_record(out, failed_record(second, "RuntimeError: boom"))
    table = run_study(path, workers=0, output_dir=out, pipeline=FAKE)
    status = table.groupby("variant_id")["status"].first()
    assert (status[first.id], status[second.id], status[third.id]) == ("ok", "failed", "ok")
    assert fake_log("solve") == 2
