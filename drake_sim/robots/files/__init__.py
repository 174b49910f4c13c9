"""A robot's description files made Drake-ready without ROS: packages found by a package map,
xacro rendered with ``$(find pkg)``, meshes converted once into the cache; the VAMP robots'
resources fetched from the package index. Used by the arms (``planning.model``) and the mobile
robots alike."""
