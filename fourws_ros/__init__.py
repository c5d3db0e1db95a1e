# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""fourws ROS 2 nodes: thin adapters over the core (the only package that imports rclpy)."""
