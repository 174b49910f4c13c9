"""Controllers: LeafSystems that turn commands and measurements into actuation."""
