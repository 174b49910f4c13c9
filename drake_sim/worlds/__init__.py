"""World descriptions: typed YAML files for the places robots run in (Wall-E's line-following
courses, the lidar robot's walled arenas with their routes and goals), their geometry, and the
functions that generate their assets and ground truth and add them to a plant."""
