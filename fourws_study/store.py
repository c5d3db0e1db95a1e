# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A study's output folder: blocks of results written as they finish, the merged table, and
what was run.

Layout of ``DIR``::

    study.yaml              the study file as given
    base_run_config.json    the resolved base run (RunConfig.to_dict(), versioned)
    versions.json           software versions
    manifest.json           study name, the hash that identifies it, points, block size
    blocks/block-000042.parquet   the rows of block 42 (points 42*B .. 42*B + B - 1)
    results.parquet         every finished row, sorted by point (written at the end, and
                            when the study is interrupted)

A block is written to a hidden temporary file and renamed into ``blocks/`` when complete
(an atomic step on POSIX file systems), so ``blocks/`` only ever holds complete blocks:
whatever kills the study, ``pyarrow.parquet.read_table("DIR/blocks")`` (or
:func:`read_results`) reads every point finished so far, and ``--resume`` runs exactly the
blocks that are not there (:meth:`StudyStore.missing_blocks`). All block files share one
schema (:func:`fourws_study.point.columns`).

A block file is checked whole before it counts: written with Parquet page checksums (CRC-32
of every data page) and a SHA-256 of its rows in the file's metadata (:data:`ROWS_DIGEST`:
the page headers, which no page checksum covers, say how many values a page holds), read
back with both verified, its columns those of the study and its points those of its block.
``--resume`` recomputes a block that fails (a flipped byte, a truncated or foreign file);
:func:`read_results` (the merge, ``fourws study report``, ``rerun``) refuses it in one line
naming the file and the ``--resume`` that recomputes it, and refuses any other file in
``blocks/`` (a stray file would also break
``read_table("DIR/blocks")``; names starting with ``.`` or ``_`` are ignored, as pyarrow
ignores them). A flipped byte in a block file is caught either way: in a data page by its
checksum, in the footer by the schema or as a file Parquet cannot read, anywhere else by the
rows' digest (flipping each of the 30 946 bytes of a block in turn: 3 flips in page headers
gave other rows with the page checksums alone, none with the digest).
"""

from __future__ import annotations

import hashlib
import json
import os
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any, Sequence

import pyarrow as pa
import pyarrow.parquet as pq

from fourws_run.config import software_versions
from fourws_sim.config_yaml import parse_yaml
from fourws_sim.errors import ParameterError
from fourws_study.point import columns
from fourws_study.spec import Study

BLOCKS = "blocks"
#: Schema metadata key of a block file: the SHA-256 of its rows (:func:`rows_digest`).
ROWS_DIGEST = b"fourws.rows_sha256"
RESULTS = "results.parquet"
MANIFEST = "manifest.json"
#: Layout version of the folder.
STORE_VERSION = 1

_TYPES = {"int64": pa.int64(), "float64": pa.float64(), "bool": pa.bool_(),
          "string": pa.string(), "list<float64>": pa.list_(pa.float64())}


def schema(study: Study) -> pa.Schema:
    """The Arrow schema of the study's result rows."""
    return pa.schema([(name, _TYPES[kind]) for name, kind in columns(study)])


def rows_to_table(rows: Sequence[dict[str, Any]], study_schema: pa.Schema) -> pa.Table:
    """Rows (mappings) as a table of ``study_schema`` (missing values are null)."""
    data = {f.name: [row.get(f.name) for row in rows] for f in study_schema}
    return pa.table(data, schema=study_schema)


def rows_digest(table: pa.Table) -> str:
    """SHA-256 of a table's rows, column by column in order (JSON of ``to_pylist``: floats
    exactly, as ``repr`` writes them)."""
    rows = json.dumps(table.to_pylist(), allow_nan=True, default=str)
    return hashlib.sha256(rows.encode()).hexdigest()


def study_hash(study: Study) -> str:
    """What identifies a study's results: its file's content without the parts that do not
    change a row (``description``, ``report``) and its resolved base run (a changed vehicle
    file changes the runs even when the study file did not)."""
    data = parse_yaml(study.text, study.source)
    if isinstance(data, dict):
        data = {k: v for k, v in data.items() if k not in ("description", "report")}
    base = study.base_config().to_dict()
    base.pop("versions", None)
    digest = hashlib.sha256()
    digest.update(json.dumps(data, sort_keys=True, default=str).encode())
    digest.update(json.dumps(base, sort_keys=True, default=str).encode())
    return digest.hexdigest()


