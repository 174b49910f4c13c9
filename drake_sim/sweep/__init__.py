"""Parameter sweeps and Monte-Carlo evaluations: ``python -m drake_sim.sweep SWEEP.yaml``.

A sweep runs one app (a *runner*) many times with varied parameters, in parallel worker
processes or on a Ray cluster, and writes one CSV row per rollout. It answers questions such as
"how often does the flip succeed for robots of these sizes and masses?" with a success rate and
its confidence interval rather than one lucky run.

Sweep file (YAML; paths relative to the file; unknown keys are errors)::

    name: flip_robot_variants     # default: the file's stem; the table goes to sweeps/<name>/
    runner: flip                  # flip, pickplace, walle or navigation (sweep.runners)
    scenario: ../flip.yaml        # default: the runner's (config/flip.yaml,
                                  # config/pickplace_scenario.yaml)
    options: {duration: 6.0}      # runner options: flip, walle: duration (s), robot (YAML)
    seed: 0                       # the sweep's seed: every random draw and rollout seed
    samples: 1                    # random draws per grid point (default 1)
    repeats: 2                    # rollouts (seeds) per draw (default 1)
    parameters:                   # --set keys into the runner's scenario (a.b[2].c)
      robot.body.mass: {grid: [2.0, 2.5, 3.5]}             # every value (Cartesian product)
      flip.drive_speed: {uniform: [0.6, 1.0]}              # [low, high), low < high
      imu.angular_velocity_noise: {normal: [0.01, 0.002]}  # [mean, sigma], sigma >= 0
      mode: {choice: [kinematic, physics]}                 # one value drawn at random
      scene: {random: 200}                                 # 200 generated scenes, 0 to 199
      scene.object.position[1]: {uniform: [-0.3, -0.2]}   # one item of a list
    metrics: [flips, odometry_error_m]     # report keys kept in the table
    success: [flips >= 2, "stuck == false"]  # all must hold; or one boolean key: success

The rollouts are the grid points (first parameter slowest) times ``samples`` draws times
``repeats`` seeds. Draws and per-rollout seeds come from ``seed`` and the draw and repeat
numbers only, so the same file gives the same rollouts on any backend with any number of
workers; every grid point gets the same draws and seeds (common random numbers), so grid points
are compared on the same random scenes and noise.
``random: N`` enumerates values the runner generates, like a grid of their numbers 0 to N - 1:
``pickplace`` generates ``scene`` (``planning.task.scene_generator.random_scene`` from
``default_rng(k)`` on the scenario's table, so scene k is the same in every sweep).
For the flip and walle runners, paths under ``robot.`` vary the robot file
(``config/ddrive.yaml``, ``config/walle.yaml``), the rest the scenario (``config/flip.yaml``,
``config/walle_scenario.yaml``); for pickplace, ``PickPlaceScenario`` (``mode``, ``scene.*``,
``task.*``, ...), and the rollout's seed is the planner's. Every path is checked against the
runner's scenario before anything runs; a value the scenario rejects at run time (a negative
mass drawn from a normal) makes that rollout a ``failed`` row with the reason.

Command::

    python -m drake_sim.sweep SWEEP.yaml [--backend local|ray] [--address ADDR] [--workers N]
        [--out DIR] [--resume] [--limit N]
    python -m drake_sim.sweep --plot DIR

``DIR/results.csv`` has the columns ``index, status, success, seed``, the parameters, the
metrics, then ``wall_time_s, worker, reason``; it is saved, rewritten whole and atomically, as
each rollout finishes (a stop never leaves a cut row, nor a header-only table), and
``--resume`` runs only the indices not in it, keeping its rows as they are.
``DIR/sweep.json`` describes the sweep (for ``--plot``) and ``DIR/summary.json`` holds the
summary printed at the end: rollouts, success rate with a Wilson 95 % interval, each metric's
median, min and max. Ctrl-C or SIGTERM cancels what has not started (local workers finish and
write the rollout they are running; Ray cancels it), keeps every row written, prints one line
and exits 0 (the project's convention for a user stop). Exit code 2 with one stderr line on
bad input, and when Ray is missing or cannot start for ``--backend ray`` (before the plan is
printed or any file written).

Modules: ``spec`` (file and rollout list), ``runners`` (what a worker runs), ``backends``
(local processes, Ray), ``table`` (CSV), ``execute`` (the loop), ``summary``, ``plot``,
``command`` (the CLI).
"""
