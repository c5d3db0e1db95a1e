# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""fourws studies: sweeps and Monte Carlo over speed, laws and parameter error (no rclpy)."""
