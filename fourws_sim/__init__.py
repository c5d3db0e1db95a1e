# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""fourws simulator core: parameters, tire models, vehicle models, integrators (no rclpy)."""
