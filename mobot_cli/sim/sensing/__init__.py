"""Sensors computed from the simulation: lidar rays on the static world, IMU, contacts."""
