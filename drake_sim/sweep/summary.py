"""What a sweep found: the success rate with its Wilson 95 % interval, and each metric's median,
minimum and maximum, computed from the table's rows (so a resumed sweep is summarised whole)."""

import math

import numpy as np

Z_95 = 1.959963984540054  # Standard normal quantile of 0.975.


def wilson_interval(successes: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """The Wilson score interval of a success probability (Wilson 1927), which stays inside
    [0, 1] and is sensible for rates near 0 or 1 and small ``n``, unlike the normal
    approximation. (0, 1) when ``n`` is 0."""
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    denominator = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denominator
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denominator
    # Mathematically low <= p <= high; clamp so that rounding never says otherwise.
    return min(max(0.0, centre - half), p), max(min(1.0, centre + half), p)


def numeric(values) -> list[float]:
    """The finite numbers among ``values`` (booleans count as 0 and 1)."""
    out = []
    for v in values:
        if isinstance(v, bool) or (isinstance(v, int | float) and math.isfinite(v)):
            out.append(float(v))
    return out


def summarize(rows: list[dict], metrics, *, has_success: bool) -> dict:
    """Counts, success rate (rows whose ``success`` is true; failed rollouts count as
    unsuccessful) and per-metric statistics over the rows that ran."""
    ok = [r for r in rows if r.get("status") == "ok"]
    out = {"rollouts": len(rows), "ok": len(ok), "failed": len(rows) - len(ok), "metrics": {}}
    if has_success:
        wins = sum(1 for r in rows if r.get("success") is True)
        low, high = wilson_interval(wins, len(rows))
        out["success"] = {
            "count": wins,
            "rate": wins / len(rows) if rows else 0.0,
            "ci95": [low, high],
        }
    for key in metrics:
        values = numeric(r.get(key) for r in ok)
        if values:
            out["metrics"][key] = {
                "median": float(np.median(values)),
                "min": min(values),
                "max": max(values),
                "n": len(values),
            }
    return out


def format_summary(summary: dict) -> str:
    """The summary as a few lines of text."""
    lines = [f"rollouts {summary['rollouts']} (ok {summary['ok']}, failed {summary['failed']})"]
    if "success" in summary:
        s = summary["success"]
        low, high = s["ci95"]
        lines.append(
            f"success {s['count']}/{summary['rollouts']} = {s['rate']:.1%} "
            f"(Wilson 95% CI {low:.1%} to {high:.1%})"
        )
    for key, m in summary["metrics"].items():
        lines.append(f"  {key}: median {m['median']:.4g}, min {m['min']:.4g}, max {m['max']:.4g}")
    return "\n".join(lines)
