"""Developer tools, each a ``python -m drake_sim.tools.<tool>`` entry point: model generation,
README pictures, replay frames and the headless-browser helper."""
