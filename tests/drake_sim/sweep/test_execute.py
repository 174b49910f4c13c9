import json

from drake_sim.sweep import execute as mut
from drake_sim.sweep.jobs import make_job
from drake_sim.sweep.spec import load_sweep, rollouts
from drake_sim.sweep.table import TABLE_FILE, Table, read_rows
from tests.drake_sim.sweep.sweep_files import tiny_flip


def result(index, status="ok", report=None):
    return {
        "index": index,
        "seed": 100 + index,
        "overrides": {"flip.drive_speed": 0.6},
        "status": status,
        "reason": "" if status == "ok" else "RuntimeError: diverged",
        "report": report or {},
        "wall_time_s": 0.5,
        "worker": "host:1",
    }


def test_make_row(tmp_path):
    spec = load_sweep(tiny_flip(tmp_path))
    report = {"flips": 2, "travel_extent_m": 1.0, "odometry_error_m": 0.1, "finite": True}
    dut = mut.make_row(spec, result(3, report=report))
    assert dut == {
        "index": 3, "status": "ok", "seed": 103, "wall_time_s": 0.5, "worker": "host:1",
        "reason": "", "flip.drive_speed": 0.6, "flips": 2, "travel_extent_m": 1.0,
        "odometry_error_m": 0.1, "success": True,
    }  # fmt: skip
    assert mut.make_row(spec, result(3, report={**report, "finite": False}))["success"] is False
    failed = mut.make_row(spec, result(4, status="failed"))
    assert failed["success"] is False and failed["flips"] is None


class InterruptedBackend:
    """Yields the first ``n`` rows, then acts as if Ctrl-C arrived; ``stop()`` returns one more
    row that finished meanwhile (a local worker's running rollout)."""

    def __init__(self, n):
        self.n = n
        self.stopped = False

    def run(self, job, plain):
        for item in plain[: self.n]:
            yield result(item["index"])
        raise KeyboardInterrupt

    def stop(self):
        self.stopped = True
        return [result(self.n)]


def test_a_stop_keeps_the_rows_written(tmp_path):
    spec = load_sweep(tiny_flip(tmp_path, repeats=3))
    table = Table(tmp_path / TABLE_FILE, mut.header(spec), resume=False)
    backend = InterruptedBackend(2)
    finished = mut.execute(spec, make_job(spec), rollouts(spec), table, backend)
    table.close()
    assert not finished and backend.stopped
    assert [r["index"] for r in read_rows(tmp_path / TABLE_FILE)[1]] == [0, 1, 2]


class RaisingBackend:
    """Its runner is stopped (Ctrl-C) before any row arrives, or after ``n`` rows."""

    def __init__(self, n=0):
        self.n = n

    def run(self, job, plain):
        for item in plain[: self.n]:
            yield result(item["index"])
        raise KeyboardInterrupt

    def stop(self):
        return []


def test_a_stopped_resume_leaves_a_complete_table_byte_for_byte(tmp_path):
    spec = load_sweep(tiny_flip(tmp_path, repeats=2))
    path = tmp_path / TABLE_FILE
    every = rollouts(spec)
    table = Table(path, mut.header(spec), resume=False)
    assert mut.execute(spec, make_job(spec), every, table, ListBackend())
    complete = path.read_bytes()
    # The table is complete: a later run stopped before any row leaves it as it was.
    table = Table(path, mut.header(spec), resume=True)
    assert not mut.execute(spec, make_job(spec), every, table, RaisingBackend())
    table.close()
    assert path.read_bytes() == complete
    # A resumed run of a part of the sweep, stopped after one row: the old rows are kept as
    # they were, the new one after them.
    lines = complete.splitlines(keepends=True)
    path.write_bytes(b"".join(lines[:2]))  # the header and the first row
    kept = path.read_bytes()
    table = Table(path, mut.header(spec), resume=True)
    todo = [r for r in every if r.index not in table.done]
    assert not mut.execute(spec, make_job(spec), todo, table, RaisingBackend(1))
    assert path.read_bytes().startswith(kept)
    assert len(read_rows(path)[1]) == 2


class SlowSaveTable(Table):
    """A table whose save is cut by Ctrl-C once, as a stop in the middle of writing would."""

    cut = True

    def append(self, row):
        if self.cut:
            self.cut = False
            raise KeyboardInterrupt
        super().append(row)


def test_a_stop_while_saving_keeps_the_row(tmp_path):
    spec = load_sweep(tiny_flip(tmp_path, repeats=2))
    table = SlowSaveTable(tmp_path / TABLE_FILE, mut.header(spec), resume=False)
    assert not mut.execute(spec, make_job(spec), rollouts(spec), table, ListBackend())
    assert [r["index"] for r in read_rows(tmp_path / TABLE_FILE)[1]] == [3]


class ListBackend:
    def run(self, job, plain):
        for item in reversed(plain):  # any order
            yield result(item["index"])

    def stop(self):
        return []


def test_execute_writes_every_row(tmp_path):
    spec = load_sweep(tiny_flip(tmp_path))
    table = Table(tmp_path / TABLE_FILE, mut.header(spec), resume=False)
    assert mut.execute(spec, make_job(spec), rollouts(spec), table, ListBackend())
    table.close()
    assert [r["index"] for r in read_rows(tmp_path / TABLE_FILE)[1]] == [1, 0]


def test_write_sweep_info(tmp_path):
    spec = load_sweep(tiny_flip(tmp_path))
    mut.write_sweep_info(spec, tmp_path / "out")
    dut = json.loads((tmp_path / "out" / mut.SWEEP_FILE).read_text())
    assert dut["name"] == "tiny" and dut["size"] == 2 and dut["metrics"][0] == "flips"
    assert dut["parameters"] == [{"path": "flip.drive_speed", "kind": "grid", "values": [0.6, 0.8]}]
    assert dut["success"] == [{"key": "finite", "op": None, "value": None}]
