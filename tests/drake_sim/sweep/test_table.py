import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.sweep import table as mut


def test_columns():
    assert mut.columns(["a.b"], ["m"]) == [
        "index", "status", "success", "seed", "a.b", "m", "wall_time_s", "worker", "reason",
    ]  # fmt: skip


def test_cells_round_trip():
    for value in (None, True, False, 3, 0.25, [0.5, 0.1], "physics", "ConfigError: x, y"):
        assert mut.parse_cell(mut.cell(value)) == value


def test_rows_are_saved_as_written_and_resumed(tmp_path):
    path = tmp_path / "out" / mut.TABLE_FILE
    header = mut.columns(["p"], ["m"])
    dut = mut.Table(path, header, resume=False)
    assert not path.exists()  # no header-only table: written with its first row
    dut.append({"index": 0, "status": "ok", "p": 1.5, "m": [1, 2], "reason": ""})
    # Saved: readable while the table is still open.
    assert mut.read_rows(path)[1][0]["m"] == [1, 2]
    dut.append({"index": 2, "status": "failed", "reason": "RuntimeError: boom, again"})
    dut.close()
    found_header, rows = mut.read_rows(path)
    assert found_header == header
    assert [r["index"] for r in rows] == [0, 2]
    assert rows[1]["reason"] == "RuntimeError: boom, again" and rows[1]["m"] is None
    again = mut.Table(path, header, resume=True)
    assert again.done == {0, 2}
    again.close()


def test_an_existing_table_is_never_overwritten(tmp_path):
    path = tmp_path / mut.TABLE_FILE
    dut = mut.Table(path, ["index", "m"], resume=False)
    dut.append({"index": 0, "m": 1})
    dut.close()
    with pytest.raises(ConfigError, match="exists: pass --resume"):
        mut.Table(path, ["index", "m"], resume=False)
    with pytest.raises(ConfigError, match="its columns are not this sweep's"):
        mut.Table(path, ["index", "other"], resume=True)
    assert mut.read_rows(path) == (["index", "m"], [{"index": 0, "m": 1}])


def test_a_table_without_rows_starts_again(tmp_path):
    path = tmp_path / mut.TABLE_FILE
    mut.Table(path, ["index", "old"], resume=False).close()  # stopped before any row
    assert not path.exists()
    path.write_text("index,old\r\n")  # a header alone, as an older version left it
    dut = mut.Table(path, ["index", "new"], resume=True)
    assert dut.done == set()
    dut.append({"index": 0, "new": 1})
    assert mut.read_rows(path) == (["index", "new"], [{"index": 0, "new": 1}])


def test_resumed_rows_are_kept_byte_for_byte(tmp_path):
    path = tmp_path / mut.TABLE_FILE
    old = b'index,m\r\n0,"[1, 2]"\r\n1,0.125000\r\n'  # written by another program
    path.write_bytes(old)
    dut = mut.Table(path, ["index", "m"], resume=True)
    assert dut.done == {0, 1}
    dut.close()
    assert path.read_bytes() == old  # nothing appended, nothing rewritten
    dut = mut.Table(path, ["index", "m"], resume=True)
    dut.append({"index": 2, "m": 3})
    assert path.read_bytes() == old + b"2,3\r\n"
    cut = tmp_path / "cut.csv"
    cut.write_bytes(old[:-2])  # the last row without its line end
    dut = mut.Table(cut, ["index", "m"], resume=True)
    dut.append({"index": 2, "m": 3})
    assert [r["index"] for r in mut.read_rows(cut)[1]] == [0, 1, 2]


def test_a_failed_save_leaves_the_table_as_it_was(tmp_path, monkeypatch):
    path = tmp_path / mut.TABLE_FILE
    dut = mut.Table(path, ["index", "m"], resume=False)
    dut.append({"index": 0, "m": 1})
    before = path.read_bytes()

    def refuse(*args, **kwargs):
        raise ConfigError("results table cannot be written: disk full")

    monkeypatch.setattr(mut, "write_atomic", refuse)
    with pytest.raises(ConfigError, match="disk full"):
        dut.append({"index": 1, "m": 2})
    assert path.read_bytes() == before and dut.done == {0}


def test_missing_table_reads_empty(tmp_path):
    assert mut.read_rows(tmp_path / "none.csv") == ([], [])
