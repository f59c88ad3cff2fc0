"""The platform model (8) with K5..K8 derived from the description against the Drake plant.

TWIL + WAM rests on the default world's floor with the arm held at home by stiff implicit joint
PD (so the robot is one rigid body, as (8) assumes); a torque pair is applied to the wheels from
rest for 0.1 s and the platform's mean acceleration (forward and yaw, from the change of the
base's body twist) is compared with (8), u_dot = -f(u) + F tau, F = [[K7, K7], [K8, -K8]], at
the mean velocity. Over the first 20 ms the forward acceleration is up to twice (8)'s while the
wheels' contacts load up (contact compliance); from 50 ms on it settles on (8).

Measured (Drake 1.51.1, 1 ms steps): within 3.1% for the four pairs. Asserted: 5% (the issue's
bound).
"""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.multibody.tree import PdControllerGains

from twil_control.control.platform_model import derive_constants, dynamics
from twil_control.world.platform_dynamics import PlatformMassModel
from twil_control.world.simulation import Simulation

ARM = [f"wam_joint_{i}" for i in range(1, 8)]
WHEELS = ["right_wheel_joint", "left_wheel_joint"]
HOME = [0.0, -1.95, 0.0, 3.05, 0.0, 0.0, 0.0]
R, B = 0.075, 0.161


def _measured_acceleration(tau_pair, settle=0.3, push=0.1) -> tuple[np.ndarray, np.ndarray]:
    """(mean acceleration, mean velocity (u1, u2)) over `push` s of the pair from rest."""
    sim = Simulation()
    sim.add_world(sim_world())
    instances = sim.spawn("twil_wam", "twil_wam")
    plant = sim.plant
    for j in ARM:
        plant.GetJointActuatorByName(j).set_controller_gains(PdControllerGains(p=2e4, d=400.0))
    sim.finalize()
    simulator = sim.build()
    root = simulator.get_mutable_context()
    ctx = sim.plant_context(root)
    for j, q in zip(ARM, HOME):
        plant.GetJointByName(j).set_angle(ctx, q)
    for instance in instances:  # each instance's PD input: [q_desired, v_desired] of its actuators
        actuators = [plant.get_joint_actuator(i) for i in plant.GetJointActuatorIndices(instance)]
        desired = np.zeros(2 * len(actuators))
        for k, a in enumerate(actuators):
            if a.joint().name() in ARM:
                desired[k] = HOME[ARM.index(a.joint().name())]
        plant.get_desired_state_input_port(instance).FixValue(ctx, desired)
    u = np.zeros(plant.num_actuated_dofs())
    port = plant.get_actuation_input_port().FixValue(ctx, u)
    simulator.Initialize()
    simulator.AdvanceTo(settle)  # settle on the contacts with zero wheel torque
    base = plant.GetBodyByName("base_link")

    def body_twist():
        V = base.EvalSpatialVelocityInWorld(ctx)
        R_WB = base.EvalPoseInWorld(ctx).rotation().matrix()
        return np.array([(R_WB.T @ V.translational())[0], V.rotational()[2]])

    order = [int(i) for i in plant.GetJointActuatorIndices()]
    for name, tau in zip(WHEELS, tau_pair):
        u[order.index(int(plant.GetJointActuatorByName(name).index()))] = tau
    port.GetMutableData().set_value(u)
    before = body_twist()
    simulator.AdvanceTo(settle + push)
    after = body_twist()
    return (after - before) / push, (after + before) / 2


def sim_world():
    from twil_control.world.models import MODELS

    return MODELS["default_world"]


@pytest.mark.slow
@pytest.mark.parametrize("tau", [(2.0, 2.0), (2.0, -2.0), (3.0, 1.0), (-1.0, 2.5)])
def test_accelerations_predicted_by_8_match_the_plant_within_5_percent(tau):
    model = PlatformMassModel("twil_wam", ARM, WHEELS)
    mp = model.mass_properties(HOME)
    K = derive_constants(mp.mass, mp.yaw_inertia, mp.d, R, B, wheel_inertia=model.wheel_inertia)
    measured, u = _measured_acceleration(tau)
    predicted = np.array(dynamics(*u, *tau, *K.values()))
    size = np.abs(predicted).max()
    for k in range(2):  # forward and yaw: each within 5% of itself, or (when ~0) of the larger one
        bound = 0.05 * (abs(predicted[k]) if abs(predicted[k]) > 0.1 * size else size)
        assert abs(measured[k] - predicted[k]) <= bound, (tau, measured, predicted)
