"""Robot descriptions: each robot's YAML parameters (typed and checked) and the function that
renders its xacro and adds it to a plant."""
