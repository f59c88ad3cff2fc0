"""Keyboard teleops reading the launch's terminal (nodes/terminal_keys.py):
teleop_twist_keyboard's teleop_twist_keyboard.py and turtlebot3_teleop's turtlebot3_teleop_key,
with their keys, speeds and limits.

Keys are read as the simulation's time advances (each timer tick takes what was typed since the
last one), so drive by hand with ``--realtime 1`` or ``--view``; turtlebot3_teleop_key's command
moves half a step towards its target every 0.1 s, as the original's key poll does. Ctrl-C ends
the launch (docs/ros1.md).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import ClassVar

from ..core.messages import header, msg_class
from ..core.param_rules import param
from ..core.ros_node import RosNode
from .terminal_keys import TerminalKeys

MOVE = {
    "i": (1, 0, 0, 0),
    "o": (1, 0, 0, -1),
    "j": (0, 0, 0, 1),
    "l": (0, 0, 0, -1),
    "u": (1, 0, 0, 1),
    ",": (-1, 0, 0, 0),
    ".": (-1, 0, 0, 1),
    "m": (-1, 0, 0, -1),
    "O": (1, -1, 0, 0),
    "I": (1, 0, 0, 0),
    "J": (0, 1, 0, 0),
    "L": (0, -1, 0, 0),
    "U": (1, 1, 0, 0),
    "<": (-1, 0, 0, 0),
    ">": (-1, -1, 0, 0),
    "M": (-1, 1, 0, 0),
    "t": (0, 0, 1, 0),
    "b": (0, 0, -1, 0),
}
SPEED = {"q": (1.1, 1.1), "z": (0.9, 0.9), "w": (1.1, 1.0), "x": (0.9, 1.0), "e": (1.0, 1.1), "c": (1.0, 0.9)}
NO_TERMINAL = "%s reads keys from the launch's terminal; stdin is not one, so no keys are read"


def _twist(lx: float, ly: float, lz: float, az: float):
    vec = msg_class("geometry_msgs/Vector3")
    return msg_class("geometry_msgs/Twist")(
        linear=vec(x=float(lx), y=float(ly), z=float(lz)), angular=vec(x=0.0, y=0.0, z=float(az))
    )


@dataclass
class TeleopTwistKeyboardParams:
    ros_package: ClassVar[str] = "teleop_twist_keyboard"
    speed: float = param(0.5, finite=True)
    turn: float = param(1.0, finite=True)
    speed_limit: float = param(1000.0, finite=True)
    turn_limit: float = param(1000.0, finite=True)
    repeat_rate: float = param(0.0, ge=0)
    key_timeout: float = param(0.0, ge=0)
    stamped: bool = False
    frame_id: str = ""


class TeleopTwistKeyboard(RosNode):
    TICK = 0.01

    def __init__(self, *a, keys: TerminalKeys | None = None, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.params = self.typed_params(TeleopTwistKeyboardParams)
        self.keys = keys or TerminalKeys()
        msgtype = "geometry_msgs/TwistStamped" if p.stamped else "geometry_msgs/Twist"
        self._pub = self.create_publisher("cmd_vel", msgtype)
        self.speed, self.turn = p.speed, p.turn
        self.move = (0, 0, 0, 0)
        self._last_key = self.now()
        self._last_publish = self.now()
        if not self.keys.available:
            self.log.warning(NO_TERMINAL, self.fqn)
            return
        self.log.info(
            "Reading from the keyboard and Publishing to Twist! u i o / j k l / m , . to move, shift to "
            "strafe, t/b up/down, q/z w/x e/c speeds +-10%%, anything else stops; speed %s turn %s",
            self.speed,
            self.turn,
        )
        self.create_timer(self.TICK, self._tick)

    def _tick(self, event) -> None:
        now, p = self.now(), self.params
        updated = False
        for key in self.keys.read():
            self._last_key = now
            if key in MOVE:
                self.move = MOVE[key]
            elif key in SPEED:
                self.speed = min(p.speed_limit, self.speed * SPEED[key][0])
                self.turn = min(p.turn_limit, self.turn * SPEED[key][1])
                self.log.info("currently:\tspeed %s\tturn %s ", self.speed, self.turn)
            else:
                self.move = (0, 0, 0, 0)
            updated = True
        if p.key_timeout > 0 and now - self._last_key > p.key_timeout and any(self.move):
            self.move, updated = (0, 0, 0, 0), True
        repeat = p.repeat_rate > 0 and now - self._last_publish >= 1.0 / p.repeat_rate - 1e-9
        if updated or repeat:
            self._publish(now)

    def _publish(self, now: float) -> None:
        self._last_publish = now
        x, y, z, th = self.move
        twist = _twist(x * self.speed, y * self.speed, z * self.speed, th * self.turn)
        if self.params.stamped:
            twist = msg_class("geometry_msgs/TwistStamped")(
                header=header(self.params.frame_id, now), twist=twist
            )
        self._pub.publish(twist)

    def shutdown(self) -> None:
        self.keys.close()


LIMITS = {"burger": (0.22, 2.84), "waffle": (0.26, 1.82), "waffle_pi": (0.26, 1.82)}
LIN_STEP, ANG_STEP = 0.01, 0.1


def _toward(output: float, target: float, slop: float) -> float:
    """turtlebot3_teleop_key's makeSimpleProfile: at most `slop` closer to the target."""
    if target > output:
        return min(target, output + slop)
    if target < output:
        return max(target, output - slop)
    return target


class Turtlebot3TeleopKey(RosNode):
    PERIOD = 0.1

    def __init__(self, *a, keys: TerminalKeys | None = None, **kw) -> None:
        super().__init__(*a, **kw)
        self.model = str(self.get_param("model", "burger"))
        self.max_linear, self.max_angular = LIMITS.get(self.model, LIMITS["burger"])
        self.keys = keys or TerminalKeys()
        self._pub = self.create_publisher("cmd_vel", "geometry_msgs/Twist")
        self.target = [0.0, 0.0]
        self.control = [0.0, 0.0]
        if not self.keys.available:
            self.log.warning(NO_TERMINAL, self.fqn)
            return
        self.log.info(
            "Control Your TurtleBot3! w/x: linear velocity (%s: ~ %s), a/d: angular velocity (~ %s), "
            "space or s: stop",
            self.model,
            self.max_linear,
            self.max_angular,
        )
        self.create_timer(self.PERIOD, self._tick)

    def _tick(self, event) -> None:
        for key in self.keys.read():
            if key in "wx":
                step = LIN_STEP if key == "w" else -LIN_STEP
                self.target[0] = min(max(self.target[0] + step, -self.max_linear), self.max_linear)
            elif key in "ad":
                step = ANG_STEP if key == "a" else -ANG_STEP
                self.target[1] = min(max(self.target[1] + step, -self.max_angular), self.max_angular)
            elif key in " s":
                self.target, self.control = [0.0, 0.0], [0.0, 0.0]
            else:
                continue
            self.log.log(
                logging.INFO, "currently:\tlinear vel %s\t angular vel %s ", self.target[0], self.target[1]
            )
        self.control[0] = _toward(self.control[0], self.target[0], LIN_STEP / 2.0)
        self.control[1] = _toward(self.control[1], self.target[1], ANG_STEP / 2.0)
        self._pub.publish(_twist(self.control[0], 0.0, 0.0, self.control[1]))

    def shutdown(self) -> None:
        self.keys.close()
