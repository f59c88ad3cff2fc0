"""gazebo's role: the simulated world. Creates the Drake plant and loads the world SDF."""
from __future__ import annotations

from dataclasses import dataclass

from .base import RosNode


@dataclass
class DrakeWorldParams:
    world: str                                   # SDF file of the world (floor and obstacles)
    time_step: float = 0.001                     # plant step, s (gazebo's max_step_size)
    contact_model: str = "point"
    discrete_contact_approximation: str = "lagged"
    penetration_allowance: float = 0.001
    stiction_tolerance: float = 1e-4
    sampled_output_ports: bool = False           # Drake's use_sampled_output_ports (world/simulation.py)


class DrakeWorld(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.params = self.typed_params(DrakeWorldParams)

    def make_simulation(self):
        from ..world.simulation import PlantSettings, Simulation
        p = self.params
        sim = Simulation(PlantSettings(
            time_step=p.time_step, contact_model=p.contact_model,
            discrete_contact_approximation=p.discrete_contact_approximation,
            penetration_allowance=p.penetration_allowance, stiction_tolerance=p.stiction_tolerance,
            sampled_output_ports=p.sampled_output_ports))
        sim.add_world(p.world)
        return sim
