"""Functions that assemble Drake Diagrams from typed configuration."""
