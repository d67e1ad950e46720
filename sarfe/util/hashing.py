"""SHA-256 digests, the one place sarfe hashes: keys of cached or reusable results (the linear
stage's key, the mesh cache, batch variant ids) and checksums of files and stage files.

    sha256_hex(*chunks, length=None) -> str     chunks in order (bytes, or str as UTF-8)
    file_sha256(path) -> str                    a file's bytes, read in 1 MiB blocks

Both return lower-case hex digits (64, or the first ``length``).
"""
from __future__ import annotations

import hashlib

BLOCK_BYTES = 1 << 20       # a file is hashed in blocks of this many bytes (constant memory)


def sha256_hex(*chunks, length: int | None = None) -> str:
    """Hex SHA-256 of ``chunks`` fed in order — each ``bytes`` (or any buffer) as it is, each
    ``str`` encoded as UTF-8 — so ``sha256_hex(a, b) == sha256_hex(a + b)``; the first
    ``length`` hex digits when given (a short key), all 64 otherwise."""
    digest = hashlib.sha256()
    for chunk in chunks:
        digest.update(chunk.encode() if isinstance(chunk, str) else chunk)
    text = digest.hexdigest()
    return text if length is None else text[:length]


def file_sha256(path) -> str:
    """Hex SHA-256 (64 digits) of the bytes of the file at ``path``."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(BLOCK_BYTES), b""):
            digest.update(block)
    return digest.hexdigest()


__all__ = ["sha256_hex", "file_sha256"]
