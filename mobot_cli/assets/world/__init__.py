"""Gazebo SDF worlds and models: read (reader.py), built into static bodies (build.py), cached (load.py)."""
