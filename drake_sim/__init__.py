"""Drake simulation of a flipping differential-drive robot: models, systems and entry points."""
