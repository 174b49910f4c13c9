import dataclasses as dc
import sys

import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.sweep import backends as mut
from drake_sim.sweep.jobs import make_job
from drake_sim.sweep.spec import load_sweep, rollouts
from tests.drake_sim.sweep.sweep_files import crash_on_odd_index, tiny_flip


def test_local_backend_runs_on_two_workers(tmp_path):
    spec = load_sweep(tiny_flip(tmp_path, duration=0.2))
    plain = [dc.asdict(r) for r in rollouts(spec)]
    dut = mut.make_backend("local", workers=2)
    try:
        rows = list(dut.run(make_job(spec), plain))
    finally:
        dut.close()
    assert sorted(r["index"] for r in rows) == [0, 1]
    assert all(r["status"] == "ok" for r in rows)
    assert {r["seed"] for r in rows} == {r["seed"] for r in plain}


def test_local_backend_stop_cancels_what_has_not_started(tmp_path):
    spec = load_sweep(tiny_flip(tmp_path, duration=0.2, repeats=4))
    plain = [dc.asdict(r) for r in rollouts(spec)]
    dut = mut.LocalBackend(1)
    results = dut.run(make_job(spec), plain)
    first = next(results)  # one done, the rest queued or running
    late = dut.stop()
    assert first["status"] == "ok"
    assert len(late) < len(plain) - 1  # most of the queue never ran


def test_a_worker_that_dies_fails_its_rollout_only():
    backend = mut.LocalBackend(2, task=crash_on_odd_index)
    try:
        rows = {
            r["index"]: r
            for r in backend.run({}, [{"index": i, "seed": i, "overrides": {}} for i in range(6)])
        }
    finally:
        backend.close()
    assert sorted(rows) == list(range(6))  # every rollout has its row, the sweep went on
    for index, row in rows.items():
        assert row["status"] == ("failed" if index % 2 else "ok"), row
    assert "worker process died" in rows[1]["reason"]


def test_address_needs_ray():
    with pytest.raises(ConfigError, match="--address is for --backend ray"):
        mut.make_backend("local", workers=1, address="auto")


def test_ray_not_installed(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import fails
    with pytest.raises(ConfigError, match=r"Ray is not installed \(pip install 'ray>=2.30'"):
        mut.make_backend("ray", workers=1)
    with pytest.raises(ConfigError, match="--backend ray: Ray is not installed"):
        mut.check_backend("ray")
    mut.check_backend("local")  # needs nothing more
