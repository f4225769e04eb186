"""How the tables of recording folders are stored: CSV text (plain or gzip-compressed) and an optional Parquet twin.

The CSV is the contract. Every value is written so that reading it back gives the same float64 (``%.17g``,
a round trip), except columns given a stored *resolution* (decimal places of their SI unit: the truth's
position, velocity and attitude, whose last digits are far below any simulated effect; see
:data:`nav.recording.TRUTH_RESOLUTION`). Compression is gzip (readable by numpy, pandas, R and ``zcat``) written
with a zero timestamp, so the same table always gives the same bytes and the same hash.

A Parquet twin (``imu.parquet`` beside ``imu.csv.gz``, optional, needs pyarrow) holds the values of the CSV as
read back from it, and the SHA-256 of the CSV file it twins in its key-value metadata
(:data:`TWIN_HASH_KEY`); a reader uses a twin only when that hash is the CSV's.
"""

from __future__ import annotations

import gzip
import hashlib
import multiprocessing
import os
import warnings
import zlib
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from itertools import chain, islice
from pathlib import Path

import numpy as np

FORMS = ("csv.gz", "csv")  # a table NAME is stored as NAME.csv.gz or NAME.csv
DEFAULT_FORM = "csv.gz"
GZIP_LEVEL = 1  # the fastest level: 14.1 MB for a 100 m truth table against 12.9 MB at level 6, in a third of the time
MAX_FORMAT_WORKERS = 4  # one process compresses (gzip level 1) about as fast as two format exact text
TEXT_BLOCK_ROWS = 8192  # rows formatted at a time; a written .gz table compresses each block while the next is formatted
EXACT_FORMAT = "%.17g"  # float64 -> text -> the same float64
TWIN_SUFFIX = ".parquet"
TWIN_HASH_KEY = b"gaitsim.csv_sha256"
PARQUET_EXTRA = "pip install 'gaitsim[parquet]' (pyarrow)"


def check_form(form: str) -> str:
    """``form`` if it is one of :data:`FORMS`; else ValueError naming the value and the allowed forms."""
    if form not in FORMS:
        raise ValueError(f"table form {form!r} is not allowed; allowed: {', '.join(FORMS)}")
    return form


def column_formats(header: tuple[str, ...], resolution: dict[str, int] | None = None) -> list[str]:
    """printf formats of the columns: ``%.{n}f`` for a column whose name before ``_`` is a key of
    ``resolution`` (``{"pos": 9}``: pos_x, pos_y, pos_z to 1e-9 of their unit), else :data:`EXACT_FORMAT`."""
    resolution = resolution or {}
    return [f"%.{resolution[name.split('_')[0]]}f" if name.split("_")[0] in resolution else EXACT_FORMAT
            for name in header]


def _block_jobs(header: tuple[str, ...], table: np.ndarray, resolution: dict[str, int] | None) -> list[tuple]:
    """(row format, rows) pairs of a table's :data:`TEXT_BLOCK_ROWS`-row blocks."""
    table = np.asarray(table, float).reshape(-1, len(header))
    row = ",".join(column_formats(header, resolution)) + "\n"
    return [(row, table[start:start + TEXT_BLOCK_ROWS]) for start in range(0, len(table), TEXT_BLOCK_ROWS)]


def _block_text(job: tuple) -> str:
    """The CSV text of one block: a (row format, rows) pair of :func:`_block_jobs`."""
    row, block = job
    return (row * len(block)) % tuple(block.ravel().tolist())


def _block_bytes(job: tuple) -> bytes:
    """:func:`_block_text` encoded (ASCII), as written."""
    return _block_text(job).encode()


def table_blocks(header: tuple[str, ...], table: np.ndarray, resolution: dict[str, int] | None = None) -> Iterator[str]:
    """The CSV text of a table in blocks: the header row of column names, then :data:`TEXT_BLOCK_ROWS` rows
    (one per sample) at a time."""
    yield ",".join(header) + "\n"
    yield from map(_block_text, _block_jobs(header, table, resolution))


