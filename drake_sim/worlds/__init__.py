"""World descriptions: typed YAML files for the places robots run in (Wall-E's line-following
courses), their geometry, and the functions that generate their assets and add them to a plant."""
