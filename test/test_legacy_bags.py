# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Bags recorded before the messages moved into the fourws package (type names
``fourws_msgs/msg/...``, from the separate interface package of earlier revisions) still load.

Source: the values written into such a bag come back unchanged.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fourws_analysis import bag as B
from fourws_run import interface


def test_bag_with_the_old_message_package_name_loads(tmp_path: Path) -> None:
    old = f"{interface.LEGACY_MSG_PACKAGES[0]}/msg/VehicleState"
    assert old != B.TOPIC_TYPES[B.TOPIC_STATE]
    store = B.typestore()
    with B.BagWriter(tmp_path / "b") as bag:
        bag.write_run_config({"maneuver": {"type": "step_steer"}, "law": "fws"})
        for i in range(20):
            t = 0.01 * i
            msg = B.make_message(old, header={"stamp": B.stamp(t), "frame_id": "base_link"},
                                 step=i, yaw_rate_radps=0.5 * t)
            bag.write_raw(B.TOPIC_STATE, store.serialize_cdr(msg, old), int(t * 1e9), old)
    state = B.load_bag(tmp_path / "b").topics[B.TOPIC_STATE]
    np.testing.assert_array_equal(state.fields["step"], np.arange(20))
    np.testing.assert_allclose(state.fields["yaw_rate_radps"], 0.5 * 0.01 * np.arange(20),
                               rtol=0, atol=1e-15)
