"""Tables written block by block (formatting and compression overlapped) hold the bytes of the one-piece text."""

import gzip
import zlib

import numpy as np
import pytest

from nav import storage

HEADER = ("t", "pos_x", "acc_x")


@pytest.mark.parametrize("rows", [0, 1, storage.TEXT_BLOCK_ROWS, 2 * storage.TEXT_BLOCK_ROWS + 5])
@pytest.mark.parametrize("form", storage.FORMS)
def test_written_table_is_the_table_text(tmp_path, rows, form):
    table = np.random.default_rng(rows).normal(size=(rows, 3)) * [1.0, 100.0, 1e-7]
    path = tmp_path / f"table.{form}"
    digest = storage.write_table(path, HEADER, table, {"pos": 9})
    assert digest == storage.sha256(path)
    text = storage.table_text(HEADER, table, {"pos": 9})
    data = path.read_bytes()
    if form == "csv.gz":
        assert gzip.decompress(data).decode() == text
        assert data == zlib.compress(text.encode(), storage.GZIP_LEVEL, 16 + zlib.MAX_WBITS)  # one stream, mtime 0
    else:
        assert data.decode() == text
    assert text.count("\n") == rows + 1


@pytest.mark.parametrize("form", storage.FORMS)
def test_tables_formatted_by_forked_workers_have_the_same_bytes(tmp_path, form):
    rng = np.random.default_rng(5)
    tables = [rng.normal(size=(rows, 3)) * [1.0, 100.0, 1e-7] for rows in (3 * storage.TEXT_BLOCK_ROWS + 7, 0, 11)]
    written = {}
    for workers in (1, 2, 3):
        paths = [tmp_path / f"w{workers}-{i}.{form}" for i in range(len(tables))]
        storage.write_tables([(path, HEADER, table, {"pos": 9}) for path, table in zip(paths, tables)], workers)
        written[workers] = [path.read_bytes() for path in paths]
    assert written[1] == written[2] == written[3]
    text = storage.table_text(HEADER, tables[0], {"pos": 9})
    assert (gzip.decompress(written[2][0]) if form == "csv.gz" else written[2][0]).decode() == text
