"""What the reference-program nodes share (cart_reference, joint_trajectory_reference): reading a
YAML program of timed joint segments, and the joints' first measured position it starts from."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from twil_control.errors import TwilControlError

from ..control.trajectory import SegmentChain
from ..core.paths import InputPathError, find_file
from ..core.ros_node import RosNode
from ..core.yaml_io import YamlError, display_path, load_yaml


class ProgramError(TwilControlError, ValueError):
    """A reference program that cannot be followed; the message names the file and entry."""


def program_path(file: str) -> Path:
    """A program file's path, found by core.paths' rule (the working directory, then the
    package root)."""
    try:
        return find_file(file, "reference program")
    except InputPathError as error:
        raise ProgramError(str(error)) from None


def read_entries(path: Path, allowed: set[str]) -> list[dict]:
    """The program's entries: a non-empty YAML list of mappings with keys among `allowed`
    ('time' required), times >= 0 and increasing."""
    where = f"reference program {display_path(path)}"
    try:
        entries = load_yaml(path)
    except YamlError as error:
        raise ProgramError(f"reference program: {error}") from None
    if not isinstance(entries, list) or not entries:
        raise ProgramError(f"{where}: expected a non-empty list of segments")
    last = -math.inf
    for i, e in enumerate(entries):
        here = f"{where}: segment {i}"
        if not isinstance(e, dict) or set(e) - allowed or "time" not in e:
            raise ProgramError(
                f"{here} must be a mapping with keys {sorted(allowed)} ('time' required), got {e!r}"
            )
        t = e["time"]
        if isinstance(t, bool) or not isinstance(t, (int, float)) or not (0 <= t < math.inf) or t <= last:
            raise ProgramError(f"{here}: time must be a number of seconds >= 0, increasing (got {t!r})")
        last = t
    return entries


def segment(
    entry: dict,
    where: str,
    n: int,
    positions_key: str,
    duration_key: str,
    default_duration: float,
    allow_step: bool,
) -> tuple[float, np.ndarray, float]:
    """(time, target positions, duration) of one entry, checked."""
    q = np.asarray(entry.get(positions_key, []), dtype=float)
    if q.shape != (n,) or not np.isfinite(q).all():
        raise ProgramError(
            f"{where}: {positions_key} must be {n} finite numbers, got {entry.get(positions_key)!r}"
        )
    d = entry.get(duration_key, default_duration)
    lowest = "0 s (0: a step)" if allow_step else "0 s"
    if (
        isinstance(d, bool)
        or not isinstance(d, (int, float))
        or not (d >= 0 if allow_step else d > 0)
        or not d < math.inf
    ):
        raise ProgramError(
            f"{where}: {duration_key} must be {'>=' if allow_step else '>'} {lowest}, got {d!r}"
        )
    return float(entry["time"]), q, float(d)


@dataclass
class ProgramParams:
    """The private params every program node takes."""

    file: str
    rate: float = 100.0
    joint_states: str = "/joint_states"


class ProgramNode(RosNode):
    """A node publishing a program's samples at its `rate`: `publish_at(t)` is the subclass's."""

    def start_program(self, p: ProgramParams, chain: SegmentChain, joints: list[str]) -> None:
        if not (math.isfinite(p.rate) and p.rate > 0):
            raise ProgramError(f"node {self.fqn}: rate must be > 0 Hz (got {p.rate!r})")
        self.chain, self._period = chain, 1.0 / p.rate
        MeasuredStart(self, p.joint_states, joints, chain)

    def on_start(self) -> None:
        self.create_timer(self._period, lambda event: self.publish_at(self.now()))

    def publish_at(self, t: float) -> None:
        raise NotImplementedError


class MeasuredStart:
    """Starts a SegmentChain from the first joint_states message that holds all its joints."""

    def __init__(self, node, topic: str, joints: list[str], chain: SegmentChain) -> None:
        self.joints, self.chain = list(joints), chain
        node.create_subscription(topic, "sensor_msgs/JointState", self._joint_states)

    def _joint_states(self, msg) -> None:
        if not self.chain.started:
            index = {name: i for i, name in enumerate(msg.name)}
            if all(j in index for j in self.joints):
                self.chain.start_from([msg.position[index[j]] for j in self.joints])
