"""``--plot DIR``: pictures of a finished (or stopped) sweep, from its table and ``sweep.json``.

Writes ``success.png`` (success rate with its Wilson 95 % interval, overall and per value of
each grid parameter), ``hist_<metric>.png`` and ``<metric>_vs_<parameter>.png``, each
atomically (a stop leaves the old picture or the new one). matplotlib is optional: without it
this is one line on stderr and exit code 2.
"""

import io
import json
import re
from pathlib import Path

from drake_sim.base.config import read_text
from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic
from drake_sim.sweep.execute import SWEEP_FILE
from drake_sim.sweep.summary import numeric, wilson_interval
from drake_sim.sweep.table import TABLE_FILE, read_rows


def _pyplot():
    try:
        import matplotlib
    except ImportError:
        raise ConfigError("--plot needs matplotlib: pip install matplotlib") from None
    matplotlib.use("Agg")  # files only, no display
    import matplotlib.pyplot as plt

    return plt


def _slug(text: str) -> str:
    return re.sub(r"[^\w.-]+", "_", text).strip("_")


def plot_sweep(folder: Path) -> list[Path]:
    """Writes the PNGs of the sweep in ``folder`` and returns their paths.

    Raises:
        ConfigError: no sweep there, or matplotlib is not installed.
    """
    info_file = folder / SWEEP_FILE
    text = read_text(info_file, "sweep info")
    try:
        info = json.loads(text)
    except ValueError:
        raise ConfigError(f"{info_file}: not a sweep info file") from None
    _, rows = read_rows(folder / TABLE_FILE)
    if not rows:
        raise ConfigError(f"{folder / TABLE_FILE}: no rollouts to plot")
    plt = _pyplot()
    params = [p["path"] for p in info["parameters"]]
    written = []

    def save(fig, name: str) -> None:
        path = folder / f"{_slug(name)}.png"
        fig.tight_layout()
        png = io.BytesIO()
        fig.savefig(png, format="png", dpi=100)
        plt.close(fig)
        written.append(write_atomic(path, png.getvalue(), "plot"))

    if info["success"]:
        groups = [("all", rows)]
        for p in info["parameters"]:
            if p["kind"] in ("grid", "choice"):
                groups += [
                    (f"{p['path']}={v}", [r for r in rows if r.get(p["path"]) == v])
                    for v in p["values"]
                ]
        fig, ax = plt.subplots(figsize=(max(4, len(groups) * 0.9), 3.5))
        for i, (_, group) in enumerate(groups):
            wins = sum(1 for r in group if r.get("success") is True)
            low, high = wilson_interval(wins, len(group))
            rate = wins / len(group) if group else 0.0
            ax.errorbar(i, rate, yerr=[[rate - low], [high - rate]], fmt="o", capsize=4)
        ax.set_xticks(range(len(groups)), [g[0] for g in groups], rotation=30, ha="right")
        ax.set_ylim(-0.05, 1.05)
        ax.set_ylabel("success rate (Wilson 95% CI)")
        ax.set_title(info["name"])
        save(fig, "success")
    ok = [r for r in rows if r.get("status") == "ok"]
    for metric in info["metrics"]:
        values = numeric(r.get(metric) for r in ok)
        if not values:
            continue
        fig, ax = plt.subplots(figsize=(5, 3.5))
        ax.hist(values, bins=min(30, max(5, len(values) // 3)))
        ax.set_xlabel(metric)
        ax.set_ylabel("rollouts")
        save(fig, f"hist_{metric}")
        for param in params:
            pairs = [(r.get(param), r.get(metric)) for r in ok]
            pairs = [(x, y) for x, y in pairs if numeric([x]) and numeric([y])]
            if not pairs:
                continue
            fig, ax = plt.subplots(figsize=(5, 3.5))
            ax.scatter([x for x, _ in pairs], [y for _, y in pairs], s=12, alpha=0.7)
            ax.set_xlabel(param)
            ax.set_ylabel(metric)
            save(fig, f"{metric}_vs_{param}")
    return written
