"""Collision checking of arm configurations and segments: Drake's checker behind an adapter, and
the conservative sphere model of the Panda (cover, batched kinematics, compiled kernel) that
answers first."""
