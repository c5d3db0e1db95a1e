"""fourws rear-wheel steering control laws (no rclpy)."""
