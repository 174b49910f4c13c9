"""Benchmark of Wall-E's balance controllers: ``python benchmarks/walle_balance_benchmark.py``.

For each controller (PID and LQR, side by side), on the default robot and scenario
(``config/walle.yaml``, ``config/walle_balance.yaml``):

* the largest push it recovers from: a force at the top of the body for ``--push-duration``
  s, found by bisection over its size (in m g, m the robot's mass), forward and backward. A
  push is survived when the robot has not fallen and, ``--settle`` s after it, is upright
  within 2 degrees and nearly still (under 0.15 m/s);
* balancing headless with IMU noise for ``--duration`` simulated s: the largest lean and
  distance from the start after the first second, and the real-time factor (median of
  ``--runs`` runs with seeds 0, 1, ...);
* a manoeuvre (``MANOEUVRE``: drive, turn while driving, reverse, stop): the largest lean
  after the first second, and how far the robot lags its distance reference (RMS and max).

``--json FILE`` also writes the figures for ``python -m benchmarks.report``. Not a test: speeds
depend on the machine.
"""

import argparse
import dataclasses as dc
import json
import os
import platform
import statistics

import numpy as np
from pydrake.common import RandomGenerator
from pydrake.systems.analysis import Simulator

from diagrams.walle_balance import make_walle_diagram
from diagrams.walle_balance_scenario import Push, WalleBalanceScenario, load_walle_balance_scenario
from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.base.resources import config_dir
from drake_sim.robots.walle import default_robot_file
from drake_sim.robots.walle_params import WalleParams, load_walle_params
from drake_sim.runs.walle_track import run_walle, walle_track
from drake_sim.systems.control.balance_controller import CONTROLLERS, STATUS_FIELDS

S, S_REF = STATUS_FIELDS.index("s"), STATUS_FIELDS.index("s_ref")

PUSH_TIME = 1.0  # s, when the push starts.
MANOEUVRE = (
    (1.0, (0.0, 0.0)),  # Stand,
    (4.0, (0.4, 0.0)),  # drive,
    (7.0, (0.4, 1.0)),  # turn while driving,
    (10.0, (-0.2, 0.0)),  # reverse,
    (13.0, (0.0, 0.0)),  # stop.
)
"""(until t s, cmd_vel [v m/s, omega rad/s]), in order."""


def survives(
    scenario: WalleBalanceScenario,
    robot: WalleParams,
    fraction: float,
    *,
    direction: float,
    duration: float,
    settle: float,
) -> bool:
    """Whether the robot recovers from a push of ``fraction`` m g (forward for ``direction``
    +1, backward for -1) at the top of its body for ``duration`` s."""
    force = [direction * fraction * robot.total_mass * 9.81, 0.0, 0.0]
    pushed = dc.replace(scenario, pushes=[Push(time=PUSH_TIME, force=force, duration=duration)])
    end = PUSH_TIME + duration + settle
    run = run_walle(pushed, robot, end)
    track = run.track
    last = track.t >= end - 0.5
    if run.fell or np.degrees(np.abs(track.pitch[last])).max() > 2.0:
        return False
    p, t = track.p_WA[:, last], track.t[last]
    return bool(np.linalg.norm(p[:, -1] - p[:, 0]) / (t[-1] - t[0]) < 0.15)


def largest_push(scenario, robot, *, direction, duration, settle, steps: int) -> float:
    """Bisection over the push's size (m g) between 0 and 2: ``steps`` halvings."""
    low, high = 0.0, 2.0
    for _ in range(steps):
        middle = 0.5 * (low + high)
        kwargs = dict(direction=direction, duration=duration, settle=settle)
        if survives(scenario, robot, middle, **kwargs):
            low = middle
        else:
            high = middle
    return low


