"""Walking paths: the centre line the foot's heel contacts are placed on.

A path is a chain of straight and circular segments parametrised by arclength s (m). Yaw angles are measured
counter-clockwise from east (the world x axis), in rad inside, deg in scenario files: north is yaw 90 deg.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Segment:
    """A line (``curvature == 0``) or circular arc starting at ``start`` with tangent yaw ``yaw0``.

    Attributes
    ----------
    start : (x, y) m.
    yaw0 : rad, tangent direction at the start.
    length : m.
    curvature : 1/m, positive turns left (counter-clockwise).
    """

    start: tuple[float, float]
    yaw0: float
    length: float
    curvature: float = 0.0

    def at(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Position (N, 2) m and tangent yaw (N,) rad at arclengths ``s`` from the segment start."""
        s = np.asarray(s, float)
        k = self.curvature
        yaw = self.yaw0 + k * s
        if abs(k) < 1e-12:
            dx, dy = s * np.cos(self.yaw0), s * np.sin(self.yaw0)
        else:
            dx = (np.sin(yaw) - np.sin(self.yaw0)) / k
            dy = (np.cos(self.yaw0) - np.cos(yaw)) / k
        return np.column_stack([self.start[0] + dx, self.start[1] + dy]), yaw

    def end(self) -> tuple[tuple[float, float], float]:
        p, yaw = self.at(np.array([self.length]))
        return (float(p[0, 0]), float(p[0, 1])), float(yaw[0])


