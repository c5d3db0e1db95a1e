"""fourws studies: sweeps and Monte Carlo over speed, laws and parameter error (no rclpy)."""
