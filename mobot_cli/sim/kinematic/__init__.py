"""The kinematic engine: robots follow their commanded twist; PyBullet only answers
where things are and what touches what."""
