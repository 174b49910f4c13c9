"""The motion planner's compiled kernels: ready, being built in the background, or to build now.

The compiled search (``compiled_rrt``: RRT-Connect, shortcutting and the fine check on the
robot's spheres, ``sphere_batch.classify_many``, ``hull_kernel.prove_free_packed``) is compiled
by numba once per machine and cached beside its sources; that first compile takes two to three
minutes on two cores. No run waits for it:

* ``background`` (the default, ``DRAKE_SIM_KERNELS`` unset): a ``MotionPlanner`` made while the
  cache is cold starts ``python -m planning.planner_kernels --background`` (one at a time per
  cache, held by a lock) and plans meanwhile with Drake's collision checker and the Python
  pipeline, which need no long compile; at the first request after the background build has
  finished it switches to the compiled search. On a terminal one line shows what is compiling,
  how far it is and the time expected.
* ``wait`` (``DRAKE_SIM_KERNELS=wait``: tests, benchmarks, anything that must plan the same way
  every time): the planner has the compiled search from its first request, waiting for a
  background build in progress, or building here.

``python -m planning.planner_kernels`` builds them in the foreground, with the same progress line
(for a container image or a CI step that wants them ready).

The build's state is a small JSON file beside numba's cache (``status.json``: the step, how many,
the time expected from the last build on this machine), written atomically; the lock is an
``fcntl`` lock, released by the system however the process ends.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic
from planning.collision import pair_tables, sphere_batch, sphere_kernel
from planning.collision.hull_kernel import prove_free_packed
from planning.search import compiled_rrt, pose_kernel

ENV_MODE = "DRAKE_SIM_KERNELS"
"""The environment variable that chooses the mode: ``background`` (default) or ``wait``."""
MODES = ("background", "wait")
EXPECTED_S = 150.0
"""s a first build is expected to take on two cores, until one has been timed on the machine."""
_POLL_S = 0.25  # s between looks at a build another process runs


def heavy_dispatchers() -> tuple:
    """The compiled functions whose first compile is long: the ones ``ready`` looks for."""
    return (
        compiled_rrt.solve,
        compiled_rrt.plan,
        compiled_rrt.fine_check,
        sphere_batch.classify_many,
        prove_free_packed,
        pair_tables.clearances,
    )


def mode() -> str:
    """The mode ``DRAKE_SIM_KERNELS`` names (``background`` when unset).

    Raises:
        ConfigError: an unknown mode (bad input: one line and exit code 2 from a CLI).
    """
    value = os.environ.get(ENV_MODE, "").strip() or "background"
    if value not in MODES:
        raise ConfigError(f"{ENV_MODE}={value!r}: expected one of {', '.join(MODES)}")
    return value


def ready() -> bool:
    """Whether every heavy kernel is compiled in this process or in numba's cache for this
    machine and these sources (a few file reads)."""
    return not any(sphere_kernel.cache_is_cold(d) for d in heavy_dispatchers())


def state_dir() -> Path:
    """The folder of the build's lock and status: numba's cache folder of the compiled search."""
    return Path(compiled_rrt.plan._cache._cache_path)


def read_status() -> dict:
    """The last status a build wrote (``{}`` when none, or unreadable)."""
    try:
        return json.loads((state_dir() / "status.json").read_text())
    except (OSError, ValueError):
        return {}


def building() -> bool:
    """Whether a build holds the lock now (in this process or another)."""
    lock = _try_lock()
    if lock is None:
        return True
    lock.close()
    return False


def await_shared(limit_s: float = 120.0) -> None:
    """Waits, while a build runs, until it has cached IK's compiled steps (its first step),
    rather than compiling them here at the same time on the other core: a planner made on a
    fresh install has them then in the time it spends compiling its other kernels. Returns at
    once when they are cached or no build runs; after ``limit_s`` s, whatever the build does."""
    deadline = time.monotonic() + limit_s
    dispatchers = (pose_kernel.newton, pose_kernel.line)
    while any(sphere_kernel.cache_is_cold(d) for d in dispatchers) and building():
        if time.monotonic() > deadline:
            return
        time.sleep(_POLL_S)


def start_background() -> bool:
    """Starts a background build unless the kernels are ready or one runs already; returns
    whether one is running now. The lock is taken here and handed to the build process (an
    inherited descriptor), so two planners made at once start one build. Its output goes to
    ``build.log`` beside the status; it runs in its own session, so Ctrl-C in this terminal
    stops this process and not the build."""
    if ready():
        return False
    lock = _try_lock()
    if lock is None:
        return True
    try:
        started = time.time()
        with open(state_dir() / "build.log", "ab") as log:
            process = subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "planning.planner_kernels",
                    "--background",
                    "--lock-fd",
                    str(lock.fileno()),
                ],
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=log,
                start_new_session=True,
                pass_fds=(lock.fileno(),),
            )
        status = {"state": "building", "step": 0, "steps": "?", "name": "starting"}
        _write_status(
            {**status, "pid": process.pid, "started": started, "expected_s": _last_build_s()}
        )
    finally:
        lock.close()  # the build process holds the lock through its own descriptor now
    return True


def wait_ready(*, progress=None) -> float:
    """Has the heavy kernels ready in this process's cache: waits for a build another process
    runs, or builds them here (``build``). Returns the wall time it took, s.

    Args:
        progress: a ``ProgressLine`` to show how far a build is (None: quiet).
    """
    start = time.perf_counter()
    while not ready():
        lock = _try_lock()
        if lock is None:  # another process builds: follow its status
            if progress is not None:
                progress.show(read_status())
            time.sleep(_POLL_S)
            continue
        try:
            if not ready():
                build(progress=progress)
        finally:
            lock.close()
        break  # built here: what numba could cache is cached
    if progress is not None:
        progress.done()
    return time.perf_counter() - start


def build(*, progress=None) -> None:
    """Compiles the heavy kernels (the caller holds the lock: ``_try_lock``) on the default
    Panda scene, writing the status at each step and, at the end, the time it took (the next
    build's estimate)."""
    from planning.planner_options import MotionPlannerOptions
    from planning.planning_scene import PlanningScene
    from planning.search.joint_path import JointPathSearch

    start = time.time()
    status = {"pid": os.getpid(), "started": start, "expected_s": _last_build_s()}

    def step(i: int, n, name: str) -> None:
        current = {**status, "state": "building", "step": i, "steps": n, "name": name}
        _write_status(current)
        if progress is not None:
            progress.show(current)

    try:
        # IK's Newton steps first: a planner made meanwhile waits for them (``await_shared``)
        # while it compiles the time parameterisation, rather than compiling them too.
        step(1, "?", "IK and Cartesian steps")
        pose_kernel.warm_up()
        step(2, "?", "the robot's model")
        search = JointPathSearch(PlanningScene(), MotionPlannerOptions())
        steps = search.warm_up_steps()
        for i, (name, run) in enumerate(steps):
            step(i + 3, len(steps) + 2, name)
            run()
    except Exception as e:
        _write_status({**status, "state": "failed", "error": f"{type(e).__name__}: {e}"})
        raise
    elapsed = time.time() - start
    _write_status({**status, "state": "done", "finished": time.time(), "elapsed_s": elapsed})
    with contextlib.suppress(Exception):
        write_atomic(state_dir() / "last_build_s", f"{elapsed:.1f}\n")


class ProgressLine:
    """One line on a terminal (``stream``, stderr by default) that a build's status rewrites in
    place: what is compiling, step k of n, seconds elapsed of those expected. Off a terminal it
    prints nothing but the first line (once, as a note)."""

    def __init__(self, what: str, stream=None):
        self._stream = stream if stream is not None else sys.stderr
        self._tty = hasattr(self._stream, "isatty") and self._stream.isatty()
        self._what = what
        self._shown = False

    def show(self, status: dict) -> None:
        """Shows ``status`` (a ``read_status`` dict; ignored when empty)."""
        if not status:
            return
        text = (
            f"{self._what}: compiling the planner's kernels once for this machine "
            f"({describe(status)})"
        )
        if self._tty:
            self._stream.write("\r\x1b[2K" + text)
            self._stream.flush()
        elif not self._shown:
            print(text, file=self._stream, flush=True)
        self._shown = True

    def done(self) -> None:
        """Ends the line (on a terminal) once a build it showed has finished."""
        if self._tty and self._shown:
            self._stream.write("\r\x1b[2K")
            self._stream.flush()


def describe(status: dict) -> str:
    """A build's status in words: ``step 3 of 7: the compiled search, 40 s of about 150 s``
    (just starting when ``status`` is empty or not a build's)."""
    if status.get("state") != "building":
        return f"starting, about {_last_build_s():.0f} s"
    elapsed = max(0.0, time.time() - status.get("started", time.time()))
    return (
        f"step {status.get('step', '?')} of {status.get('steps', '?')}: "
        f"{status.get('name', '')}, {elapsed:.0f} s of about "
        f"{status.get('expected_s', EXPECTED_S):.0f} s"
    )


def _try_lock():
    """The build lock, taken without waiting (an open file that holds it), or None when
    another process holds it. Where locks are not available it is always taken."""
    folder = state_dir()
    folder.mkdir(parents=True, exist_ok=True)
    f = open(folder / "build.lock", "a+b")  # noqa: SIM115 (returned, closed by the caller)
    try:
        import fcntl

        fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except ImportError:
        return f
    except OSError:
        f.close()
        return None
    return f


def _write_status(status: dict) -> None:
    with contextlib.suppress(Exception):  # the status is a courtesy; the build goes on
        write_atomic(state_dir() / "status.json", json.dumps(status) + "\n", "build status")


def _last_build_s() -> float:
    try:
        return float((state_dir() / "last_build_s").read_text())
    except (OSError, ValueError):
        return EXPECTED_S


def main(argv=None) -> int:
    """``python -m planning.search.kernels [--background]``: builds the kernels now."""
    parser = argparse.ArgumentParser(
        prog="python -m planning.planner_kernels",
        description="Compiles the motion planner's kernels once for this machine.",
    )
    parser.add_argument(
        "--background", action="store_true", help="as a planner's background build: no progress"
    )
    parser.add_argument("--lock-fd", type=int, help=argparse.SUPPRESS)  # held, from the parent
    args = parser.parse_args(argv)
    if ready():
        if not args.background:
            print("the planner's kernels are compiled and cached")
        return 0
    progress = None if args.background else ProgressLine("planning.planner_kernels")
    try:
        if args.lock_fd is not None:  # started by start_background, which took the lock
            with os.fdopen(args.lock_fd, "rb"):
                start = time.perf_counter()
                build(progress=progress)
                seconds = time.perf_counter() - start
        else:
            seconds = wait_ready(progress=progress)
    except KeyboardInterrupt:
        print("\nstopped: the kernels are not compiled yet", file=sys.stderr)
        return 0
    if not args.background:
        print(f"compiled the planner's kernels in {seconds:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
