"""ROS 2 formats: message definitions, CDR, TF, and the rosbag2/MCAP plumbing. No transport."""
