"""Collisions of a robot with its world, from the plant's contact results (what a bumper sees).

A contact pair counts when one body belongs to the robot and the other does not and is not one
of the `ground` bodies (the floor the wheels stand on). Point-pair and hydroelastic contacts are
both read, so the monitor works under either contact model. A static world model anchored to the
world body (world/static_world.py) is still named, and ignored as ground, by its own model and
link, through the simulation's `anchored_sources`.
"""
from __future__ import annotations

from pydrake.multibody.tree import ModelInstanceIndex
from pydrake.systems.framework import EventStatus, LeafSystem


class ContactMonitor(LeafSystem):
    """Every `period` s calls report(t, pairs) with the sorted (robot body, other body) names in
    contact, when there are any."""

    def __init__(self, sim, robot_instances, ground_models: set[str], period: float, report, clock) -> None:
        super().__init__()
        plant = sim.plant
        self._report = report
        self._clock = clock
        robot = {int(i) for i in robot_instances}
        self._robot_bodies: set[int] = set()
        self._ignored: set[int] = set()
        self._names: dict[int, str] = {}
        for k in range(plant.num_model_instances()):
            instance = ModelInstanceIndex(k)
            model = plant.GetModelInstanceName(instance)
            for b in plant.GetBodyIndices(instance):
                self._names[int(b)] = f"{model}::{plant.get_body(b).name()}"
                if k in robot:
                    self._robot_bodies.add(int(b))
                elif model in ground_models:
                    self._ignored.add(int(b))
        # static world models anchored to the world body (static_world): named by geometry
        self._anchored = {gid: f"{model}::{link}" for gid, (model, link) in sim.anchored_sources.items()
                          if model not in ground_models}
        self._anchored_ground = {gid for gid, (model, _) in sim.anchored_sources.items() if model in ground_models}
        self._inspector = sim.scene_graph.model_inspector()
        self._plant = plant
        self._contacts = self.DeclareAbstractInputPort(
            "contact_results", plant.get_contact_results_output_port().Allocate())
        self.DeclarePeriodicPublishEvent(period, 0.0, self._on_tick)

    def connect(self, sim) -> None:
        sim.builder.Connect(sim.plant.get_contact_results_output_port(), self._contacts)

    def _body_of_geometry(self, geometry_id) -> int:
        return int(self._plant.GetBodyFromFrameId(self._inspector.GetFrameId(geometry_id)).index())

    def _other(self, body: int, geometry_id) -> str | None:
        """The name of what a robot body touches, or None when it is ground or the robot."""
        if body in self._robot_bodies or body in self._ignored or geometry_id in self._anchored_ground:
            return None
        return self._anchored.get(geometry_id) or self._names[body]

    def _pair(self, a: int, id_a, b: int, id_b):
        if a in self._robot_bodies:
            other = self._other(b, id_b)
            return (self._names[a], other) if other else None
        if b in self._robot_bodies:
            other = self._other(a, id_a)
            return (self._names[b], other) if other else None
        return None

    def _on_tick(self, context) -> EventStatus:
        results = self._contacts.Eval(context)
        pairs = set()
        for i in range(results.num_point_pair_contacts()):
            info = results.point_pair_contact_info(i)
            pair = info.point_pair()
            p = self._pair(int(info.bodyA_index()), pair.id_A, int(info.bodyB_index()), pair.id_B)
            if p:
                pairs.add(p)
        for i in range(results.num_hydroelastic_contacts()):
            surface = results.hydroelastic_contact_info(i).contact_surface()
            m, n = surface.id_M(), surface.id_N()
            p = self._pair(self._body_of_geometry(m), m, self._body_of_geometry(n), n)
            if p:
                pairs.add(p)
        if pairs:
            t = context.get_time()
            self._clock.set(t)
            self._report(t, sorted(pairs))
        return EventStatus.Succeeded()
