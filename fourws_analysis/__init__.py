"""fourws analysis: linear stability, frequency response, handling, recorded-run analysis (no rclpy)."""
