# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The simulator's publishers of the car in 3D: ``/tf``, ``/tf_static``, ``/robot_description``
and ``/fourws/markers``.

What is drawn is :class:`fourws_run.scene.CarScene`'s (no ROS there), written as CDR bytes by
:mod:`fourws_run.scene_codecs`; this class owns the publishers (counted, like every
publication of the simulator, so the recorder's accounting and the lockstep flow window cover
them) and is called from the simulator's ``side_publications``, the one place a state's
publications besides the state itself are made. The URDF and the fixed transforms are
published once, latched.
"""

from __future__ import annotations

from typing import Any, Callable

from fourws_ros import topics
from fourws_ros.reporting import PublishCounts
from fourws_run.scene import DYNAMIC_FRAMES, STATIC_FRAMES, CarScene, PathTrail
from fourws_run.scene_codecs import MarkersEncoder, TransformsEncoder
from fourws_run.ticks import Tick
from fourws_run.urdf import robot_description
from fourws_sim.maneuvers import Maneuver
from fourws_sim.params import Vehicle


class ScenePublisher:
    """Publishes a run's scene (module docstring).

    Parameters
    ----------
    node : rclpy Node
        The simulator node.
    counts : PublishCounts
        The simulator's counted publishers.
    vehicle : Vehicle
        The simulated vehicle (its URDF and geometry).
    maneuver : Maneuver, optional
        The run's maneuver (its course, if it has one).
    path_period_s : float
        Simulation time between two path-and-course marker messages, s.
    """

    def __init__(self, node: Any, counts: PublishCounts, vehicle: Vehicle,
                 maneuver: Maneuver | None, path_period_s: float) -> None:
        self.scene = CarScene(vehicle, maneuver)
        self.path_period_s = float(path_period_s)
        self._tf = counts.publisher(node, topics.TF)
        self._markers = counts.publisher(node, topics.MARKERS)
        self._static = counts.publisher(node, topics.TF_STATIC)
        self._description = counts.publisher(node, topics.ROBOT_DESCRIPTION)
        self._tf_encoder = TransformsEncoder(DYNAMIC_FRAMES)
        self._fast = MarkersEncoder(self.scene.fast_markers)
        self._slow = MarkersEncoder(self.scene.slow_markers)
        self._next_path_s = 0.0
        self._latched = False

    def publish_latched(self) -> None:
        """The URDF and the fixed transforms (once; with the first state, when the run's
        subscribers have matched)."""
        if self._latched:
            return
        self._latched = True
        msg = topics.message_class(topics.ROBOT_DESCRIPTION)()
        msg.data = robot_description(self.scene.vehicle)
        self._description.publish(msg)
        self._static.publish(TransformsEncoder(STATIC_FRAMES).encode(
            0, self.scene.static_transforms()))

    def restart(self) -> None:
        """A reset: the path and the wheel spin start again."""
        self.scene.trail = PathTrail()
        self._next_path_s = 0.0

    def publications(self, tick: Tick, markers_due: bool) -> list[Callable[[], None]]:
        """What ``tick`` publishes of the scene, in order: its transforms (and its markers
        when due, ``markers_due``: with the odometry), then the path and course when due
        (every :attr:`path_period_s`), two calls a clock may make on different integration
        steps."""
        self.publish_latched()
        outputs = tick.outputs

        def frames() -> None:
            self._tf.publish(self._tf_encoder.encode(tick.stamp_ns,
                                                     self.scene.transforms(outputs)))
            if markers_due:
                self._markers.publish(self._fast.encode(tick.stamp_ns,
                                                        self.scene.fast_values(outputs)))

        jobs = [frames]
        if tick.t >= self._next_path_s - 1e-12:
            self._next_path_s = tick.t + self.path_period_s
            jobs.append(lambda: self._markers.publish(
                self._slow.encode(tick.stamp_ns, self.scene.slow_values(outputs))))
        return jobs


__all__ = ["ScenePublisher"]
