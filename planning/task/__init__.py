"""Tasks built on the planning API: pick-and-place, its geometry and random scenes for it."""
