"""pypardiso is pointed at MKL's runtime once, from the wheel's metadata; a user's path is kept."""
import os
import pathlib

import pytest

from sarfe import linalg as linear_solvers


def test_mkl_runtime_found_from_metadata_or_left_to_pypardiso(monkeypatch):
    pytest.importorskip("pypardiso")
    monkeypatch.delenv("PYPARDISO_MKL_RT", raising=False)
    linear_solvers._locate_mkl_runtime.cache_clear()
    linear_solvers._locate_mkl_runtime()
    path = os.environ.get("PYPARDISO_MKL_RT")
    if path is not None:           # the pip mkl wheel: a real shared library
        assert pathlib.Path(path).is_file() and "mkl_rt" in pathlib.Path(path).name


def test_user_mkl_runtime_path_is_kept(monkeypatch):
    monkeypatch.setenv("PYPARDISO_MKL_RT", "/opt/custom/libmkl_rt.so")
    linear_solvers._locate_mkl_runtime.cache_clear()
    linear_solvers._locate_mkl_runtime()
    assert os.environ["PYPARDISO_MKL_RT"] == "/opt/custom/libmkl_rt.so"
    linear_solvers._locate_mkl_runtime.cache_clear()
