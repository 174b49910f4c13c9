"""Where rollouts run: worker processes on this machine, or Ray tasks on a cluster.

Both take the same plain-data job and rollouts and yield rows (``runners.run_rollout``) as they
finish, in whatever order; which backend and how many workers change how fast a sweep runs,
never what it computes. ``stop()`` cancels the work not yet started (after Ctrl-C) and returns
the rows that finished meanwhile.
"""

import multiprocessing
import signal
from collections.abc import Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

from drake_sim.base.errors import ConfigError
from drake_sim.sweep.runners import run_rollout

BACKENDS = ("local", "ray")


def _ignore_interrupts() -> None:
    """Worker initializer: Ctrl-C reaches the whole process group, but only the driver decides
    what stops, so that workers are never killed half-way through writing a result."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def crashed_row(rollout: dict, reason: str) -> dict:
    """The row of a rollout whose worker process died (a segfault, out of memory)."""
    return {
        "index": rollout["index"],
        "seed": rollout["seed"],
        "overrides": rollout["overrides"],
        "status": "failed",
        "reason": reason,
        "report": {},
        "wall_time_s": 0.0,
        "worker": "",
    }


class LocalBackend:
    """A ``ProcessPoolExecutor`` of ``workers`` spawned processes (spawn, not fork: a forked
    child of a process that has loaded Drake and threads is not safe).

    At most ``workers`` rollouts are in flight at a time. A worker that dies (a crash in compiled
    code, out of memory) breaks the whole pool and fails every rollout in flight, not only the
    one to blame: those are run again one at a time in a pool of their own, so that only a
    rollout that kills its worker by itself ends as a failed row, and the rest of the sweep goes
    on in a new pool.
    """

    def __init__(self, workers: int, task=run_rollout):
        self.workers = workers
        self._task = task  # What a worker runs per rollout (tests put in one that crashes).
        self._pool = self._make_pool(workers)
        self._pending = {}  # Future -> rollout, submitted and not yet handed to the caller.

    @staticmethod
    def _make_pool(workers: int) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            max_workers=workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_ignore_interrupts,
        )

    def run(self, job: dict, rollouts: list[dict]) -> Iterator[dict]:
        queue = list(reversed(rollouts))  # pop() takes them in order
        self._pending = {}
        while queue or self._pending:
            while queue and len(self._pending) < self.workers:
                rollout = queue.pop()
                self._pending[self._pool.submit(self._task, job, rollout)] = rollout
            done, _ = wait(self._pending, return_when=FIRST_COMPLETED)
            suspects = []
            for future in done:  # each leaves _pending only as it is handed over
                rollout = self._pending.pop(future)
                try:
                    result = future.result()
                except BrokenProcessPool:
                    suspects.append(rollout)
                    continue
                yield result
            if suspects:  # the pool is broken: whatever else was in flight failed with it
                suspects += self._pending.values()
                self._pending = {}
                yield from self._run_alone(job, suspects)

    def _run_alone(self, job: dict, suspects: list[dict]) -> Iterator[dict]:
        """Runs each rollout that was in a broken pool again, alone, then renews the pool."""
        for rollout in suspects:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = self._make_pool(1)
            future = self._pool.submit(self._task, job, rollout)
            self._pending = {future: rollout}
            try:
                result = future.result()
            except BrokenProcessPool:
                result = crashed_row(rollout, "worker process died (a crash or out of memory)")
            self._pending = {}
            yield result
        self._pool.shutdown(wait=True, cancel_futures=True)
        self._pool = self._make_pool(self.workers)

    def stop(self) -> list[dict]:
        """Cancels the rollouts not started, waits for the running ones, returns their rows."""
        for future in self._pending:
            future.cancel()
        self._pool.shutdown(wait=True, cancel_futures=True)
        return [
            f.result()
            for f in self._pending
            if f.done() and not f.cancelled() and f.exception() is None
        ]

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


def import_ray():
    """The ``ray`` module.

    Raises:
        ConfigError: Ray is not installed (or cannot be imported).
    """
    try:
        import ray
    except ImportError:
        raise ConfigError(
            "--backend ray: Ray is not installed (pip install 'ray>=2.30', or "
            "pip install -e .[ray])"
        ) from None
    return ray


def check_backend(name: str) -> None:
    """Raises ``ConfigError`` at once when backend ``name`` cannot run here (Ray not
    installed), so that the command fails before it prints or writes anything."""
    if name == "ray":
        import_ray()


class RayBackend:
    """Ray tasks, one CPU each: on the cluster at ``address`` (``auto`` joins the one this
    machine belongs to), or on a local Ray instance of ``workers`` CPUs when it is None."""

    def __init__(self, workers: int, address: str | None = None):
        ray = import_ray()
        self._ray = ray
        try:
            if address is not None:
                ray.init(address=address, log_to_driver=False)
            else:
                ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
        except (ConnectionError, RuntimeError, ValueError) as e:
            first = (str(e).strip().splitlines() or [type(e).__name__])[0]
            raise ConfigError(f"--backend ray: cannot start or join Ray: {first}") from None
        self._task = ray.remote(num_cpus=1, max_retries=0)(run_rollout)
        self._pending = []

    def run(self, job: dict, rollouts: list[dict]) -> Iterator[dict]:
        job_ref = self._ray.put(job)
        self._pending = [self._task.remote(job_ref, r) for r in rollouts]
        while self._pending:
            (done,), self._pending = self._ray.wait(self._pending, num_returns=1)
            yield self._ray.get(done)

    def stop(self) -> list[dict]:
        """Cancels every rollout not finished (Ray can stop running tasks, so it does)."""
        for ref in self._pending:
            self._ray.cancel(ref, force=True)
        self._pending = []
        return []

    def close(self) -> None:
        self._ray.shutdown()


def make_backend(name: str, *, workers: int, address: str | None = None):
    """The backend called ``name`` (one of ``BACKENDS``)."""
    if name == "ray":
        return RayBackend(workers, address)
    if address is not None:
        raise ConfigError("--address is for --backend ray")
    return LocalBackend(workers)
