# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The shipped Foxglove layout (config/foxglove/fourws.json) is what
:mod:`fourws_analysis.foxglove_layout` builds, and names only topics and fields that exist.

Sources: the module itself (the file is generated), the interface names and the ``.msg``
fields (:mod:`fourws_run.interface`, the typestore), the app's layout format (every panel of
``layout`` has its config in ``configById``).
"""

from __future__ import annotations

import json
from pathlib import Path

from fourws_analysis.foxglove_layout import PLOTS, layout_json
from fourws_run import interface
from fourws_run.bagfile import typestore
from fourws_sim.params import CONFIG_DIR

SHIPPED = Path(CONFIG_DIR) / "foxglove" / "fourws.json"


def _panels(node):
    if isinstance(node, str):
        return [node]
    return _panels(node["first"]) + _panels(node["second"])


def test_the_shipped_layout_is_the_generated_one():
    assert SHIPPED.read_text() == layout_json(), \
        "regenerate: python -m fourws_analysis.foxglove_layout > config/foxglove/fourws.json"


def test_the_layout_names_what_a_bag_holds():
    data = json.loads(SHIPPED.read_text())
    panels = _panels(data["layout"])
    assert sorted(panels) == sorted(data["configById"])
    assert [p.split("!")[0] for p in panels] == ["3D", "Plot", "Plot", "Plot", "RawMessages"]
    three_d = data["configById"][panels[0]]
    assert three_d["followTf"] == interface.FRAME_BODY
    assert three_d["fixedFrame"] == interface.FRAME_ODOM
    (urdf,) = three_d["layers"].values()
    assert urdf["sourceType"] == "topic" and urdf["topic"] == interface.ROBOT_DESCRIPTION
    assert interface.MARKERS in three_d["topics"]
    store = typestore()
    paths = [p["value"] for pid in panels[1:4] for p in data["configById"][pid]["paths"]]
    assert len(paths) == sum(len(series) for _, series in PLOTS) == 6
    for path in paths:
        topic, name = path.rsplit(".", 1)
        fields = dict(store.fielddefs[interface.TOPIC_TYPES[topic]][1])
        assert name in fields, path
    # yaw rate, lateral acceleration, sideslip, front and rear steer: the plots
    names = {p.rsplit(".", 1)[1] for p in paths}
    assert {"yaw_rate_radps", "lateral_accel_mps2", "sideslip_rad", "front_wheel_angle_rad",
            "rear_wheel_angle_rad"} <= names
    assert data["configById"][panels[4]]["topicPath"] == interface.STATE
