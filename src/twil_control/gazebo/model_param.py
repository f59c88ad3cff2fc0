"""A node's ``model`` parameter (the spawned model it watches or drives), checked against the
models the launch spawned: a name that is not one is an error naming the node, the parameter,
where it was set and the models there are."""

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
