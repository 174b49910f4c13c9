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


def test_rows_are_flushed_as_written_and_resumed(tmp_path):
    path = tmp_path / "out" / mut.TABLE_FILE
    header = mut.columns(["p"], ["m"])
    dut = mut.Table(path, header, resume=False)
    dut.append({"index": 0, "status": "ok", "p": 1.5, "m": [1, 2], "reason": ""})
    # Flushed: readable while the table is still open.
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
    mut.Table(path, ["index", "new"], resume=False).close()
    assert mut.read_rows(path) == (["index", "new"], [])


def test_missing_table_reads_empty(tmp_path):
    assert mut.read_rows(tmp_path / "none.csv") == ([], [])
