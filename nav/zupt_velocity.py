"""Stance velocity models (compensation step 2 of the seed paper).

In the detected stance the foot is not exactly still: it creeps or rolls by millimetres per second, more at
the stance edges that a larger threshold pulls into the ZUPT window. Instead of "velocity = 0", the ZUPT can
use the expected residual velocity for the gait and the detector threshold. These models give it per sample,
in the foot's heading frame (x forward along the foot's horizontal heading, y left, z up; m/s): the filter
rotates it by its current heading estimate.

- :class:`ConstantStanceVelocity`: one vector for every stationary sample.
- :class:`StanceVelocityProfile`: a velocity profile over normalised detected-stance time tau in [0, 1]
  (piecewise linear between knots), fitted offline from arrays of stance velocities (simulated truth or a
  tracker) with :meth:`StanceVelocityProfile.fit`, saved and loaded as JSON.

A model is valid only for the gait and the detector parameters it was fitted with; the JSON keeps both in
``metadata`` for that reason.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .alignment import stationary_runs, yaw_of
from .files import write_text_atomic
from .series import resample

MODEL_FORMAT = "nav.stance_velocity/1"


def normalised_stance_time(stationary: np.ndarray) -> np.ndarray:
    """(N,) normalised time tau = (i - start + 0.5) / length inside each stationary run; NaN outside."""
    stationary = np.asarray(stationary, bool)
    starts, ends = stationary_runs(stationary)
    tau = np.full(stationary.shape, np.nan)
    if len(starts) == 0:
        return tau
    run_id = np.cumsum(np.isin(np.arange(len(stationary)), starts)) - 1
    inside = np.flatnonzero(stationary)
    rid = run_id[inside]
    tau[inside] = (inside - starts[rid] + 0.5) / (ends[rid] - starts[rid])
    return tau


def to_heading_frame(vel_world: np.ndarray, quat: np.ndarray) -> np.ndarray:
    """World velocities (..., 3) m/s rotated into the heading frame of attitudes quat (..., 4)."""
    yaw = yaw_of(quat)
    return rotate_to_heading(vel_world, np.cos(yaw), np.sin(yaw))


def rotate_to_heading(vel_world: np.ndarray, cos_yaw, sin_yaw) -> np.ndarray:
    """World vectors (..., 3) in the frame (forward, left, up) of a heading given by its cosine and sine (the
    unit horizontal forward vector (cos_yaw, sin_yaw), scalars or broadcastable to (...))."""
    c, s = cos_yaw, sin_yaw
    v = np.asarray(vel_world, float)
    return np.stack([c * v[..., 0] + s * v[..., 1], -s * v[..., 0] + c * v[..., 1], v[..., 2]], axis=-1)


def stance_velocities(vel_world: np.ndarray, quat: np.ndarray, stationary: np.ndarray) -> list[np.ndarray]:
    """Heading-frame velocities (n_i, 3) m/s of every stationary run, e.g. from a recording's truth.

    Parameters
    ----------
    vel_world : (N, 3) m/s true (or tracked) velocity; quat : (N, 4) attitude body->world; stationary : (N,) bool
    detected stance.
    """
    v_h = to_heading_frame(vel_world, quat)
    starts, ends = stationary_runs(stationary)
    return [v_h[a:b] for a, b in zip(starts, ends)]


@dataclass(frozen=True)
class ConstantStanceVelocity:
    """The same stance velocity (3,) m/s in the heading frame at every stationary sample."""

    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def stance_velocity(self, stationary: np.ndarray) -> np.ndarray:
        """(N, 3) m/s: the constant where stationary, zero elsewhere."""
        stationary = np.asarray(stationary, bool)
        return np.where(stationary[:, None], np.asarray(self.velocity, float), 0.0)

    def to_json(self) -> dict:
        return {"format": MODEL_FORMAT, "type": "constant", "velocity_m_s": list(self.velocity)}


@dataclass(frozen=True)
class StanceVelocityProfile:
    """Expected foot velocity over normalised detected-stance time.

    Attributes
    ----------
    tau : (K,) increasing knots in [0, 1] (0 = first detected stationary sample, 1 = last).
    velocity : (K, 3) m/s, heading frame (forward, left, up), mean over the fitted stances.
    spread : (K, 3) m/s, standard deviation over the fitted stances (for reports; not used by the filter).
    max_samples : detected stances longer than this (samples, at the fitted rate) are rest, not a step: the
        profile is not applied there (zero stance velocity). Default: 1.5 x the longest fitted stance.
    metadata : dict, what it was fitted on (gait, detector parameters, number of stances).
    """

    tau: np.ndarray
    velocity: np.ndarray
    spread: np.ndarray
    max_samples: int
    metadata: dict = field(default_factory=dict)

    @classmethod
    def fit(cls, stances: list[np.ndarray], knots: int = 21, metadata: dict | None = None) -> "StanceVelocityProfile":
        """Average stance velocity profiles on a common normalised-time grid.

        Parameters
        ----------
        stances : list of (n_i, 3) m/s heading-frame velocities, one per detected stance (see
            :func:`stance_velocities`); each is placed on tau_i = (j + 0.5) / n_i and interpolated linearly.
            Every stance weighs the same whatever its length, so give the stances of steps only: not the rests
            (they would also raise ``max_samples`` above them) and not fragments whose velocity the source
            cannot resolve (a tracker's central difference is longer than a 10 ms fragment).
        knots : number of knots K on [0, 1].
        metadata : stored with the model (e.g. the detector's params.as_dict() and the gait).
        """
        stances = [np.asarray(s, float) for s in stances if len(s) >= 2]
        if not stances:
            raise ValueError("StanceVelocityProfile.fit: need at least one stance of >= 2 samples")
        tau = np.linspace(0.0, 1.0, knots)
        resampled = np.stack([resample(tau, (np.arange(len(s)) + 0.5) / len(s), s) for s in stances])
        meta = dict(metadata or {})
        meta["stances"] = len(stances)
        longest = max(len(s) for s in stances)
        return cls(tau, resampled.mean(axis=0), resampled.std(axis=0), int(np.ceil(1.5 * longest)), meta)

    def stance_velocity(self, stationary: np.ndarray) -> np.ndarray:
        """(N, 3) m/s: the profile at each stance sample's normalised time; zero elsewhere and in long rests."""
        stationary = np.asarray(stationary, bool).copy()
        starts, ends = stationary_runs(stationary)
        for a, b in zip(starts, ends):
            if b - a > self.max_samples:
                stationary[a:b] = False
        tau = normalised_stance_time(stationary)
        inside = np.isfinite(tau)
        out = np.zeros(tau.shape + (3,))
        out[inside] = resample(tau[inside], self.tau, self.velocity)
        return out

    def to_json(self) -> dict:
        return {"format": MODEL_FORMAT, "type": "profile", "tau": self.tau.tolist(),
                "velocity_m_s": self.velocity.tolist(), "spread_m_s": self.spread.tolist(),
                "max_samples": self.max_samples,
                "frame": "heading frame: x forward along the foot's horizontal heading, y left, z up",
                "metadata": self.metadata}


def save_stance_velocity(model, path: str | Path) -> Path:
    """Write a model as JSON (atomically: a temporary file renamed into place)."""
    return write_text_atomic(path, json.dumps(model.to_json(), indent=2, default=float))


def load_stance_velocity(path: str | Path):
    """Read a model written by :func:`save_stance_velocity`; errors name the file, key and value."""
    path = Path(path)
    try:
        with open(path) as fh:
            doc = json.load(fh)
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: cannot read a stance-velocity model: {exc}") from exc
    if doc.get("format") != MODEL_FORMAT:
        raise ValueError(f"{path}: key 'format' = {doc.get('format')!r}, expected {MODEL_FORMAT!r}")
    kind = doc.get("type")
    if kind == "constant":
        v = np.asarray(doc.get("velocity_m_s"), float)
        if v.shape != (3,) or not np.all(np.isfinite(v)):
            raise ValueError(f"{path}: key 'velocity_m_s' = {doc.get('velocity_m_s')!r}, expected 3 finite numbers")
        return ConstantStanceVelocity(tuple(float(x) for x in v))
    if kind == "profile":
        tau = np.asarray(doc.get("tau"), float)
        vel = np.asarray(doc.get("velocity_m_s"), float)
        spread = np.asarray(doc.get("spread_m_s", np.zeros_like(vel)), float)
        if tau.ndim != 1 or len(tau) < 2 or np.any(np.diff(tau) <= 0) or tau[0] < 0 or tau[-1] > 1:
            raise ValueError(f"{path}: key 'tau' must be >= 2 increasing values in [0, 1]; got {doc.get('tau')!r}")
        if vel.shape != (len(tau), 3) or not np.all(np.isfinite(vel)):
            raise ValueError(f"{path}: key 'velocity_m_s' must be {len(tau)} rows of 3 finite numbers (m/s)")
        max_samples = doc.get("max_samples")
        if not isinstance(max_samples, int) or max_samples < 1:
            raise ValueError(f"{path}: key 'max_samples' = {max_samples!r}, expected a positive integer (samples)")
        return StanceVelocityProfile(tau, vel, spread, max_samples, doc.get("metadata", {}))
    raise ValueError(f"{path}: key 'type' = {kind!r}; allowed: 'constant', 'profile'")