@dataclass(frozen=True)
class Path:
    """A chain of segments, each starting where the previous one ends (equal and hashable by value).

    Attributes
    ----------
    segments : tuple of :class:`Segment`.
    """

    segments: tuple[Segment, ...]

    def __post_init__(self):
        object.__setattr__(self, "segments", tuple(self.segments))

    @property
    def offsets(self) -> np.ndarray:
        """(len(segments) + 1,) m, arclength at the start of each segment and at the end."""
        return np.concatenate([[0.0], np.cumsum([seg.length for seg in self.segments])])

    @property
    def length(self) -> float:
        """Total arclength (m)."""
        return float(self.offsets[-1])

    @property
    def min_radius(self) -> float:
        """Smallest turn radius (m) on the path (inf for a straight path)."""
        k = max((abs(seg.curvature) for seg in self.segments), default=0.0)
        return np.inf if k == 0 else 1.0 / k

    def at(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Position (N, 2) m and tangent yaw (N,) rad at arclengths ``s`` (clipped to the path)."""
        s = np.clip(np.asarray(s, float), 0.0, self.length)
        idx = np.clip(np.searchsorted(self.offsets, s, side="right") - 1, 0, len(self.segments) - 1)
        pos = np.zeros((s.size, 2))
        yaw = np.zeros(s.size)
        for i, seg in enumerate(self.segments):
            m = idx == i
            if m.any():
                pos[m], yaw[m] = seg.at(s[m] - self.offsets[i])
        return pos, yaw


def straight(length: float, yaw: float, start=(0.0, 0.0)) -> Path:
    """A straight line of ``length`` (m) toward ``yaw`` (rad)."""
    return Path([Segment(tuple(start), yaw, length)])


def arc(radius: float, turn: float, yaw: float, start=(0.0, 0.0)) -> Path:
    """A constant-radius turn of ``turn`` rad (positive: left) with radius (m), starting toward ``yaw``."""
    return Path([Segment(tuple(start), yaw, abs(turn) * radius, np.sign(turn) / radius)])


def _legs(waypoints: np.ndarray, corner_radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Leg lengths (m), leg yaws (rad), signed corner turns in (-pi, pi] (rad) and the straight part of each leg
    left once its corners are rounded with ``corner_radius`` (m; negative where the corners do not fit)."""
    legs = np.diff(np.asarray(waypoints, float), axis=0)
    lengths = np.linalg.norm(legs, axis=1)
    yaws = np.arctan2(legs[:, 1], legs[:, 0])
    turns = np.angle(np.exp(1j * np.diff(yaws)))
    cut = corner_radius * np.tan(np.abs(turns) / 2)  # tangent length taken off each leg per corner
    remaining = lengths - np.concatenate([[0.0], cut]) - np.concatenate([cut, [0.0]])
    return lengths, yaws, turns, remaining


def corners_fit(waypoints: np.ndarray, corner_radius: float) -> bool:
    """True when consecutive waypoints (N, 2) m differ and every corner rounded with ``corner_radius`` (m) fits
    on its two legs."""
    lengths, _, _, remaining = _legs(waypoints, corner_radius)
    return bool(np.all(lengths > 0) and np.all(remaining >= -1e-9))


def polyline(waypoints: np.ndarray, corner_radius: float) -> Path:
    """Straight legs between waypoints (N, 2) m, each interior corner rounded by an arc of ``corner_radius``.

    The path starts at the first and ends at the last waypoint; a closed loop repeats the first point at the
    end. Raises ValueError (with the corner index) when a rounded corner does not fit on its legs.
    """
    w = np.asarray(waypoints, float)
    lengths, yaws, turns, remaining = _legs(w, corner_radius)
    if np.any(remaining < -1e-9):
        bad = int(np.argmin(remaining))
        raise ValueError(
            f"leg {bad} ({lengths[bad]:.3f} m) is too short for corners of radius {corner_radius} m"
        )
    segments: list[Segment] = []
    pos = (float(w[0, 0]), float(w[0, 1]))
    for i in range(len(lengths)):
        seg = Segment(pos, float(yaws[i]), float(max(remaining[i], 0.0)))
        segments.append(seg)
        pos, yaw = seg.end()
        if i < len(turns) and abs(turns[i]) > 1e-12:
            corner = Segment(pos, float(yaws[i]), float(abs(turns[i]) * corner_radius),
                             float(np.sign(turns[i]) / corner_radius))
            segments.append(corner)
            pos, _ = corner.end()
    return Path([s for s in segments if s.length > 0])


def simplify(points: np.ndarray, tolerance: float) -> np.ndarray:
    """Ramer-Douglas-Peucker simplification of a 2-D polyline (K, 2) m: the fewest of its points that keep every
    point within ``tolerance`` (m) of the simplified line."""
    if len(points) < 3:
        return points
    a, b = points[0], points[-1]
    d = b - a
    length = np.hypot(*d)
    rel = points - a
    dist = np.abs(d[0] * rel[:, 1] - d[1] * rel[:, 0]) / length if length > 0 else np.hypot(rel[:, 0], rel[:, 1])
    i = int(np.argmax(dist))
    if dist[i] <= tolerance:
        return np.array([a, b])
    return np.vstack([simplify(points[:i + 1], tolerance)[:-1], simplify(points[i:], tolerance)])


def hairpins(points: np.ndarray, radius: float, sharpest_turn: float) -> np.ndarray:
    """Waypoints (K, 2) m with the legs after every corner sharper than ``sharpest_turn`` (rad) moved sideways by
    two ``radius`` (m) to the turn's side, so that a U-turn becomes a hairpin of two corners of that radius."""
    pts = points.copy()
    for i in range(1, len(pts) - 1):
        d0, d1 = pts[i] - pts[i - 1], pts[i + 1] - pts[i]
        turn = math.atan2(d0[0] * d1[1] - d0[1] * d1[0], d0 @ d1)
        if abs(turn) > sharpest_turn:
            u = d0 / np.hypot(*d0)
            side = np.array([-u[1], u[0]]) * (1.0 if turn >= 0 else -1.0)
            pts = np.vstack([pts[:i + 1], pts[i] + 2 * radius * side, pts[i + 1:] + 2 * radius * side])
            return hairpins(pts, radius, sharpest_turn)
    return pts
