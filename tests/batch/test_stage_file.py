"""Linear stages cached by `sarfe batch` are data files (npz + manifest + SHA-256), never pickles:
a file a user places in <output>/.cache can be rejected, never run."""
import io
import json
import pickle
import zipfile
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from sarfe.batch import store
from sarfe.batch.stage_file import StageFileError, load_stage_file, stage_bytes
from sarfe.pipeline import build_linear_model, load_case

ROOT = Path(__file__).resolve().parents[2]


def assert_same(a, b):
    """Equal trees: arrays bit for bit (a file round trip, no arithmetic), sparse by content."""
    import dataclasses

    if dataclasses.is_dataclass(a):
        assert type(a) is type(b)
        for f in dataclasses.fields(a):
            assert_same(getattr(a, f.name), getattr(b, f.name))
    elif isinstance(a, dict):
        assert list(a) == list(b)
        for k in a:
            assert_same(a[k], b[k])
    elif isinstance(a, (list, tuple)):
        assert type(a) is type(b) and len(a) == len(b)
        for x, y in zip(a, b):
            assert_same(x, y)
    elif sp.issparse(a):
        assert sp.issparse(b) and (a != b).nnz == 0 and a.shape == b.shape
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    elif isinstance(a, float) and np.isnan(a):
        assert np.isnan(b)
    else:
        assert a == b


@pytest.fixture(scope="module")
def fe_stage():
    """The squeak rig's linear stage (FE: mesh, Craig–Bampton model, contact geometry)."""
    return build_linear_model(load_case(ROOT / "cases" / "squeak_rig.yaml"))


def test_fe_stage_round_trip(tmp_path, fe_stage):
    store.save_stage(tmp_path, fe_stage.key, fe_stage)
    path = store.stage_cache_path(tmp_path, fe_stage.key)
    assert path.suffix == ".npz" and path.is_file()
    assert_same(fe_stage, store.load_stage(tmp_path, fe_stage.key))


def test_matrices_stage_with_sparse_round_trip(tmp_path):
    stage = build_linear_model(load_case(ROOT / "cases" / "lumped_rattle.yaml"))
    import dataclasses
    stage = dataclasses.replace(stage, stiffness=sp.csr_matrix(stage.stiffness),
                                info={"nan": float("nan"), "nested": [1, (2.0, "x")]})
    path = tmp_path / "s.npz"
    path.write_bytes(stage_bytes(stage, stage.key))
    assert_same(stage, load_stage_file(path, stage.key))


def test_placed_pickle_is_never_loaded(tmp_path, fe_stage):
    """A pickle under the name the cache used to read — and one renamed to .npz — runs nothing."""
    class Boom:
        def __reduce__(self):
            return (Path(tmp_path / "ran").touch, ())
    cache = tmp_path / ".cache"
    cache.mkdir()
    (cache / f"{fe_stage.key}.pkl").write_bytes(pickle.dumps(Boom()))
    (cache / f"{fe_stage.key}.npz").write_bytes(pickle.dumps(Boom()))
    assert store.load_stage(tmp_path, fe_stage.key) is None
    assert not (tmp_path / "ran").exists()


def _rewrite(path, change):
    with np.load(path) as archive:
        arrays = {k: archive[k] for k in archive.files}
    change(arrays)
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    path.write_bytes(buffer.getvalue())


def test_damaged_or_edited_files_are_rejected(tmp_path, fe_stage):
    path = tmp_path / "s.npz"
    data = stage_bytes(fe_stage, fe_stage.key)
    path.write_bytes(data[: len(data) // 2])                       # truncated
    with pytest.raises(StageFileError):
        load_stage_file(path, fe_stage.key)
    path.write_bytes(data)
    with pytest.raises(StageFileError, match="another|not the stage"):
        load_stage_file(path, "0" * 64)                            # another linear model

    def flip(arrays):                                              # one number changed
        arrays["a0"] = arrays["a0"].copy()
        arrays["a0"].flat[0] += 1.0
    _rewrite(path, flip)
    with pytest.raises(StageFileError, match="hash"):
        load_stage_file(path, fe_stage.key)


def test_foreign_class_rejected_even_with_a_matching_hash(tmp_path, fe_stage):
    """An attacker can recompute the hash; the manifest still may only name sarfe dataclasses."""
    from sarfe.batch.stage_file import _digest

    path = tmp_path / "s.npz"
    path.write_bytes(stage_bytes(fe_stage, fe_stage.key))

    def retarget(arrays):
        header = json.loads(arrays["__manifest__"].tobytes())
        header["tree"]["cls"] = "subprocess:Popen"
        manifest = json.dumps(header).encode()
        arrays["__manifest__"] = np.frombuffer(manifest, dtype=np.uint8)
        rest = {k: v for k, v in arrays.items() if not k.startswith("__")}
        arrays["__sha256__"] = np.frombuffer(_digest(manifest, rest).encode(), dtype=np.uint8)
    _rewrite(path, retarget)
    with pytest.raises(StageFileError, match="not sarfe's"):
        load_stage_file(path, fe_stage.key)
    with zipfile.ZipFile(path) as archive:   # and no entry needs pickle to be read
        assert all(name.endswith(".npy") for name in archive.namelist())