def manoeuvre(scenario, robot) -> dict:
    """Drives ``MANOEUVRE`` and returns the largest lean (deg) after the first second and
    the distance lag behind the reference (m), sampled every 10 ms."""
    diagram = make_walle_diagram(scenario, robot)
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    diagram.SetRandomContext(context, RandomGenerator(scenario.random_seed))
    lag, t = [], 0.0
    for until, command in MANOEUVRE:
        diagram.GetInputPort("cmd_vel").FixValue(context, np.asarray(command))
        while t < until - 1e-9:
            t += 0.01
            simulator.AdvanceTo(t)
            status = diagram.GetOutputPort("status").Eval(context)
            lag.append(status[S] - status[S_REF])
    track = walle_track(diagram, context, robot)
    return {
        "manoeuvre max |pitch| (deg)": np.degrees(np.abs(track.pitch[track.t >= 1.0]).max()),
        "manoeuvre rms lag (m)": float(np.sqrt(np.mean(np.square(lag)))),
        "manoeuvre max lag (m)": float(np.max(np.abs(lag))),
    }


def figures(rows: dict[str, dict[str, float]], settings: dict) -> dict:
    """The controllers' figures as ``--json`` figures: one row per figure ("max drift (m)"
    gives the figure "max drift" in m), one column per controller."""
    table = []
    for key in next(iter(rows.values())):
        name, _, unit = key.partition(" (")
        row = {"figure": name, "unit": unit.rstrip(")") or "x"}
        table.append(row | {controller: values[key] for controller, values in rows.items()})
    columns = [["figure", "figure", "", ""], ["unit", "unit", "", ""]]
    columns += [[controller, controller.upper(), "", ".3f"] for controller in rows]
    note = (
        f"Pushes at the body's top for {settings['push_duration_s']:g} s, found by bisection to "
        f"{2.0 / 2 ** settings['steps']:.3f} m g; balance: {settings['duration_s']:g} s with IMU "
        f"noise, seeds 0 to {settings['runs'] - 1} (largest lean and drift after the first "
        "second; the real-time factor is their median)."
    )
    factors = {f"real_time_factor_{c}": v["real-time factor"] for c, v in rows.items()}
    return {
        "settings": settings,
        "figures": factors,
        "tables": [{"title": "Per controller", "columns": columns, "rows": table, "note": note}],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--duration", type=float, default=20.0, help="simulated s of balance")
    parser.add_argument("--runs", type=int, default=3, help="balance runs per controller")
    parser.add_argument("--push-duration", type=float, default=0.2, help="s")
    parser.add_argument("--settle", type=float, default=4.0, help="s after the push")
    parser.add_argument("--steps", type=int, default=8, help="bisection steps")
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args()
    base = load_walle_balance_scenario(config_dir() / "walle_balance.yaml")
    robot = load_walle_params(default_robot_file())
    weight = robot.total_mass * 9.81
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    print(f"robot: {robot.total_mass:.2f} kg, push {args.push_duration} s at the body's top")
    rows = {}
    for controller in CONTROLLERS:
        scenario = dc.replace(base, balance=dc.replace(base.balance, controller=controller))
        push = {
            name: largest_push(
                scenario,
                robot,
                direction=direction,
                duration=args.push_duration,
                settle=args.settle,
                steps=args.steps,
            )
            for name, direction in (("forward", 1.0), ("backward", -1.0))
        }
        runs = [run_walle(scenario, robot, args.duration, seed=seed) for seed in range(args.runs)]
        rows[controller] = {
            "push forward (m g)": push["forward"],
            "push forward (N)": push["forward"] * weight,
            "push backward (m g)": push["backward"],
            "push backward (N)": push["backward"] * weight,
            "max |pitch| (deg)": max(r.max_abs_pitch_deg for r in runs),
            "max drift (m)": max(r.max_drift_m for r in runs),
            "real-time factor": statistics.median(r.real_time_factor for r in runs),
            **manoeuvre(scenario, robot),
        }
    print(f"{'':>28}" + "".join(f"{name:>10}" for name in rows))
    for key in next(iter(rows.values())):
        print(f"{key:>28}" + "".join(f"{row[key]:>10.3f}" for row in rows.values()))
    print(
        f"(balance: {args.duration:g} s x {args.runs} seeds with IMU noise, after the first "
        f"second; push resolution {2.0 / 2**args.steps:.3f} m g)"
    )
    if args.json:
        settings = {"duration_s": args.duration, "runs": args.runs, "steps": args.steps}
        settings |= {"push_duration_s": args.push_duration, "settle_s": args.settle}
        write_atomic(args.json, json.dumps(figures(rows, settings), indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
