"""fourws ROS 2 nodes: thin adapters over the core (the only package that imports rclpy)."""
