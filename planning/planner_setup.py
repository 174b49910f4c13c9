"""What a ``MotionPlanner`` makes before its first request: its compiled kernels (cached, or
built in the background while it plans on Drake's checker) and its joint path search.

Until the compiled search is in numba's cache, a planner plans on Drake's checker while the
kernels are built in the background (``planning.planner_kernels``), then switches to it
(``MotionPlanner`` asks ``planner_kernels.ready`` at each request); ``DRAKE_SIM_KERNELS=wait``
builds them first instead, showing the build's progress on a terminal. The time
parameterisation's and IK's compiled steps are compiled or loaded here too, once, rather than
in the first request.
"""

import dataclasses as dc
import sys

from planning import planner_kernels
from planning.collision.hull_kernel import prove_free_packed
from planning.collision.pair_tables import clearances
from planning.collision.sphere_batch import classify_many
from planning.collision.sphere_checker import sphere_model
from planning.collision.sphere_kernel import announce_compile
from planning.planner_options import MotionPlannerOptions
from planning.search import compiled_rrt
from planning.search.joint_path import JointPathSearch
from planning.search.pose_kernel import line, newton
from planning.timing import cubic, toppra


def kernels_now() -> bool:
    """Whether the compiled search can be had now: it is cached (or, in ``wait`` mode, has
    been built or waited for). Otherwise a background build has been started."""
    if planner_kernels.mode() == "wait":  # progress on a terminal; logs stay clean
        progress = planner_kernels.ProgressLine("planner") if sys.stderr.isatty() else None
        planner_kernels.wait_ready(progress=progress)
        return True
    if not planner_kernels.start_background():  # False: the kernels are cached
        return True
    print(
        "note: the planner's kernels are compiling once for this machine in the background "
        f"({planner_kernels.describe(planner_kernels.read_status())}); until they are "
        "ready, plans use Drake's collision checker",
        file=sys.stderr,
        flush=True,
    )
    return False


def warm_up_timing() -> None:
    """Compiles (first run on a machine, with a note on stderr) or loads the time
    parameterisation's compiled TOPP-RA and splines and IK's compiled steps."""
    announce_compile(
        toppra.solve,
        cubic.evaluate,
        newton,
        line,
        note="note: compiling the planner's timing and IK once for this machine (~15 s)...",
        kernel=False,
    )
    toppra.warm_up()  # the time parameterisation's compiled TOPP-RA and splines
    cubic.warm_up()


def make_search(scene, options: MotionPlannerOptions, pending: bool) -> JointPathSearch:
    """The joint path search in ``scene`` with the options' collision models; on Drake's checker
    alone while the compiled search is ``pending`` (its background build not done)."""
    if pending:
        options = dc.replace(options, spheres=dc.replace(options.spheres, enabled=False))
    else:
        announce_compile(
            compiled_rrt.solve,
            compiled_rrt.plan,
            compiled_rrt.fine_check,
            classify_many,
            prove_free_packed,
            clearances,
        )
        spheres = options.spheres
        if spheres.enabled:  # covers are made (or read from the cache) here, once
            sphere_model(scene, spheres.slack)
            if spheres.refine_slack:
                sphere_model(scene, spheres.refine_slack)
    search = JointPathSearch(scene, options)
    search.warm_up()  # the compiled search is compiled or loaded here, once
    return search
