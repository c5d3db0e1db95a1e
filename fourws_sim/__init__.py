"""fourws simulator core: parameters, tire models, vehicle models, integrators (no rclpy)."""
