"""The BARN challenge's geometry (github.com/Daffan/the-barn-challenge, run.py): its cylinders,
their grid, the Jackal's start and its goal. Shared by the BARN-style generator (barn.py) and
`mobot barn`'s rules (sweep/barn_score.py)."""

CYLINDER_RADIUS = 0.075  # m: BARN's cylinders ...
CELL = 2 * CYLINDER_RADIUS  # ... stand on a grid of this pitch
START = (-2.25, 3.0, 1.57)  # run.py, static worlds: the Jackal starts here (x, y, yaw in rad) ...
GOAL = (START[0] + 0.0, START[1] + 10.0)  # ... and its goal lies 10 m ahead (GOAL_POSITION [0, 10])
