"""Motion planning for the Franka Panda on Drake (filled in by the planning issues)."""
