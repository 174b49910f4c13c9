"""Mobile-robot navigation on occupancy maps: costmap_2d-style costmaps (static, obstacle and
inflation layers, a rolling local window), the global planner (A* / Dijkstra on the costmap),
the local planner and the navigator that drives the lidar robot to its goals."""
