# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The rclpy ``Node`` every fourws node (and the launcher's) is: its publishers and
subscriptions have no QoS event handlers unless a caller asks for some.

rclpy gives every endpoint default handlers (a warning when a peer offers an incompatible QoS
or type): two waitables per endpoint, which rclpy's single-threaded executor visits in Python
on every wake-up. The nodes that must spin it (the controller, the recorder, the realtime
simulator and the launcher: publisher identity comes with rclpy's message info only there)
wake up several times per lockstep tick, and those visits were about half of each wake-up:
303 us per message received with them, 166 us without, measured here for a node with five
subscriptions, two publishers and a timer; the lockstep graph ran 12 % faster (real-time
factor 6.4 -> 7.2, mean of three 60 s runs each, alternated). What the warnings would say of
fourws's own endpoints the graph tests say louder: every run pairs them all, and a pair that
did not match would stall the run. A user's node with an incompatible QoS keeps rclpy's
warning in its own log, and the run's verdict names the node whose answers did not come.
"""

from __future__ import annotations

from typing import Any

from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.node import Node


class FourwsNode(Node):
    """``rclpy.node.Node`` whose endpoints have no default event handlers (module
    docstring); ``event_callbacks`` given to a create call are used as given."""

    def create_publisher(self, *args: Any, **kwargs: Any) -> Any:  # noqa: D102 - rclpy's
        kwargs.setdefault("event_callbacks", PublisherEventCallbacks(use_default_callbacks=False))
        return super().create_publisher(*args, **kwargs)

    def create_subscription(self, *args: Any, **kwargs: Any) -> Any:  # noqa: D102 - rclpy's
        kwargs.setdefault("event_callbacks",
                          SubscriptionEventCallbacks(use_default_callbacks=False))
        return super().create_subscription(*args, **kwargs)


__all__ = ["FourwsNode"]
