"""Robot descriptions: URDF, xacro and SDF models to a checked RobotDescription (load.py)."""
