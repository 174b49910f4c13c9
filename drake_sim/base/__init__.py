"""The shared base every other layer may import: resource paths, typed errors, YAML loading
and command-line plumbing. It imports nothing of the project's own above it."""
