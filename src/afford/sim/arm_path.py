"""The arm's path during an execution, as a fixed number of key points.

A push or a sweep is done by the arm, not by the affordance's end point: the gripper lowered
beside a cup knocks it over on the way down. The object world model (`afford.objects`) can take
the path as an input, so the pose data records it. A key point is (x, y, z, yaw, fingers): the
TCP in metres, the gripper's yaw in degrees and the finger opening as a fraction of its range,
taken at `PATH_POINTS` instants evenly spaced in time over every arm move of the execution
(the settling that follows moves no arm and adds none).
"""

from __future__ import annotations

import numpy as np

PATH_COLUMNS = ("x", "y", "z", "yaw", "fingers")
PATH_WIDTH = len(PATH_COLUMNS)
PATH_POINTS = 32


def key_points(trace: list[tuple], points: int = PATH_POINTS) -> np.ndarray:
    """(points, PATH_WIDTH) float32: the trace of (x, y, z, axis x, axis y, fingers) per physics
    step (`Scene.record_tcp`) sampled at evenly spaced instants (NaN if empty)."""
    if not trace:
        return np.full((points, PATH_WIDTH), np.nan, dtype=np.float32)
    at = np.linspace(0, len(trace) - 1, points).round().astype(int)
    rows = np.array([trace[i] for i in at], dtype=float)
    # The same yaw as ArmKinematics.yaw_of: the finger-opening axis in the table plane.
    yaw = np.degrees(np.arctan2(rows[:, 4], rows[:, 3])) % 360.0
    return np.column_stack([rows[:, :3], yaw, rows[:, 5]]).astype(np.float32)


def empty_paths(n: int = 0) -> np.ndarray:
    return np.zeros((n, PATH_POINTS, PATH_WIDTH), dtype=np.float32)
