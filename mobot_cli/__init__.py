"""mobot: spawn wheeled robots into worlds and see what they do, headless, on PyBullet."""

__version__ = "0.1.0"
