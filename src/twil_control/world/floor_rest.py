"""Models spawned into the floor are lifted to rest on it before time starts.

gazebo_ros's spawn_model places a URDF's root link at the -z given, usually 0; for a robot whose
root is above its wheels (Husky's base_link) the wheels then start deep in the ground. Gazebo's
ODE pushes them out within its first steps (contact_max_correcting_vel); Drake's compliant
contact resolves such a depth over seconds, the wheels slipping meanwhile (a Husky commanded
1 m drove 0.80 m). So a floating model whose collision geometry starts inside the static world
with a vertical contact normal (a floor, not a wall) is raised by the deepest penetration.
"""

from __future__ import annotations

from pydrake.math import RigidTransform

#: penetrations below this (m) are contact, not a spawn into the floor
TOLERANCE = 1e-3
#: |normal z| above this: a floor-like contact
VERTICAL = 0.9


def floor_penetration(plant, plant_context, instances) -> float:
    """The deepest penetration (m) of `instances`' geometry into world-welded geometry, over
    contacts whose normal is near vertical; 0 if none."""
    query = plant.get_geometry_query_input_port().Eval(plant_context)
    inspector = query.inspector()
    fixed = {int(b.index()) for b in plant.GetBodiesWeldedTo(plant.world_body())}
    mine = {int(b) for instance in instances for b in plant.GetBodyIndices(instance)}
    deepest = 0.0
    for pair in query.ComputePointPairPenetration():
        a = int(plant.GetBodyFromFrameId(inspector.GetFrameId(pair.id_A)).index())
        b = int(plant.GetBodyFromFrameId(inspector.GetFrameId(pair.id_B)).index())
        if ((a in mine and b in fixed) or (b in mine and a in fixed)) and abs(pair.nhat_BA_W[2]) > VERTICAL:
            deepest = max(deepest, pair.depth)
    return deepest


def lift_out_of_floor(plant, plant_context, instances, root_body) -> float:
    """Raise floating `root_body` (of `instances`) by its floor penetration, in the context and as
    the default pose (resets start from it too); returns the lift (m), 0 if none was needed."""
    depth = floor_penetration(plant, plant_context, instances)
    if depth <= TOLERANCE:
        return 0.0
    pose = plant.GetFreeBodyPose(plant_context, root_body)
    lifted = RigidTransform(pose.rotation(), pose.translation() + [0.0, 0.0, depth])
    plant.SetFreeBodyPose(plant_context, root_body, lifted)
    plant.SetDefaultFloatingBaseBodyPose(root_body, lifted)
    return depth
