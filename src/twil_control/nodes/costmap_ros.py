"""costmap_2d's Costmap2DROS inside move_base: the typed parameters of one costmap namespace
(global_costmap or local_costmap), in either style costmap_2d accepts (the pre-layer one of
hydro's compatibility, or plugins: [{name, type}] with each layer's own namespace; a VoxelLayer
is a 2-D obstacle layer), and the glue: /map into the static layer, laser scans posed from tf at
their time into the obstacle layer, periodic updates and OccupancyGrid publication.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from twil_control.errors import InputError

from ..control.transforms import yaw_from_quat
from ..core import names
from ..core.messages import header, msg_class, to_sec
from ..core.params import ParamError
from ..core.tf import TfError
from ..core.typed_params import load_typed
from ..core.yaml_io import parse_yaml
from ..navigation import costmap as cm
from ..navigation.footprint import parse_footprint, radius_footprint
from ..navigation.layered_costmap import LayerConfig, LayeredCostmap, Observation, StaticMap

PACKAGE = "costmap_2d"
LAYER_TYPES = {
    "costmap_2d::StaticLayer": "static",
    "costmap_2d::ObstacleLayer": "obstacle",
    "costmap_2d::VoxelLayer": "obstacle",
    "costmap_2d::InflationLayer": "inflation",
}


@dataclass
class ObservationSource:
    ros_package: ClassVar[str] = PACKAGE
    topic: str = ""
    sensor_frame: str = ""
    data_type: str = "LaserScan"
    marking: bool = True
    clearing: bool = False
    obstacle_range: float | None = None
    raytrace_range: float | None = None
    expected_update_rate: float = 0.0
    observation_persistence: float = 0.0
    min_obstacle_height: float = 0.0
    max_obstacle_height: float = 2.0
    inf_is_valid: bool = False

    def __post_init__(self) -> None:
        if self.data_type != "LaserScan":
            raise InputError(f"data_type {self.data_type!r} is not supported; allowed: LaserScan")


@dataclass
class StaticLayerParams:
    ros_package: ClassVar[str] = PACKAGE
    enabled: bool = True
    map_topic: str = "map"
    track_unknown_space: bool = True
    use_maximum: bool = False
    lethal_cost_threshold: int = 100
    unknown_cost_value: int = -1
    trinary_costmap: bool = True
    first_map_only: bool = False
    subscribe_to_updates: bool = False


@dataclass
class InflationLayerParams:
    ros_package: ClassVar[str] = PACKAGE
    enabled: bool = True
    inflation_radius: float = 0.55
    cost_scaling_factor: float = 10.0
    inflate_unknown: bool = False

    def __post_init__(self) -> None:
        cm.check_inflation(self.inflation_radius, self.cost_scaling_factor)


@dataclass
class CostmapParams:
    """Costmap2DROS's parameters (both styles); sensor and layer namespaces are added per use."""

    ros_package: ClassVar[str] = PACKAGE

    global_frame: str = "map"
    robot_base_frame: str = "base_link"
    update_frequency: float = 5.0
    publish_frequency: float = 0.0
    transform_tolerance: float = 0.3
    rolling_window: bool = False
    always_send_full_costmap: bool = False
    width: float = 10.0
    height: float = 10.0
    resolution: float = 0.05
    origin_x: float = 0.0
    origin_y: float = 0.0
    footprint: Any = None  # [[x, y], ...] (or its string form)
    robot_radius: float = 0.46
    footprint_padding: float = 0.01
    # pre-layer style
    # costmap_2d (since hydro) adds the static layer of a pre-layer costmap only when static_map
    # is set and true
    static_map: bool = False
    map_type: str = "costmap"
    map_topic: str = "map"
    track_unknown_space: bool = False
    lethal_cost_threshold: int = 100
    unknown_cost_value: int = -1
    trinary_costmap: bool = True
    obstacle_range: float = 2.5
    raytrace_range: float = 3.0
    max_obstacle_height: float = 2.0
    inflation_radius: float = 0.55
    cost_scaling_factor: float = 10.0
    observation_sources: str = ""
    footprint_clearing_enabled: bool = True
    # layered style
    plugins: list[dict] | None = None

    def __post_init__(self) -> None:
        for name in ("resolution", "width", "height"):
            if not getattr(self, name) > 0:
                raise InputError(f"{name} must be > 0 (got {getattr(self, name)})")
        if self.update_frequency < 0 or self.publish_frequency < 0:
            raise InputError("update_frequency and publish_frequency must be >= 0 Hz")
        if self.map_type not in ("costmap", "voxel"):
            raise InputError(f"map_type {self.map_type!r} is not supported; allowed: costmap, voxel")
        cm.check_inflation(self.inflation_radius, self.cost_scaling_factor)


