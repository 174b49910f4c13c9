"""Simulation on Drake: entry points (``python -m drake_sim.<app>``) and their run harnesses.

Rooms, lowest layer first (a module imports only its own layer or those before it):

* ``drake_sim.base``: paths and resources, typed errors, YAML loading, command-line plumbing.
* ``drake_sim.robots``: robot descriptions (YAML parameters checked, xacro rendered, model added).
* ``drake_sim.systems``: LeafSystems by role (sensors, control, estimation, viewer).
* ``planning`` and ``diagrams`` (separate packages) come next; the apps here come last:
  ``flip``, ``view``, ``pickplace`` and ``drake_sim.tools``.
"""
