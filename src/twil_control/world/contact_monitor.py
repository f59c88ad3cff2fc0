"""Collisions of a robot with its world, from the geometry's contacts (what a bumper sees).

A pair counts when one body is the robot's and the other is neither the robot's nor one of the
`ground` bodies. The pairs are asked of the query object (the pairs the contact solver is
given), not read from the plant's contact results: with output ports computed when read
(world/simulation.py) those are the coming step's, and reading them would solve that step's
contact problem once more at every sample. Anchored static models keep their own names through
the simulation's `anchored_sources`.
"""

from __future__ import annotations

from pydrake.common.value import AbstractValue
from pydrake.geometry import QueryObject, Role
from pydrake.multibody.plant import ContactModel
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
        robot_bodies: set[int] = set()
        ignored: set[int] = set()
        body_names: dict[int, str] = {}
        for k in range(plant.num_model_instances()):
            instance = ModelInstanceIndex(k)
            model = plant.GetModelInstanceName(instance)
            for b in plant.GetBodyIndices(instance):
                body_names[int(b)] = f"{model}::{plant.get_body(b).name()}"
                if k in robot:
                    robot_bodies.add(int(b))
                elif model in ground_models:
                    ignored.add(int(b))
        # per proximity geometry: its robot body's name, or what it names as the other side
        # (None: ground). Kept as plain names, not the inspector, which must not outlive the
        # diagram (a stale pydrake wrapper can be handed out for a new object: laser_scene.py)
        inspector = sim.scene_graph.model_inspector()
        anchored = sim.anchored_sources  # a dict built per call: once, not per geometry
        self._robot: dict = {}
        self._other: dict = {}
        for gid in inspector.GetAllGeometryIds(Role.kProximity):
            body = int(plant.GetBodyFromFrameId(inspector.GetFrameId(gid)).index())
            if body in robot_bodies:
                self._robot[gid] = body_names[body]
            elif gid in anchored:  # static world model anchored to the world body
                model, link = anchored[gid]
                self._other[gid] = None if model in ground_models else f"{model}::{link}"
            else:
                self._other[gid] = None if body in ignored else body_names[body]
        for gid, shape in sim.windowed_shapes:  # static shapes whose role follows the robots
            self._other[gid] = None if shape.model in ground_models else f"{shape.model}::{shape.link}"
        self._model = plant.get_contact_model()
        self._representation = plant.get_contact_surface_representation()
        self._query = self.DeclareAbstractInputPort("query", AbstractValue.Make(QueryObject()))
        self.DeclarePeriodicPublishEvent(period, 0.0, self._on_tick)

    def connect(self, sim) -> None:
        sim.builder.Connect(sim.scene_graph.get_query_output_port(), self._query)

    def _geometry_pairs(self, query) -> list:
        """(id_A, id_B) of the overlapping geometries, as the plant's contact model finds them."""
        if self._model in (ContactModel.kPoint, ContactModel.kPointContactOnly):
            return [(p.id_A, p.id_B) for p in query.ComputePointPairPenetration()]
        if self._model in (ContactModel.kHydroelastic, ContactModel.kHydroelasticsOnly):
            surfaces, points = query.ComputeContactSurfaces(self._representation), []
        else:
            surfaces, points = query.ComputeContactSurfacesWithFallback(self._representation)
        return [(s.id_M(), s.id_N()) for s in surfaces] + [(p.id_A, p.id_B) for p in points]

    def _pair(self, id_a, id_b):
        """(robot body, other body) names, or None when neither or both are the robot's, or the
        other is ground."""
        if id_a in self._robot:
            other = self._other.get(id_b)
            return (self._robot[id_a], other) if other else None
        if id_b in self._robot:
            other = self._other.get(id_a)
            return (self._robot[id_b], other) if other else None
        return None

    def _on_tick(self, context) -> EventStatus:
        pairs = set()
        for id_a, id_b in self._geometry_pairs(self._query.Eval(context)):
            p = self._pair(id_a, id_b)
            if p:
                pairs.add(p)
        if pairs:
            t = context.get_time()
            self._clock.set(t)
            self._report(t, sorted(pairs))
        return EventStatus.Succeeded()
