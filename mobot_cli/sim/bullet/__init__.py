"""The physics engine: robots are PyBullet bodies whose wheels are driven by torques."""
