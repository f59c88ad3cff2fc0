"""The plant's output ports computed when read (use_sampled_output_ports False in the project's
plant config, world/simulation.py): the plant steps as a discrete update, and the ros_control cycle runs half a period
after its steps, so that it still reads the state the last step made and drives the next one
(world/robot_hw_sim.py). Without that order the cycle would act one period late, which
tests/test_computed_torque.py's closed-form step response detects (9e-4 rad against 1e-4)."""

from __future__ import annotations

import numpy as np
from conftest import read_bag
from pydrake.multibody.plant import MultibodyPlantConfig

from twil_control import PACKAGE_ROOT
from twil_control.core.node import Master
from twil_control.launch.loader import load_launch
from twil_control.launch.node_types import BUILTIN, get
from twil_control.launch.runner import RunOptions, run
from twil_control.world.simulation import Simulation, plant_config

LAUNCH = PACKAGE_ROOT / "launch/qbot_sim.launch.yaml"
WORLD_TYPES = {
    (pkg, type_)
    for pkg, type_ in (key.split("/") for key, value in BUILTIN.items() if value.endswith(":DrakeWorld"))
}


def _world_node(plan) -> str:
    """The simulator node's name (the launch calls it /gazebo, as roslaunch users do)."""
    worlds = [n.fqn for n in plan.nodes if (n.pkg, n.type) in WORLD_TYPES]
    assert len(worlds) == 1, worlds
    return worlds[0]


def _joint_states(tmp_path, sampled: bool, labels: list | None = None):
    """The run's /joint_states; the controller manager's cycle labels (t, period) go to `labels`."""
    from twil_control.ros_control.controller_manager import ControllerManager

    update = ControllerManager.update_realtime

    def record(self, t, period):
        labels.append((t, period))
        return update(self, t, period)

    if labels is not None:
        ControllerManager.update_realtime = record
    seq = tmp_path / "seq.yaml"
    seq.write_text("rate: 20\nsegments:\n  - {time: 0.0, linear_x: 0.3}\n  - {time: 0.4, angular_z: 1.0}\n")
    plan = load_launch(LAUNCH, {"cmd_sequence": str(seq)})
    plan.params.set(f"{_world_node(plan)}/sampled_output_ports", sampled)
    bag = tmp_path / f"sampled_{sampled}.bag"
    try:
        result = run(plan, RunOptions(duration=1.0, bag=bag))
    finally:
        ControllerManager.update_realtime = update
    assert result.error is None, result.error
    return read_bag(bag)["/joint_states"]


def test_the_plant_samples_its_outputs_only_when_asked():
    assert plant_config().use_sampled_output_ports is False
    for sampled in (False, True):
        sim = Simulation(plant_config(use_sampled_output_ports=sampled))
        sim.finalize()
        assert sim.plant.has_sampled_output_ports() == sampled


def test_the_project_plant_is_drakes_config_with_point_contact_and_ports_read_on_demand():
    drake, ours = MultibodyPlantConfig(), plant_config()
    changed = {
        name
        for name in dir(drake)
        if not name.startswith("_")
        and not callable(getattr(drake, name))
        and getattr(drake, name) != getattr(ours, name)
    }
    assert changed == {"contact_model", "use_sampled_output_ports"}
    assert (ours.contact_model, ours.use_sampled_output_ports) == ("point", False)


def test_the_world_node_sets_only_the_plant_fields_its_parameters_give():
    plan = load_launch(LAUNCH, {"time_step": "0.002"})
    name = _world_node(plan)
    plan.params.set(f"{name}/sampled_output_ports", True)
    spec = plan.node(name)
    world = get(spec.pkg, spec.type)(
        Master(plan.params), spec.name, spec.namespace, spec.remappings, spec.args
    )
    sim = world.make_simulation()
    assert (sim.config.time_step, sim.config.use_sampled_output_ports) == (0.002, True)
    assert (sim.config.contact_model, sim.config.stiction_tolerance) == (
        "point",
        plant_config().stiction_tolerance,
    )
    assert world.sim_time_step == 0.002


def test_the_drive_runs_the_same_cycles_with_either_kind_of_plant_step(tmp_path):
    """Same stamps, same recording times, the same joint states (measured: identical bits); the
    cycles half a period after the plant's steps are labelled t_k = k * period to the bit, as
    the cycles at the plant's own step times were (event time minus h/2 misses it now and then)."""
    labels = []
    live, sampled = _joint_states(tmp_path, False, labels), _joint_states(tmp_path, True)
    period = labels[0][1]
    assert period == 0.001 and len(labels) == 1000
    assert [t for t, _ in labels] == [k * period for k in range(1000)]
    assert len(live) == len(sampled) == 100
    assert [t for t, _ in live] == [t for t, _ in sampled]
    for (_, a), (_, b) in zip(live, sampled):
        assert (a.header.stamp.sec, a.header.stamp.nanosec) == (b.header.stamp.sec, b.header.stamp.nanosec)
        for field in ("position", "velocity", "effort"):
            np.testing.assert_allclose(getattr(a, field), getattr(b, field), rtol=0, atol=1e-9)
    moved = np.abs(np.array(live[-1][1].position) - np.array(live[0][1].position)).max()
    assert moved > 0.5  # the wheels turned (rad): the comparison is not of a robot at rest
