"""Things that move by themselves: Gazebo actors and a scenario's movers (docs/movers.md).

script.py plays keyframes as Gazebo plays an actor's trajectory, social.py walks people between
random goals by the social-force model, shapes.py casts lidar rays at their upright shapes,
crowd.py keeps their state in arrays, stage.py gives them PyBullet bodies and joins them to a World.
"""