def table_text(header: tuple[str, ...], table: np.ndarray, resolution: dict[str, int] | None = None) -> str:
    """The CSV text of a table: a header row of column names, then one row per sample."""
    return "".join(table_blocks(header, table, resolution))


def write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path``, gzip-compressed (deterministic bytes) when the name ends in ``.gz``."""
    data = text.encode()
    if Path(path).suffix == ".gz":
        data = gzip.compress(data, compresslevel=GZIP_LEVEL, mtime=0)
    Path(path).write_bytes(data)


def write_table(path: Path, header: tuple[str, ...], table: np.ndarray, resolution: dict[str, int] | None = None) -> str:
    """Write the CSV text of a table (:func:`table_text`) to ``path``: the bytes of :func:`write_text` (see
    :func:`write_tables`); returns the file's SHA-256 (hex)."""
    return write_tables([(path, header, table, resolution)])[0]


def write_tables(tables: list[tuple], workers: int = 1) -> list[str]:
    """Write tables, each given as the arguments of :func:`write_table` (path, header, table, resolution), with
    the bytes of :func:`write_text`; returns each file's SHA-256 (hex), taken from the bytes as they are written.

    A ``.gz`` table is compressed block by block in a second thread while the next block is formatted (zlib
    releases the GIL; one gzip stream with a zero timestamp, as ``gzip.compress(..., mtime=0)`` writes it).
    With ``workers`` > 1 the blocks of all the tables are formatted by that many forked processes (formatting
    exact text holds the GIL: it is most of the time) while this process compresses and writes them in order;
    one process formats them where fork is not available or this process is itself a pool's worker.
    """
    jobs = [_block_jobs(header, table, resolution) for _path, header, table, resolution in tables]
    every_job = [job for table_jobs in jobs for job in table_jobs]
    pool = _fork_pool(min(workers, len(every_job)), every_job)
    try:
        blocks = pool.imap(_forked_block_bytes, range(len(every_job))) if pool else map(_block_bytes, every_job)
        return [_write_blocks(path, chain([(",".join(header) + "\n").encode()], islice(blocks, len(table_jobs))))
                for (path, header, _table, _resolution), table_jobs in zip(tables, jobs)]
    finally:
        if pool:
            pool.terminate()


def format_workers() -> int:
    """Worker processes worth forking to format text (:func:`write_tables`): one per core this process may run
    on, at most :data:`MAX_FORMAT_WORKERS`."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    return min(cores, MAX_FORMAT_WORKERS)


def _fork_pool(workers: int, jobs: list):
    """A pool of ``workers`` forked processes that hold ``jobs`` (inherited, not pickled: a worker is sent job
    numbers), or None (one worker, no fork, or a daemonic pool worker)."""
    if workers < 2 or "fork" not in multiprocessing.get_all_start_methods() or \
            multiprocessing.current_process().daemon:
        return None
    return multiprocessing.get_context("fork").Pool(workers, initializer=_hold_jobs, initargs=(jobs,))


_worker_jobs: list = []  # in a forked worker: the jobs of write_tables


def _hold_jobs(jobs: list) -> None:
    _worker_jobs[:] = jobs


def _forked_block_bytes(number: int) -> bytes:
    """:func:`_block_bytes` of job ``number`` held by this worker."""
    return _block_bytes(_worker_jobs[number])


def _write_blocks(path: Path, blocks) -> str:
    """Write ``blocks`` (an iterable of bytes) to ``path``, gzip-compressed in a second thread for ``.gz``;
    returns the SHA-256 (hex) of the bytes written."""
    digest = hashlib.sha256()
    with open(path, "wb") as fh:
        def write(data: bytes) -> None:
            fh.write(data)
            digest.update(data)

        if Path(path).suffix != ".gz":
            for block in blocks:
                write(block)
            return digest.hexdigest()
        compressor = zlib.compressobj(GZIP_LEVEL, zlib.DEFLATED, 16 + zlib.MAX_WBITS)  # 16+: gzip container
        with ThreadPoolExecutor(max_workers=1) as pool:
            pending = None
            for block in blocks:  # takes the next block while the pending one is compressed
                if pending is not None:
                    write(pending.result())
                pending = pool.submit(compressor.compress, block)
            if pending is not None:
                write(pending.result())
        write(compressor.flush())
    return digest.hexdigest()


def open_text(path: Path):
    """A text handle on a plain or gzip-compressed (``.gz``) file."""
    return gzip.open(path, "rt") if Path(path).suffix == ".gz" else open(path)


def sha256(path: Path) -> str:
    """Hex SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _pyarrow():
    try:
        import pyarrow
        import pyarrow.parquet
    except ImportError:
        return None
    return pyarrow


