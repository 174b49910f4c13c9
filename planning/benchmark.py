"""``python -m planning.benchmark``: the command DESIGN.md names for the MotionBenchMaker
benchmark. The app itself is ``drake_sim.tools.plan_benchmark`` (apps stand outside the library
packages); this name only forwards to it, and imports nothing of the project."""

if __name__ == "__main__":
    import runpy

    runpy.run_module("drake_sim.tools.plan_benchmark", run_name="__main__", alter_sys=True)
