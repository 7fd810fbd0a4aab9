"""Maps: ground-truth occupancy grids of a world, map files (ROS map_server's PGM and YAML),
arenas varied by seed, and a team's map scored against the ground truth."""