def require_pyarrow() -> None:
    """Raise ImportError naming the extra to install when pyarrow (Parquet twins) is missing."""
    if _pyarrow() is None:
        raise ImportError(f"a Parquet twin needs pyarrow: {PARQUET_EXTRA}")


def twin_path(csv_path: Path) -> Path:
    """``imu.parquet`` for ``imu.csv`` or ``imu.csv.gz``."""
    name = Path(csv_path).name
    return Path(csv_path).with_name(name[: name.index(".csv")] + TWIN_SUFFIX)


def write_twin(csv_path: Path, header: tuple[str, ...], table: np.ndarray) -> Path:
    """Write the Parquet twin of the CSV file ``csv_path``, whose values are ``table`` (as read back from it).

    Raises
    ------
    ImportError
        naming the extra to install when pyarrow is missing.
    """
    require_pyarrow()
    pa = _pyarrow()
    columns = {name: pa.array(np.ascontiguousarray(table[:, i])) for i, name in enumerate(header)}
    arrow = pa.table(columns).replace_schema_metadata({TWIN_HASH_KEY: sha256(csv_path).encode()})
    path = twin_path(csv_path)
    pa.parquet.write_table(arrow, path, compression="zstd", use_byte_stream_split=True)
    return path


def read_twin(csv_path: Path, header: tuple[str, ...], category: type[Warning] = UserWarning) -> np.ndarray | None:
    """The table of the Parquet twin of ``csv_path``; None when there is no twin or pyarrow is missing, and None
    with a warning of ``category`` saying why when the twin is unreadable, its columns are not ``header`` or it
    does not carry the SHA-256 of the CSV as it is now (the CSV is the reference)."""
    path = twin_path(csv_path)
    pa = _pyarrow()
    if pa is None or not path.exists():
        return None
    try:
        arrow = pa.parquet.read_table(path)
    except Exception as exc:  # any unreadable twin (truncated, not Parquet) falls back to the CSV
        warnings.warn(f"{path}: unreadable binary twin ({type(exc).__name__}: {exc}); reading "
                      f"{Path(csv_path).name}", category, stacklevel=3)
        return None
    recorded = (arrow.schema.metadata or {}).get(TWIN_HASH_KEY, b"").decode()
    if tuple(arrow.column_names) != tuple(header) or recorded != sha256(csv_path):
        warnings.warn(f"{path}: ignored: it does not carry the current digest of {Path(csv_path).name} (columns "
                      f"{arrow.column_names}, recorded CSV SHA-256 {recorded[:12] or 'none'}); reading the CSV",
                      category, stacklevel=3)
        return None
    return np.column_stack([arrow.column(name).to_numpy() for name in header]).astype(float)


def add_arguments(parser) -> None:
    """``--format`` and ``--parquet`` on an argparse parser: how a command stores the tables it writes."""
    parser.add_argument("--format", choices=FORMS, default=DEFAULT_FORM,
                        help="table files: gzip-compressed CSV (default) or plain CSV")
    parser.add_argument("--parquet", action="store_true",
                        help=f"also write a Parquet twin of every table, for speed ({PARQUET_EXTRA})")
