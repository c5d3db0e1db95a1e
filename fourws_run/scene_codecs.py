# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The scene's messages as CDR bytes: ``tf2_msgs/TFMessage`` and
``visualization_msgs/MarkerArray`` written straight from :mod:`fourws_run.scene`.

Both messages are sequences (of transforms, of markers with points), so they have a layout only
once the counts are known; a run's counts are fixed (the frames of
:data:`fourws_run.scene.DYNAMIC_FRAMES`, the markers of a :class:`~fourws_run.scene.CarScene`),
so each encoder derives its layout once from the message definitions
(:func:`fourws_run.cdr.layout` with ``sequences``), keeps the bytes with every frame id,
namespace and fixed value, and writes only the changing numbers (as the encoders of
:mod:`fourws_run.codecs`): the simulator publishes them inside its tick without building Python
messages. ``test/test_scene.py`` compares the bytes with rclpy's serialization.
"""

from __future__ import annotations

from typing import Callable, Sequence

from fourws_run.cdr import CodecError, constants, layout
from fourws_run.codecs import field_packer
from fourws_run.interface import MARKERS, NS_PER_S, TF, TOPIC_TYPES
from fourws_run.scene import Marker, MarkerValues

TF_TYPE = TOPIC_TYPES[TF]
MARKER_ARRAY_TYPE = TOPIC_TYPES[MARKERS]
MARKER_TYPE = "visualization_msgs/msg/Marker"
#: The fields of a ``geometry_msgs/Transform``, in wire order (the values of one transform).
TRANSFORM_FIELDS = ("translation.x", "translation.y", "translation.z", "rotation.x",
                    "rotation.y", "rotation.z", "rotation.w")
_XYZ = ("x", "y", "z")
_RGBA = ("r", "g", "b", "a")


class TransformsEncoder:
    """Serializes a ``TFMessage`` of fixed (parent, child) frames.

    Parameters
    ----------
    frames : sequence of (str, str)
        ``header.frame_id`` and ``child_frame_id`` of each transform.
    """

    def __init__(self, frames: Sequence[tuple[str, str]]) -> None:
        strings = {}
        for i, (parent, child) in enumerate(frames):
            strings[f"transforms[{i}].header.frame_id"] = parent
            strings[f"transforms[{i}].child_frame_id"] = child
        lay = layout(TF_TYPE, strings, sequences={"transforms": len(frames)})
        self._buf = buf = lay.template()
        self.count = len(frames)
        self._stamps = [field_packer(buf, lay, (f"transforms[{i}].header.stamp.sec",
                                                f"transforms[{i}].header.stamp.nanosec"))
                        for i in range(self.count)]
        self._values = [field_packer(buf, lay, tuple(f"transforms[{i}].transform.{f}"
                                                     for f in TRANSFORM_FIELDS))
                        for i in range(self.count)]

    def encode(self, stamp_ns: int, transforms: Sequence[Sequence[float]]) -> bytes:
        """CDR bytes of ``transforms`` (one ``(tx, ty, tz, qx, qy, qz, qw)`` per frame, m and
        a unit quaternion), every header stamped ``stamp_ns`` (ns).

        Raises
        ------
        CodecError
            Not one transform per frame.
        """
        if len(transforms) != self.count:
            raise CodecError(f"{TF_TYPE}: {len(transforms)} transforms for {self.count} frames")
        sec, nanosec = divmod(int(stamp_ns), NS_PER_S)
        for stamp, values, transform in zip(self._stamps, self._values, transforms):
            stamp(sec, nanosec)
            values(*transform)
        return bytes(self._buf)


class MarkersEncoder:
    """Serializes a ``MarkerArray`` of fixed markers (:class:`fourws_run.scene.Marker`):
    namespace, id, type, frame, pose, scale and the number of points in the template; colour,
    points, text and stamps per message.

    Parameters
    ----------
    markers : sequence of Marker
    """

    def __init__(self, markers: Sequence[Marker]) -> None:
        kinds = constants(MARKER_TYPE)
        strings: dict[str, str] = {}
        sequences = {"markers": len(markers)}
        for i, m in enumerate(markers):
            if m.kind not in kinds:
                raise CodecError(f"{MARKER_TYPE} has no type {m.kind!r}")
            strings[f"markers[{i}].header.frame_id"] = m.frame
            strings[f"markers[{i}].ns"] = m.ns
            strings[f"markers[{i}].text"] = " " * m.text_chars
            sequences[f"markers[{i}].points"] = m.points
        lay = layout(MARKER_ARRAY_TYPE, strings, sequences=sequences, blank_strings=True)
        self._buf = buf = lay.template()
        self.markers = tuple(markers)
        # the points last written per marker: a course's fixed points are written once
        self._written: list[object] = [None] * len(markers)
        self._writers: list[tuple[Callable[..., None], Callable[..., None],
                                  Callable[..., None] | None, tuple[int, int] | None]] = []
        for i, m in enumerate(markers):
            p = f"markers[{i}]."
            field_packer(buf, lay, (p + "id", p + "type", p + "action"))(
                m.id, kinds[m.kind], kinds["ADD"])
            field_packer(buf, lay, tuple(p + f for f in (
                "pose.position.x", "pose.position.y", "pose.position.z", "pose.orientation.x",
                "pose.orientation.y", "pose.orientation.z", "pose.orientation.w",
                "scale.x", "scale.y", "scale.z")))(*m.position, 0.0, 0.0, 0.0, 1.0, *m.scale)
            color = field_packer(buf, lay, tuple(p + "color." + c for c in _RGBA))
            color(*m.color)
            names = tuple(f"{p}points[{j}].{c}" for j in range(m.points) for c in _XYZ)
            points = field_packer(buf, lay, names) if m.points else None
            text = None
            if m.text_chars:
                slot = lay.slot(p + "text")
                text = (slot.offset + 4, m.text_chars)
            self._writers.append((field_packer(buf, lay, (p + "header.stamp.sec",
                                                          p + "header.stamp.nanosec")),
                                  color, points, text))

    def encode(self, stamp_ns: int, values: Sequence[MarkerValues]) -> bytes:
        """CDR bytes of the markers with ``values`` (one per marker), stamped ``stamp_ns``.

        Raises
        ------
        CodecError
            Not one value per marker, a point count or a text length other than the marker's.
        """
        if len(values) != len(self._writers):
            raise CodecError(f"{MARKER_ARRAY_TYPE}: {len(values)} values for "
                             f"{len(self._writers)} markers")
        sec, nanosec = divmod(int(stamp_ns), NS_PER_S)
        buf = self._buf
        rows = zip(self._writers, values, self.markers)
        for i, ((stamp, color, points, text), v, m) in enumerate(rows):
            stamp(sec, nanosec)
            color(*v.color)
            if points is not None and v.points is not self._written[i]:
                self._written[i] = v.points
                if len(v.points) != m.points:
                    raise CodecError(f"marker {m.ns}/{m.id}: {len(v.points)} points for "
                                     f"{m.points}")
                points(*(c for point in v.points for c in point))
            if text is not None:
                data = v.text.encode("utf-8")
                if len(data) != text[1]:
                    raise CodecError(f"marker {m.ns}/{m.id}: a text of {len(data)} bytes for "
                                     f"{text[1]}")
                buf[text[0]:text[0] + text[1]] = data
        return bytes(buf)


__all__ = ["MARKER_ARRAY_TYPE", "MARKER_TYPE", "MarkersEncoder", "TF_TYPE", "TRANSFORM_FIELDS",
           "TransformsEncoder"]
