"""What every robot model module shares: rendering its xacro for a parameter set, and adding the
rendered URDF to a plant under the model name the caller chooses.

A robot's xacro (``models/<robot>/<robot>.urdf.xacro``) reads its parameters itself, through
``xacro.load_yaml`` of the file named by its ``robot_config`` argument; ``render_robot_urdf``
writes that file (``params_yaml_file``) and renders the xacro (``render_xacro``, cached).
"""

from __future__ import annotations

from pathlib import Path

from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex

from drake_sim.base.resources import make_parser, models_dir, params_yaml_file, render_xacro


def render_robot_urdf(xacro: str, prefix: str, params, **mappings: str) -> Path:
    """Renders a robot's xacro for ``params`` (cached) and returns the URDF's path.

    Args:
        xacro: the robot's xacro, relative to ``models/``.
        prefix: the name of the parameters' YAML file in the cache (``params_yaml_file``).
        params: the robot's parameters (``to_dict`` gives the YAML layout, every optional key
            filled in).
        mappings: the xacro's other arguments, after ``robot_config``.
    """
    config = str(params_yaml_file(prefix, params.to_dict()))
    return render_xacro(models_dir() / xacro, {"robot_config": config, **mappings})


def add_robot_urdf(plant: MultibodyPlant, urdf: Path, robot: str, name: str) -> ModelInstanceIndex:
    """Adds the URDF file ``urdf``, whose robot is named ``robot``, to ``plant`` as the model
    ``name`` (a free body unless the URDF welds it) and returns its model instance.

    Raises:
        RuntimeError: from Drake's parser, when ``plant`` has a model named ``name`` already
            (no automatic renaming).
    """
    parser = make_parser(plant)
    parser.SetAutoRenaming(False)
    text = urdf.read_text().replace(f'<robot name="{robot}"', f'<robot name="{name}"', 1)
    (instance,) = parser.AddModelsFromString(text, "urdf")
    return instance