def software_versions_all() -> dict[str, str]:
    """Versions of the software a study uses."""
    out = software_versions()
    for dist in ("numba", "scipy", "pyarrow", "dask", "distributed"):
        try:
            out[dist] = version(dist)
        except PackageNotFoundError:
            out[dist] = "not installed"
    return out


class StudyStore:
    """The output folder of one study (module docstring).

    Parameters
    ----------
    root : Path
        ``DIR``.
    study : Study
    block_size : int
        Points per block.
    """

    def __init__(self, root: Path, study: Study, block_size: int) -> None:
        self.root = Path(root)
        self.study = study
        self.block_size = int(block_size)
        self.schema = schema(study)
        self.hash = study_hash(study)

    # ---------------------------------------------------------------- blocks
    @property
    def n_blocks(self) -> int:
        """Blocks of the study."""
        return -(-self.study.n_points // self.block_size)

    def block_points(self, block: int) -> range:
        """Point numbers of ``block``."""
        start = block * self.block_size
        return range(start, min(start + self.block_size, self.study.n_points))

    def block_path(self, block: int) -> Path:
        """File of a finished block."""
        return self.root / BLOCKS / f"block-{block:06d}.parquet"

    def read_block(self, block: int) -> pa.Table:
        """The rows of a finished block, checked whole (module docstring).

        Raises
        ------
        ParameterError
            The file is missing, damaged, or not this block of this study (field
            ``<file>``, the file named, with the ``--resume`` that recomputes it).
        """
        path = self.block_path(block)
        again = (f"; `fourws study {self.study.source} --out {self.root} --resume` "
                 "recomputes it")
        try:
            table = pq.read_table(path, page_checksum_verification=True)
        except FileNotFoundError:
            raise ParameterError("<file>", f"missing (block {block} has not run){again}",
                                 str(path)) from None
        except (OSError, pa.ArrowException) as exc:
            problem = " ".join(str(exc).split())[:160]
            raise ParameterError("<file>", f"damaged Parquet block ({problem}){again}",
                                 str(path)) from None
        if not table.schema.equals(self.schema):
            raise ParameterError("<file>", f"not a block of this study (its columns differ)"
                                 f"{again}", str(path))
        digest = (table.schema.metadata or {}).get(ROWS_DIGEST)
        if digest is not None and digest.decode(errors="replace") != rows_digest(table):
            raise ParameterError("<file>", f"damaged Parquet block (its rows do not match the "
                                 f"checksum written with them){again}", str(path))
        if table.column("point").to_pylist() != list(self.block_points(block)):
            raise ParameterError("<file>", f"not block {block} of this study (other points)"
                                 f"{again}", str(path))
        return table.replace_schema_metadata(None)

    def _valid_block(self, block: int) -> bool:
        try:
            self.read_block(block)
        except ParameterError:
            return False
        return True

    def missing_blocks(self) -> list[int]:
        """Blocks with no complete, intact file (a resumed study runs these again)."""
        return [b for b in range(self.n_blocks) if not self._valid_block(b)]

    def check_strays(self) -> None:
        """Refuse a file in ``blocks/`` that is no block file of this study.

        Raises
        ------
        ParameterError
            Naming the first such file.
        """
        names = {self.block_path(b).name for b in range(self.n_blocks)}
        for path in sorted((self.root / BLOCKS).iterdir()):
            if path.name in names or path.name.startswith((".", "_")):
                continue
            raise ParameterError("<file>", f"is not a block of this study (its blocks are "
                                 f"{self.block_path(0).name} to "
                                 f"{self.block_path(self.n_blocks - 1).name}); move it out "
                                 f"of {self.root / BLOCKS}", str(path))

    def read_results(self) -> pa.Table:
        """Every finished row (the blocks that have a file), sorted by point.

        Raises
        ------
        ParameterError
            ``blocks/`` is missing or empty, holds a stray file (:meth:`check_strays`) or a
            damaged block (:meth:`read_block`).
        """
        blocks = self.root / BLOCKS
        if not blocks.is_dir():
            raise ParameterError("DIR", f"{self.root} is not a study folder (no {BLOCKS}/)")
        self.check_strays()
        done = [b for b in range(self.n_blocks) if self.block_path(b).exists()]
        if not done:
            raise ParameterError("DIR", f"{self.root} has no finished block yet")
        return pa.concat_tables([self.read_block(b) for b in done])

    def write_block(self, block: int, data: bytes) -> Path:
        """Write a finished block already encoded (:func:`encode_block`, done by the worker
        that ran it): a hidden temporary file, flushed to disk, then renamed into place."""
        path = self.block_path(block)
        tmp = path.with_name(f".{path.name}.tmp")
        with open(tmp, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
        return path

    # ---------------------------------------------------------------- folder
    def open(self, resume: bool) -> None:
        """Create the folder, or check it for ``resume``.

        Raises
        ------
        ParameterError
            The folder holds results and ``resume`` is not set, or it holds another study's
            (or an edited study's) results.
        """
        manifest = self.root / MANIFEST
        blocks = self.root / BLOCKS
        if manifest.is_file():
            try:
                old = json.loads(manifest.read_text())
            except json.JSONDecodeError:
                old = {}
            if not resume:
                raise ParameterError("--out", f"{self.root} already holds study results; "
                                     "give --resume to finish them or another --out")
            if old.get("hash") != self.hash or old.get("block_size") != self.block_size:
                raise ParameterError("--resume", f"{self.root} holds the results of "
                                     f"{old.get('study', 'another study')!r} with another "
                                     "study file, base run or block size; use another --out")
        elif resume and blocks.is_dir() and any(blocks.iterdir()):
            raise ParameterError("--resume", f"{self.root} has blocks but no {MANIFEST}; "
                                 "it is not a study folder")
        blocks.mkdir(parents=True, exist_ok=True)
        self.check_strays()
        (self.root / "study.yaml").write_text(self.study.text)
        (self.root / "base_run_config.json").write_text(
            json.dumps(self.study.base_config().to_dict(), indent=2, default=str))
        (self.root / "versions.json").write_text(json.dumps(software_versions_all(),
                                                            indent=2))
        manifest.write_text(json.dumps({
            "version": STORE_VERSION, "study": self.study.name, "source": self.study.source,
            "hash": self.hash, "points": self.study.n_points, "block_size": self.block_size,
            "blocks": self.n_blocks, "summary": self.study.to_summary()}, indent=2))

    def merge(self) -> tuple[Path, int]:
        """Write ``results.parquet`` from the finished blocks (sorted by point); returns the
        path and the number of rows."""
        table = self.read_results()
        path = self.root / RESULTS
        tmp = path.with_name(f".{path.name}.tmp")
        pq.write_table(table, tmp)
        os.replace(tmp, path)
        return path, table.num_rows


def encode_block(table: pa.Table, table_schema: pa.Schema) -> bytes:
    """A block's rows as the bytes of its Parquet file (cast to the study's schema)."""
    table = table.cast(table_schema)
    table = table.replace_schema_metadata({ROWS_DIGEST: rows_digest(table).encode()})
    sink = pa.BufferOutputStream()
    # page checksums and the rows' digest: a flipped byte is an error, never another number
    pq.write_table(table, sink, write_page_checksum=True)
    return sink.getvalue().to_pybytes()


def read_results(root: str | Path, study: Study) -> pa.Table:
    """Every finished row of ``study`` in its folder ``root`` (``blocks/``), sorted by point;
    works on a study that is still running or was killed.

    Raises
    ------
    ParameterError
        ``root`` is not a study folder, has no finished block, or holds a damaged block or a
        stray file (:meth:`StudyStore.read_results`).
    """
    return StudyStore(Path(root), study, study.block_size).read_results()


__all__ = ["BLOCKS", "MANIFEST", "RESULTS", "ROWS_DIGEST", "StudyStore", "encode_block",
           "read_results", "rows_digest", "rows_to_table", "schema", "software_versions_all",
           "study_hash"]
