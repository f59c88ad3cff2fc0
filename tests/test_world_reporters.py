"""The world's reporters read the plant the cheap way and still report what its ports say:
BodyStateReporter's floating-body path (the plant's state, float arithmetic) against the
plant's body-pose and body-velocity ports through pydrake's rotations; the ContactMonitor seeing
the qbot pushed into a wall (its front wheels on wall_b_mid), under the point contact model and
under hydroelastic with its point-pair fallback, and nothing while it spins in free space."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.systems.primitives import ConstantVectorSource

from twil_control.core.node import Master
from twil_control.world.body_state import BodyStateReporter
from twil_control.world.contact_monitor import ContactMonitor
from twil_control.world.simulation import Simulation, plant_config

# qbot's actuators are ordered left_front, right_front, left_rear, right_rear: opposite torques
# per side spin it in place, equal torques drive it straight
SPIN = [-1.0, 1.0, -1.0, 1.0]
AHEAD = [0.3, 0.3, 0.3, 0.3]


def _qbot(world: str, torques, x: float = 0.0, yaw: float = 0.0, contact_model: str = "point") -> Simulation:
    from twil_control import PACKAGE_ROOT

    sim = Simulation(plant_config(contact_model=contact_model))
    sim.add_world(PACKAGE_ROOT / "sim/worlds" / world)
    sim.spawn("qbot", "qbot", x=x, yaw=yaw)
    sim.finalize()
    src = sim.builder.AddSystem(ConstantVectorSource(np.array(torques, dtype=float)))
    sim.builder.Connect(src.get_output_port(), sim.plant.get_actuation_input_port())
    return sim


def test_floating_body_state_equals_the_plant_ports():
    # the state's path (floating joint positions and velocities, float arithmetic) against what
    # the body-pose and body-velocity ports give through pydrake's rotations
    sim = _qbot("default.sdf", SPIN, yaw=2.5)
    plant = sim.plant
    body = plant.GetBodyByName("base_link")
    reporter = sim.add_system(BodyStateReporter(sim, body, 0.01, lambda *a: None, Master().clock))
    assert reporter._floating
    simulator = sim.build()
    root = simulator.get_mutable_context()
    state_w = []
    for t in (0.3, 0.9, 1.5, 2.5):  # spinning up: the pose and both velocities change
        simulator.AdvanceTo(t)
        position, quat, v_body, w_body = reporter.body_state(reporter.GetMyContextFromRoot(root))
        pc = sim.plant_context(root)
        X = plant.get_body_poses_output_port().Eval(pc)[int(body.index())]
        V = plant.get_body_spatial_velocities_output_port().Eval(pc)[int(body.index())]
        q = X.rotation().ToQuaternion()
        R_BW = X.rotation().inverse()
        assert position == tuple(X.translation())  # the joint's positions, bit for bit
        np.testing.assert_allclose(quat, [q.x(), q.y(), q.z(), q.w()], rtol=0, atol=1e-15)
        assert quat[3] >= 0.0
        np.testing.assert_allclose(v_body, R_BW @ V.translational(), rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(w_body, R_BW @ V.rotational(), rtol=1e-14, atol=1e-15)
        state_w.append(plant.GetPositions(pc)[body.floating_positions_start()])  # qw
    assert abs(w_body[2]) > 0.5  # it did spin (rad/s)
    # from yaw 2.5 it spins through pi, where the state's quaternion has w < 0 and the report
    # turns it to w >= 0, as ToQuaternion does
    assert min(state_w) < 0.0 < max(state_w)


def _contacts(torques, x: float, yaw: float, seconds: float, contact_model: str = "point") -> list:
    sim = _qbot("house.sdf", torques, x=x, yaw=yaw, contact_model=contact_model)
    seen = []
    sim.add_system(
        ContactMonitor(
            sim,
            sim.robot_instances("qbot"),
            {"floor", "ground_plane"},
            0.01,
            lambda t, pairs: seen.append((t, pairs)),
            Master().clock,
        )
    )
    sim.build().AdvanceTo(seconds)
    return seen


@pytest.mark.parametrize("contact_model", ["point", "hydroelastic_with_fallback"])
def test_contact_monitor_reports_the_qbot_pushed_into_a_wall(contact_model):
    # from x = 1.2 straight at the wall x = 2 (wall_b_mid, y -2.5..1.0): the front wheels, which
    # stand 0.03 m proud of the chassis, touch it first, after the 0.7 m run-up. The qbot's and
    # the house's shapes have no hydroelastic properties, so the second model asks SceneGraph
    # for contact surfaces and falls back to point pairs: the monitor's other query
    seen = _contacts(AHEAD, x=1.2, yaw=0.0, seconds=3.0, contact_model=contact_model)
    assert seen, "no contact reported"
    first_t, pairs = seen[0]
    assert 0.2 < first_t < 1.5
    assert pairs == [
        ("qbot::left_front_wheel_link", "wall_b_mid::wall_b_mid_link"),
        ("qbot::right_front_wheel_link", "wall_b_mid::wall_b_mid_link"),
    ]
    # pushed on, it stays at the wall: contacts in at least 90% of the later 100 Hz samples
    assert len(seen) >= 0.9 * ((3.0 - first_t) * 100 + 1)


def test_contact_monitor_is_silent_while_the_qbot_spins_in_free_space():
    assert _contacts(SPIN, x=0.0, yaw=0.0, seconds=1.0) == []


if __name__ == "__main__":  # pragma: no cover
    pytest.main([__file__, "-q"])
