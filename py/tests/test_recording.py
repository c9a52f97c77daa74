"""MCAP recordings through esrl-record: write scalar topics, read them back as arrays."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import esrl_rs


def test_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "r.mcap"
    t = 0.025 * np.arange(1, 41)
    torque = np.stack([np.sin(t), np.cos(t)], axis=1)
    n = esrl_rs.write_recording(path, {
        "/esrl/joints/torque": {"left_knee": torque[:, 0], "right_knee": torque[:, 1]},
        "/esrl/reward": {"total": t * 2.0},
    }, t)
    assert n == 1 + 40 + 2 * 40  # scene, transforms, two scalar topics
    rec = esrl_rs.read_recording(path, "/esrl/joints/torque")
    assert list(rec) == ["time_ns", "time", "left_knee", "right_knee"]
    assert rec["time_ns"].dtype == np.uint64
    np.testing.assert_array_equal(rec["time_ns"], np.round(t * 1e9).astype(np.uint64))
    np.testing.assert_allclose(rec["time"], t, rtol=1e-12)
    np.testing.assert_array_equal(rec["left_knee"], torque[:, 0])
    np.testing.assert_array_equal(rec["right_knee"], torque[:, 1])
    table = esrl_rs.read_recording_table(path, "/esrl/reward")
    assert table["fields"] == ["total"] and table["values"].shape == (40, 1)
    np.testing.assert_array_equal(table["values"][:, 0], t * 2.0)
    topics = {c["topic"]: c for c in esrl_rs.recording_channels(path)}
    assert topics["/scene"]["schema_name"] == "foxglove.SceneUpdate"
    assert topics["/esrl/reward"]["message_count"] == 40


def test_recording_errors(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="none.mcap"):
        esrl_rs.read_recording(tmp_path / "none.mcap", "/x")
    path = tmp_path / "r.mcap"
    esrl_rs.write_recording(path, {"/a": {"v": [1.0, 2.0]}}, [0.1, 0.2])
    with pytest.raises(ValueError, match="no channel `/b`"):
        esrl_rs.read_recording(path, "/b")
    garbage = tmp_path / "garbage.mcap"
    garbage.write_bytes(b"not an mcap file at all")
    with pytest.raises(esrl_rs.EsrlError, match="garbage.mcap"):
        esrl_rs.read_recording(garbage, "/a")
    with pytest.raises(ValueError, match="length 1, expected 2"):
        esrl_rs.write_recording(path, {"/a": {"v": [1.0]}}, [0.1, 0.2])
    with pytest.raises(ValueError, match="time"):
        esrl_rs.write_recording(path, {"/a": {"v": [1.0]}}, [float("nan")])
