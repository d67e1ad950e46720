"""Fixtures for batch tests: the stand-in pipeline (tests/batch/batch_fake_pipeline.py) and a
shared two-worker LocalCluster."""
import os
import pathlib
import sys

import pytest

HERE = pathlib.Path(__file__).resolve().parent
if str(HERE) not in sys.path:  # importable by name here and (via spawn's sys.path) in Dask workers
    sys.path.insert(0, str(HERE))

FAKE = "batch_fake_pipeline"


@pytest.fixture(scope="session")
def fake_log_file(tmp_path_factory):
    """One line per build/solve call of the fake pipeline, also from worker processes (which
    inherit ``BATCH_FAKE_LOG`` when they start, hence session scope)."""
    path = tmp_path_factory.mktemp("fake") / "calls.log"
    path.touch()
    os.environ["BATCH_FAKE_LOG"] = str(path)
    yield path
    os.environ.pop("BATCH_FAKE_LOG", None)


@pytest.fixture
def fake_log(fake_log_file):
    """count(what) → calls of 'build' / 'solve' since this test started."""
    def lines():
        return fake_log_file.read_text().splitlines()
    start = len(lines())

    def count(what):
        return sum(1 for line in lines()[start:] if line.split()[0] == what)
    return count


@pytest.fixture(scope="session")
def dask_client(fake_log_file):
    """One two-worker LocalCluster for all batch tests (starting one costs seconds)."""
    distributed = pytest.importorskip("distributed")
    from sarfe.batch.runner import _local_client

    client, cluster = _local_client(2)
    yield client
    client.close()
    cluster.close()
    del distributed


@pytest.fixture
def no_batch_plots(monkeypatch):
    """The batch report without its PNGs, for tests that assert the table, the summary, the gate
    or the run bookkeeping (not the plots): matplotlib's layout and PNG encoding cost 0.2 s a
    figure, up to five figures a report, seconds a test. The plots themselves are asserted by
    test_lumped_study.py::test_table_outputs and test_report_confidence.py."""
    import sarfe.batch.batch_report as batch_report

    monkeypatch.setattr(batch_report, "_plots", lambda levels, output: [])
