# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""fourws analysis: linear stability, frequency response, handling, recorded-run analysis
(no rclpy)."""
