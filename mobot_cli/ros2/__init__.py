"""The world as a ROS 2 node over DDS (`--ros2`, extra ``ros2``): beside run/, live/ and sweep/.

names.py (ROS names on DDS, domain and discovery settings) and graph.py (ros_discovery_info)
need nothing; dds.py, idl.py, publisher.py import cyclonedds, and bridge.py imports them only
when a Bridge opens, so the CLI imports this package only when ROS 2 is asked for.
sim_services.py serves simulation_interfaces on rclpy (imported only when rclpy is there),
sim_requests.py translates its requests to the live protocol's and needs neither.
"""
