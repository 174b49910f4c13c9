import json
import sys

import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.sweep import plot as mut
from drake_sim.sweep.table import TABLE_FILE, Table, columns

INFO = {
    "name": "t",
    "runner": "flip",
    "source": "t.yaml",
    "size": 4,
    "parameters": [{"path": "flip.drive_speed", "kind": "grid", "values": [0.5, 1.0]}],
    "metrics": ["flips", "odometry_error_m"],
    "success": [{"key": "finite", "op": None, "value": None}],
}


def make_sweep_folder(folder):
    (folder / "sweep.json").write_text(json.dumps(INFO))
    table = Table(folder / TABLE_FILE, columns(["flip.drive_speed"], INFO["metrics"]), resume=False)
    for i, (speed, flips, ok) in enumerate([(0.5, 2, True), (0.5, 1, False), (1.0, 3, True)]):
        table.append(
            {
                "index": i,
                "status": "ok",
                "success": ok,
                "flip.drive_speed": speed,
                "flips": flips,
                "odometry_error_m": 0.01 * i,
            }  # fmt: skip
        )
    table.append({"index": 3, "status": "failed", "success": False, "reason": "boom"})
    table.close()


def test_plot_writes_pngs(tmp_path):
    pytest.importorskip("matplotlib")
    make_sweep_folder(tmp_path)
    dut = mut.plot_sweep(tmp_path)
    names = sorted(p.name for p in dut)
    assert names == [
        "flips_vs_flip.drive_speed.png",
        "hist_flips.png",
        "hist_odometry_error_m.png",
        "odometry_error_m_vs_flip.drive_speed.png",
        "success.png",
    ]
    assert all(p.stat().st_size > 1000 and p.read_bytes()[:4] == b"\x89PNG" for p in dut)


def test_plot_without_matplotlib(tmp_path, monkeypatch):
    make_sweep_folder(tmp_path)
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import fails
    with pytest.raises(ConfigError, match="--plot needs matplotlib"):
        mut.plot_sweep(tmp_path)


def test_plot_of_a_folder_without_a_sweep(tmp_path):
    with pytest.raises(ConfigError, match="sweep.json: no such sweep info"):
        mut.plot_sweep(tmp_path)
