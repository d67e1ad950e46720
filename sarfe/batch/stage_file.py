"""Linear stages on disk without pickle: a ``.npz`` of plain arrays plus a JSON manifest and a
content hash, so a file placed in ``<output>/.cache`` can at worst be rejected, never run code.

    save_stage_file(path, stage, key)      # atomic (temp file + rename)
    load_stage_file(path, key) -> stage    # StageFileError if damaged, foreign or for another key

The manifest describes the object tree: dataclasses (rebuilt only when the class is a dataclass of
``sarfe.*`` or of the pipeline module passed in), dicts, lists, tuples, numbers, strings, None,
numpy arrays (stored as npz entries, ``allow_pickle=False``) and SciPy sparse matrices (CSR parts).
The hash (SHA-256) covers the manifest and every array's dtype, shape and bytes.
"""
from __future__ import annotations

import dataclasses
import hashlib
import importlib
import io
import json
import math

import numpy as np
import scipy.sparse as sp

FORMAT = "sarfe-linear-stage/1"


class StageFileError(ValueError):
    """A stage file that is damaged, not sarfe's, or for another linear model."""


def _digest(manifest: bytes, arrays: dict) -> str:
    sha = hashlib.sha256(manifest)
    for name in sorted(arrays):
        array = np.ascontiguousarray(arrays[name])
        sha.update(f"{name}|{array.dtype.str}|{array.shape}|".encode())
        sha.update(array.tobytes())
    return sha.hexdigest()


def _encode(value, arrays: dict):
    def array(a):
        name = f"a{len(arrays)}"
        a = np.asarray(a)
        if a.dtype == object:
            raise TypeError("object arrays cannot be stored")
        arrays[name] = a
        return name

    if value is None or isinstance(value, (bool, str)):
        return {"t": "v", "v": value}
    if isinstance(value, (int, np.integer)):
        return {"t": "v", "v": int(value)}
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return {"t": "f", "v": v if math.isfinite(v) else repr(v)}
    if isinstance(value, np.ndarray):
        return {"t": "nd", "k": array(value)}
    if sp.issparse(value):
        csr = sp.csr_matrix(value)
        return {"t": "csr", "data": array(csr.data), "indices": array(csr.indices),
                "indptr": array(csr.indptr), "shape": list(csr.shape),
                "array": isinstance(value, sp.sparray) if hasattr(sp, "sparray") else False}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        cls = type(value)
        return {"t": "dc", "cls": f"{cls.__module__}:{cls.__qualname__}",
                "f": {f.name: _encode(getattr(value, f.name), arrays)
                      for f in dataclasses.fields(value)}}
    if isinstance(value, dict):
        return {"t": "dict", "items": [[_encode(k, arrays), _encode(v, arrays)]
                                       for k, v in value.items()]}
    if isinstance(value, (list, tuple)):
        return {"t": "list" if isinstance(value, list) else "tuple",
                "items": [_encode(v, arrays) for v in value]}
    raise TypeError(f"cannot store a {type(value).__name__} in a stage file")


def _class(name: str, modules: tuple):
    module, _, qualname = name.partition(":")
    if not (module == "sarfe" or module.startswith("sarfe.") or module in modules):
        raise StageFileError(f"class {name} is not sarfe's")
    obj = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    if not (isinstance(obj, type) and dataclasses.is_dataclass(obj)):
        raise StageFileError(f"{name} is not a dataclass")
    return obj


def _decode(node, arrays, modules):
    kind = node["t"]
    if kind == "v":
        return node["v"]
    if kind == "f":
        return float(node["v"])
    if kind == "nd":
        return arrays[node["k"]]
    if kind == "csr":
        parts = (arrays[node["data"]], arrays[node["indices"]], arrays[node["indptr"]])
        matrix = sp.csr_array if node.get("array") and hasattr(sp, "csr_array") else sp.csr_matrix
        return matrix(parts, shape=tuple(node["shape"]))
    if kind == "dict":
        return {_decode(k, arrays, modules): _decode(v, arrays, modules) for k, v in node["items"]}
    if kind in ("list", "tuple"):
        items = [_decode(v, arrays, modules) for v in node["items"]]
        return items if kind == "list" else tuple(items)
    if kind == "dc":
        cls = _class(node["cls"], modules)
        values = {name: _decode(v, arrays, modules) for name, v in node["f"].items()}
        fields = {f.name: f for f in dataclasses.fields(cls)}
        if set(values) != set(fields):
            raise StageFileError(f"fields of {node['cls']} differ from this sarfe version")
        obj = cls(**{k: v for k, v in values.items() if fields[k].init})
        for k, v in values.items():
            if not fields[k].init:
                object.__setattr__(obj, k, v)
        return obj
    raise StageFileError(f"unknown node type {kind!r}")


def stage_bytes(stage, key: str) -> bytes:
    """The ``.npz`` bytes of ``stage`` (manifest, hash and arrays)."""
    arrays: dict = {}
    tree = _encode(stage, arrays)
    manifest = json.dumps({"format": FORMAT, "key": key, "tree": tree}).encode()
    buffer = io.BytesIO()
    np.savez(buffer, __manifest__=np.frombuffer(manifest, dtype=np.uint8),
             __sha256__=np.frombuffer(_digest(manifest, arrays).encode(), dtype=np.uint8), **arrays)
    return buffer.getvalue()


def load_stage_file(path, key: str, modules=()):
    """The stage stored at ``path`` for linear-model ``key``; StageFileError when the file is
    not a sarfe stage file, its hash does not match its content, or it is for another key."""
    try:
        with np.load(path, allow_pickle=False) as archive:
            arrays = {name: archive[name] for name in archive.files}
    except Exception as exc:  # missing, truncated, not an npz, object arrays
        raise StageFileError(f"unreadable stage file {path}: {type(exc).__name__}: {exc}") from None
    try:
        manifest = arrays.pop("__manifest__").tobytes()
        stored = arrays.pop("__sha256__").tobytes().decode()
    except (KeyError, UnicodeDecodeError):
        raise StageFileError(f"{path} is not a sarfe stage file") from None
    if _digest(manifest, arrays) != stored:
        raise StageFileError(f"{path}: content hash does not match (damaged or edited)")
    try:
        header = json.loads(manifest)
    except ValueError:
        raise StageFileError(f"{path}: unreadable manifest") from None
    if header.get("format") != FORMAT or header.get("key") != key:
        raise StageFileError(f"{path} is not the stage of linear model {key[:16]}")
    try:
        return _decode(header["tree"], arrays, tuple(modules))
    except StageFileError:
        raise
    except Exception as exc:
        raise StageFileError(f"{path}: cannot rebuild the stage ({type(exc).__name__}: {exc})") from None


__all__ = ["FORMAT", "StageFileError", "load_stage_file", "stage_bytes"]