def _footprint(p: CostmapParams) -> np.ndarray:
    fp = p.footprint
    if isinstance(fp, str):  # costmap_2d accepts the string form "[[x, y], ...]"
        fp = parse_yaml(fp, "footprint")[0]
    if fp is None or fp == []:
        return radius_footprint(p.robot_radius + p.footprint_padding)
    return parse_footprint(fp, p.footprint_padding)


@dataclass
class CostmapSetup:
    params: CostmapParams
    layers: LayerConfig
    sources: dict[str, ObservationSource]
    static: StaticLayerParams | None
    footprint: np.ndarray


def load_costmap_params(node, namespace: str) -> CostmapSetup:
    """Read one costmap namespace (e.g. ~global_costmap) with its sensor or layer namespaces."""
    server = node.master.params
    ns = names.resolve(namespace, node.namespace, node.name)

    def read(namespace: str, schema: type):
        return load_typed(server, namespace, schema, node.log.warning)

    raw = server.get(ns, {})
    extra: list[str] = []
    sources = str(raw.get("observation_sources", "")).split()
    plugins = raw.get("plugins")
    layer_names = [p.get("name", "") for p in plugins] if isinstance(plugins, list) else []
    extra = [
        n for n in sources + layer_names if n and n not in {f.name for f in dataclasses.fields(CostmapParams)}
    ]
    schema = dataclasses.make_dataclass(
        "CostmapParams", [(n, dict, field(default_factory=dict)) for n in extra], bases=(CostmapParams,)
    )
    p = read(ns, schema)
    fp = _footprint(p)
    if plugins is None:  # pre-layer style
        layers = LayerConfig(
            static=p.static_map,
            obstacles=bool(sources),
            inflation=True,
            obstacle_range=p.obstacle_range,
            raytrace_range=p.raytrace_range,
            inflation_radius=p.inflation_radius,
            cost_scaling_factor=p.cost_scaling_factor,
            footprint_clearing=p.footprint_clearing_enabled,
            track_unknown_space=p.track_unknown_space,
            lethal_cost_threshold=p.lethal_cost_threshold,
        )
        static = (
            StaticLayerParams(
                map_topic=p.map_topic,
                track_unknown_space=p.track_unknown_space,
                lethal_cost_threshold=p.lethal_cost_threshold,
                unknown_cost_value=p.unknown_cost_value,
                trinary_costmap=p.trinary_costmap,
            )
            if p.static_map
            else None
        )
        srcs = {s: read(names.join(ns, s), ObservationSource) for s in sources}
        return CostmapSetup(p, layers, srcs, static, fp)
    layers = LayerConfig(
        static=False, obstacles=False, inflation=False, track_unknown_space=p.track_unknown_space
    )
    static, srcs = None, {}
    for i, plugin in enumerate(plugins):
        if (
            not isinstance(plugin, dict)
            or set(plugin) - {"name", "type"}
            or "name" not in plugin
            or "type" not in plugin
        ):
            raise ParamError(
                f"{server.source_of(names.join(ns, 'plugins'))}: {ns}/plugins[{i}] must be "
                f"{{name: ..., type: ...}} (got {plugin!r})"
            )
        kind = LAYER_TYPES.get(plugin["type"])
        if kind is None:
            raise ParamError(
                f"{server.source_of(names.join(ns, 'plugins'))}: {ns}/plugins[{i}] has type "
                f"{plugin['type']!r}; allowed: {', '.join(LAYER_TYPES)}"
            )
        lns = names.join(ns, plugin["name"])
        if kind == "static":
            static = read(lns, StaticLayerParams)
            layers.static = static.enabled
            layers.track_unknown_space = static.track_unknown_space
            layers.lethal_cost_threshold = static.lethal_cost_threshold
        elif kind == "inflation":
            infl = read(lns, InflationLayerParams)
            layers.inflation = infl.enabled
            layers.inflation_radius, layers.cost_scaling_factor = (
                infl.inflation_radius,
                infl.cost_scaling_factor,
            )
        else:
            obs_raw = server.get(lns, {})
            obs_sources = str(obs_raw.get("observation_sources", "")).split()
            obs_schema = dataclasses.make_dataclass(
                "ObstacleLayerParams",
                [
                    ("enabled", bool, True),
                    ("observation_sources", str, ""),
                    ("obstacle_range", float, 2.5),
                    ("raytrace_range", float, 3.0),
                    ("track_unknown_space", bool, False),
                    ("footprint_clearing_enabled", bool, True),
                    ("max_obstacle_height", float, 2.0),
                    ("combination_method", int, 1),
                    ("origin_z", float, 0.0),
                    ("z_resolution", float, 0.2),
                    ("z_voxels", int, 10),
                    ("publish_voxel_map", bool, False),
                    ("mark_threshold", int, 0),
                    ("unknown_threshold", int, 15),
                ]
                + [(s, dict, field(default_factory=dict)) for s in obs_sources],
                namespace={"ros_package": PACKAGE},
            )
            op = read(lns, obs_schema)
            layers.obstacles = op.enabled
            layers.obstacle_range, layers.raytrace_range = op.obstacle_range, op.raytrace_range
            layers.footprint_clearing = op.footprint_clearing_enabled
            srcs.update({s: read(names.join(lns, s), ObservationSource) for s in obs_sources})
    return CostmapSetup(p, layers, srcs, static if layers.static else None, fp)


