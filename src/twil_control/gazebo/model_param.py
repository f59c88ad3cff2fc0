"""A node's ``model`` parameter (the spawned model it watches or drives), checked against the
models the launch spawned: a name that is not one is an error naming the node, the parameter,
where it was set and the models there are; and the contact watch the nodes that watch one
model's contacts (contact_monitor, collision_publisher) add with it."""

from __future__ import annotations

from ..core.params import param_error


def model_instances(node, sim, model: str, param: str = "model"):
    """The model instances of `model`, the value of `node`'s private parameter `param`."""
    if model in sim.robots:
        return sim.robot_instances(model)
    spawned = ", ".join(sim.robots) or "none yet (spawn_model comes first)"
    error = param_error(
        node.master.params, f"{node.fqn}/{param}", f"names no spawned model (spawned: {spawned})"
    )
    raise type(error)(f"node {node.fqn}: {error}") from None


def watch_contacts(node, sim, system_name: str) -> None:
    """Add to `sim` the contact sampler of `node` (its params `model`, `ground`, `update_rate`),
    which calls `node._on_contacts` with the pairs every 1 / update_rate s of simulated time."""
    from ..world.contact_monitor import ContactMonitor

    p = node.params
    sim.add_system(
        ContactMonitor(
            sim,
            model_instances(node, sim, p.model),
            set(p.ground),
            1.0 / p.update_rate,
            node._on_contacts,
            node.master.clock,
        ),
        f"{node.fqn}/{system_name}",
    )
