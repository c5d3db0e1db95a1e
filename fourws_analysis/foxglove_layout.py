# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The Foxglove layout fourws ships (``config/foxglove/fourws.json``), built from the names of
:mod:`fourws_run.interface` with the Foxglove SDK's layout classes.

One layout for a bag and for a live run (``fourws run --live``; the live view serves the same
topics as the bag holds): a 3D panel following ``base_link`` in ``odom`` with the car drawn from
``/robot_description`` and the markers of ``/fourws/markers``; plots of yaw rate and lateral
acceleration, of sideslip, and of the front and rear road-wheel angles (applied, and the rear
command); the raw state. Plots take the messages' header stamps (simulation time).

The panels are built with the SDK's typed classes and written in the format of the app's
layout files (:func:`app_layout`), which "Import from file..." reads.
``python -m fourws_analysis.foxglove_layout > config/foxglove/fourws.json`` writes the file;
``test/test_foxglove_layout.py`` checks that the shipped file is what this module builds and
that every topic and field it names exists.
"""

from __future__ import annotations

import json
import sys
from typing import Any, Mapping

from foxglove import layouts as fl

from fourws_run.interface import (FRAME_BODY, FRAME_ODOM, MARKERS, REAR_STEER_CMD,
                                  ROBOT_DESCRIPTION, STATE)

#: The plots: (title, [(message path, label)]) -- the fields of ``VehicleState`` (and the
#: rear-steer command) by name.
PLOTS: tuple[tuple[str, tuple[tuple[str, str], ...]], ...] = (
    ("yaw rate (rad/s), lateral acceleration (m/s^2)",
     ((f"{STATE}.yaw_rate_radps", "yaw rate r"),
      (f"{STATE}.lateral_accel_mps2", "lateral acceleration a_y"))),
    ("sideslip (rad)", ((f"{STATE}.sideslip_rad", "sideslip beta"),)),
    ("road-wheel angles (rad)",
     ((f"{STATE}.front_wheel_angle_rad", "front (applied)"),
      (f"{STATE}.rear_wheel_angle_rad", "rear (applied)"),
      (f"{REAR_STEER_CMD}.angle_rad", "rear command"))),
)


def layout() -> fl.Layout:
    """The layout (module docstring)."""
    three_d = fl.ThreeDeePanel(title="the car", config=fl.ThreeDeeConfig(
        follow_tf=FRAME_BODY, fixed_frame=FRAME_ODOM, follow_mode="follow-heading",
        layers={"fourws-urdf": fl.BaseRendererUrdfLayerSettings(
            layer_id="foxglove.Urdf", label="fourws car", source_type="topic",
            topic=ROBOT_DESCRIPTION, visible=True)},
        topics={MARKERS: fl.BaseRendererRosMarkerTopicSettings(visible=True)}))
    plots = [fl.SplitItem(content=fl.PlotPanel(title=title, config=fl.PlotConfig(
        paths=[fl.PlotSeries(value=path, label=label, enabled=True,
                             timestamp_method="headerStamp") for path, label in series],
        show_legend=True, legend_display="top")))
        for title, series in PLOTS]
    raw = fl.SplitItem(content=fl.RawMessagesPanel(
        title="state", config=fl.RawMessagesConfig(topic_path=STATE)))
    return fl.Layout(content=fl.SplitContainer(direction="row", items=[
        fl.SplitItem(proportion=3, content=three_d),
        fl.SplitItem(proportion=2, content=fl.SplitContainer(direction="column",
                                                             items=[*plots, raw]))]))


#: Panel ids of the app's layout files by the SDK's panel types (the 3D panel is ``3D`` there).
APP_PANEL_TYPES = {"ThreeDee": "3D", "Plot": "Plot", "RawMessages": "RawMessages"}


def app_layout(content: Mapping[str, Any]) -> dict[str, Any]:
    """The layout in the format the Foxglove app imports ("Import from file...") and exports:
    ``configById`` (each panel's config, its title included, by ``Type!id``) and ``layout``,
    the binary split tree (``first``, ``second``, ``direction``, ``splitPercentage``), made
    from the SDK's typed layout ``content`` (its ``to_json``)."""
    configs: dict[str, Any] = {}

    def tree(node: Mapping[str, Any]) -> Any:
        if node.get("type") == "panel":
            kind = APP_PANEL_TYPES[node["panelType"]]
            pid = f"{kind}!fourws{len(configs)}"
            configs[pid] = {**node.get("config", {}), "title": node.get("title", kind)}
            return pid
        items = list(node["items"])
        first, rest = items[0], items[1:]
        if not rest:
            return tree(first["content"])
        share = first.get("proportion", 1) / sum(i.get("proportion", 1) for i in items)
        second = rest[0]["content"] if len(rest) == 1 else {**node, "items": rest}
        return {"direction": node["direction"], "first": tree(first["content"]),
                "second": tree(second), "splitPercentage": round(100 * share, 3)}

    arrangement = tree(content)
    return {"configById": configs, "globalVariables": {}, "userNodes": {},
            "playbackConfig": {"speed": 1.0}, "layout": arrangement}


def layout_json() -> str:
    """The layout as the file holds it (the app's format, indented, keys sorted)."""
    content = json.loads(layout().to_json())["content"]
    return json.dumps(app_layout(content), indent=2, sort_keys=True) + "\n"


if __name__ == "__main__":
    sys.stdout.write(layout_json())
