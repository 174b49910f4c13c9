"""Runs of the apps: each app's recipe (``AppRecipe``: its files, seed, flags and run), its run
harness and report, the one loader (``recipe.load_inputs``), the one run loop
(``loop.SimulationRun``) and the command line they share (``command``).

A notebook starts a run in two calls::

    from drake_sim.runs.mapping import RECIPE
    run = RECIPE.start(seed=1, overrides=["lidar.noise_sigma=0.02"])
    run.run(run.default_duration())  # then run.report()
"""