def pose2d(translation, quaternion) -> tuple[float, float, float]:
    return float(translation[0]), float(translation[1]), yaw_from_quat(quaternion)


class CostmapRos:
    """One costmap of move_base: inputs from /map, scans and tf; outputs on <name>/costmap."""

    def __init__(self, node, name: str, tf) -> None:
        self.node, self.name, self.tf = node, name, tf
        setup = load_costmap_params(node, "~" + name)
        self.setup = setup
        p = setup.params
        self.params = p
        self.costmap = LayeredCostmap(
            setup.footprint,
            p.resolution,
            setup.layers,
            p.width,
            p.height,
            p.rolling_window,
            (p.origin_x, p.origin_y),
        )
        self.map_frame = "map"
        self.have_map = setup.static is None  # before subscribing: a latched map arrives at once
        if setup.static is not None:
            node.create_subscription(setup.static.map_topic, "nav_msgs/OccupancyGrid", self._on_map)
        for sname, src in setup.sources.items():
            if not src.topic:
                raise ParamError(f"{name}/{sname}: observation source needs a topic")
            node.create_subscription(
                src.topic,
                "sensor_msgs/LaserScan",
                lambda msg, s=src, r=self._ranges(src): self._on_scan(msg, s, r),
            )
        self._pub = node.create_publisher(f"~{name}/costmap", "nav_msgs/OccupancyGrid")
        if p.update_frequency > 0:
            node.create_timer(1.0 / p.update_frequency, lambda e: self.update())
        if p.publish_frequency > 0:
            node.create_timer(1.0 / p.publish_frequency, lambda e: self.publish())

    def _ranges(self, src: ObservationSource):
        layers = self.setup.layers
        return (
            src.obstacle_range if src.obstacle_range is not None else layers.obstacle_range,
            src.raytrace_range if src.raytrace_range is not None else layers.raytrace_range,
        )

    def _on_map(self, msg) -> None:
        s = self.setup.static
        data = np.asarray(msg.data, dtype=np.int8).reshape(msg.info.height, msg.info.width)
        o = msg.info.origin
        q = (o.orientation.x, o.orientation.y, o.orientation.z, o.orientation.w)
        costs = cm.occupancy_to_cost(
            data, s.lethal_cost_threshold, s.track_unknown_space, s.trinary_costmap, s.unknown_cost_value
        )
        self.map_frame = msg.header.frame_id or "map"
        self.costmap.set_static_map(
            StaticMap(costs, float(msg.info.resolution), (o.position.x, o.position.y, yaw_from_quat(q)))
        )
        self.have_map = True

    def _on_scan(self, msg, src: ObservationSource, ranges) -> None:
        frame = src.sensor_frame or msg.header.frame_id
        try:
            transform = self.tf.lookup_transform(self.params.global_frame, frame, to_sec(msg.header.stamp))
        except TfError:
            try:  # the newest transform, as costmap_2d tolerates transform_tolerance of lag
                transform = self.tf.lookup_transform(self.params.global_frame, frame)
            except TfError as exc:
                self.node.log_once(30, f"scan-tf-{frame}", f"{self.name}: scan dropped: {exc}")
                return
        pose = pose2d(*transform)
        r = np.asarray(msg.ranges, dtype=float)
        angle_min = msg.angle_min
        qx, qy = transform[1][0], transform[1][1]
        if 1.0 - 2.0 * (qx * qx + qy * qy) < 0.0:
            # a laser mounted upside down (its z axis down): beam angles turn clockwise seen
            # from above, so the scan is read backwards from -angle_max (as tf projects it)
            angle_min = -(msg.angle_min + (len(r) - 1) * msg.angle_increment)
            r = r[::-1]
        if src.inf_is_valid:
            r = np.where(np.isinf(r), np.inf, r)
        self.costmap.add_observation(
            Observation(
                pose,
                r,
                angle_min,
                msg.angle_increment,
                msg.range_min,
                msg.range_max,
                src.marking,
                src.clearing,
                *ranges,
                source=src.topic,
                stamp=to_sec(msg.header.stamp),
                keep_time=src.observation_persistence,
            )
        )

    def robot_pose(self) -> tuple[float, float, float]:
        return pose2d(*self.tf.lookup_transform(self.params.global_frame, self.params.robot_base_frame))

    def update(self) -> bool:
        """Update the layers at the robot's pose; False when tf or the map is not there yet."""
        if not self.have_map:
            return False
        try:
            pose = self.robot_pose()
            T = (0.0, 0.0, 0.0)
            if self.setup.static is not None and self.map_frame != self.params.global_frame:
                T = pose2d(*self.tf.lookup_transform(self.map_frame, self.params.global_frame))
        except TfError as exc:
            self.node.log_once(30, f"tf-{self.name}", f"{self.name}: no robot pose yet ({exc})")
            return False
        self.costmap.update(pose, T)
        return True

    def publish(self) -> None:
        if not self.costmap.updated:
            return
        m = self.costmap.master
        h, w = m.shape
        info = msg_class("nav_msgs/MapMetaData")(
            map_load_time=header("", self.node.now()).stamp,
            resolution=float(m.resolution),
            width=w,
            height=h,
            origin=msg_class("geometry_msgs/Pose")(
                position=msg_class("geometry_msgs/Point")(x=float(m.origin[0]), y=float(m.origin[1]), z=0.0),
                orientation=msg_class("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
            ),
        )
        self._pub.publish(
            msg_class("nav_msgs/OccupancyGrid")(
                header=header(self.params.global_frame, self.node.now()),
                info=info,
                data=cm.cost_to_occupancy(m.costs).ravel(),
            )
        )
