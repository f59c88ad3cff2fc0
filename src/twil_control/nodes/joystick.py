"""joy's joy_node and teleop_twist_joy's teleop_node (docs/ros1.md, "A robot's bring-up").

joy_node reads a Linux joystick device (8-byte js_event records) and publishes sensor_msgs/Joy;
without the device it says so once and tries again every second, as joy_node does. The device
is polled at 100 Hz of simulated time, so events are taken in order, at the time the simulation
reaches. teleop_node turns Joy into a Twist while the enable button is held, with
teleop_twist_joy's parameters.
"""

from __future__ import annotations

import logging
import os
import struct
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..core.messages import header, msg_class
from ..core.param_rules import param
from ..core.ros_node import RosNode

_EVENT = struct.Struct("<IhBB")  # time (ms), value, type, number
_BUTTON, _AXIS, _INIT = 0x01, 0x02, 0x80


@dataclass
class JoyParams:
    ros_package: ClassVar[str] = "joy"
    no_effect: ClassVar[dict] = {
        "dev_ff": ("/dev/input/event0", "force feedback is not simulated"),
        "dev_name": ("", "devices are opened by ~dev only"),
        "sticky_buttons": (False, "sticky buttons are not simulated"),
    }
    dev: str = "/dev/input/js0"
    dev_ff: str = "/dev/input/event0"
    dev_name: str = ""
    deadzone: float = param(0.05, ge=0, lt=1)
    autorepeat_rate: float = param(0.0, ge=0)
    coalesce_interval: float = param(0.001, ge=0)
    default_trig_val: bool = False
    sticky_buttons: bool = False


def scale_axis(value: int, deadzone: float) -> float:
    """joy_node's axis value in [-1, 1] from a raw js_event value (the sign turned: up is +)."""
    dead = 32767.0 * deadzone
    v = float(value)
    v = v - dead if v > dead else (v + dead if v < -dead else 0.0)
    return v * -1.0 / (1.0 - deadzone) / 32767.0


class JoyNode(RosNode):
    POLL = 0.01

    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.params = self.typed_params(JoyParams)
        self._pub = self.create_publisher("joy", "sensor_msgs/Joy")
        self.fd: int | None = None
        self.axes: list[float] = []
        self.buttons: list[int] = []
        self._next_open = 0.0
        self._last_publish = -1e9
        self._seen = False
        self.create_timer(self.POLL, self._poll)

    def _open(self, now: float) -> None:
        self._next_open = now + 1.0
        try:
            self.fd = os.open(self.params.dev, os.O_RDONLY | os.O_NONBLOCK)
        except OSError:
            self.log_once(
                logging.WARNING,
                "no device",
                f"Couldn't open joystick {self.params.dev}. Will retry every second.",
            )
            return
        self.log.info("Opened joystick: %s. deadzone_: %f.", self.params.dev, self.params.deadzone)

    def _poll(self, event) -> None:
        now = self.now()
        if self.fd is None:
            if now >= self._next_open:
                self._open(now)
            return
        changed = False
        while True:
            try:
                data = os.read(self.fd, _EVENT.size * 64)
            except BlockingIOError:
                break
            except OSError:
                self.log.warning("Connection to joystick device lost unexpectedly. Will reopen.")
                os.close(self.fd)
                self.fd = None
                return
            if not data:
                break
            for i in range(0, len(data) - _EVENT.size + 1, _EVENT.size):
                changed |= self._event(*_EVENT.unpack_from(data, i))
        rate = self.params.autorepeat_rate
        self._seen |= changed  # joy_node repeats only once the device has said something
        if changed or (self._seen and rate > 0 and now - self._last_publish >= 1.0 / rate - 1e-9):
            self._publish(now)

    def _event(self, _time: int, value: int, kind: int, number: int) -> bool:
        kind &= ~_INIT
        if kind == _BUTTON:
            while len(self.buttons) <= number:
                self.buttons.append(0)
            self.buttons[number] = 1 if value else 0
            return True
        if kind == _AXIS:
            while len(self.axes) <= number:
                self.axes.append(0.0)
            self.axes[number] = scale_axis(value, self.params.deadzone)
            return True
        return False

    def _publish(self, now: float) -> None:
        self._last_publish = now
        self._pub.publish(
            msg_class("sensor_msgs/Joy")(
                header=header(self.params.dev, now),
                axes=np.array(self.axes, dtype=np.float32),
                buttons=np.array(self.buttons, dtype=np.int32),
            )
        )

    def shutdown(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None


LINEAR = ("x", "y", "z")
ANGULAR = ("yaw", "pitch", "roll")


@dataclass
class TeleopTwistJoyParams:
    ros_package: ClassVar[str] = "teleop_twist_joy"
    enable_button: int = 0
    enable_turbo_button: int = -1
    axis_linear: int | dict[str, int] = 1
    scale_linear: float | dict[str, float] = 0.5
    scale_linear_turbo: float | dict[str, float] = 1.0
    axis_angular: int | dict[str, int] = 0
    scale_angular: float | dict[str, float] = 0.5
    scale_angular_turbo: float | dict[str, float] | None = None


def _mapping(value, first: str) -> dict:
    return dict(value) if isinstance(value, dict) else {first: value}


class TeleopTwistJoy(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.params = self.typed_params(TeleopTwistJoyParams)
        self.axis_linear = _mapping(p.axis_linear, "x")
        self.axis_angular = _mapping(p.axis_angular, "yaw")
        turbo_angular = p.scale_angular if p.scale_angular_turbo is None else p.scale_angular_turbo
        self.scales = {
            "normal": (_mapping(p.scale_linear, "x"), _mapping(p.scale_angular, "yaw")),
            "turbo": (_mapping(p.scale_linear_turbo, "x"), _mapping(turbo_angular, "yaw")),
        }
        self._pub = self.create_publisher("cmd_vel", "geometry_msgs/Twist")
        self.create_subscription("joy", "sensor_msgs/Joy", self._on_joy)
        self.sent_disable = False
        self.log.info("Teleop enable button %d.", p.enable_button)

    @staticmethod
    def _value(joy, axes: dict, scales: dict, name: str) -> float:
        if name not in axes or name not in scales or not 0 <= axes[name] < len(joy.axes):
            return 0.0
        return float(joy.axes[axes[name]]) * float(scales[name])

    def _twist(self, joy, which: str):
        linear, angular = self.scales[which]
        vec = msg_class("geometry_msgs/Vector3")
        lx, ly, lz = (self._value(joy, self.axis_linear, linear, n) for n in LINEAR)
        yaw, pitch, roll = (self._value(joy, self.axis_angular, angular, n) for n in ANGULAR)
        return msg_class("geometry_msgs/Twist")(
            linear=vec(x=lx, y=ly, z=lz), angular=vec(x=roll, y=pitch, z=yaw)
        )

    def _pressed(self, joy, button: int) -> bool:
        return 0 <= button < len(joy.buttons) and bool(joy.buttons[button])

    def _on_joy(self, joy) -> None:
        p = self.params
        if p.enable_turbo_button >= 0 and self._pressed(joy, p.enable_turbo_button):
            self._pub.publish(self._twist(joy, "turbo"))
            self.sent_disable = False
        elif self._pressed(joy, p.enable_button):
            self._pub.publish(self._twist(joy, "normal"))
            self.sent_disable = False
        elif not self.sent_disable:
            vec = msg_class("geometry_msgs/Vector3")
            zero = vec(x=0.0, y=0.0, z=0.0)
            self._pub.publish(msg_class("geometry_msgs/Twist")(linear=zero, angular=zero))
            self.sent_disable = True
