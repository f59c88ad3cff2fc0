"""The cart launch's ROS graph against the paper's Fig. 7 ("ROS nodes for the simulation of the
proposed controller"), as the paper's text describes the figure (Section 4.2):

- ``/gazebo`` is the simulator; the topics whose names start with ``/gazebo`` set or verify the
  simulation (Gazebo's set_model_state / set_link_state in, model_states / link_states out);
- ``/twil/ros_control/controller_spawner`` is the node that loads the two controllers;
- ``/joint_states`` and ``/twil/ros_control/cart_linearizing_controller/command`` are connected
  to ``/gazebo``, because the controllers are plugins loaded in the /gazebo node: it publishes
  the joint states and subscribes to the controller's command.

The launch has more nodes than the figure (the reference publisher, odometry, ground truth,
robot_state_publisher): the figure's nodes must be there with exactly the figure's edges among
the figure's topics, and /gazebo may add only /clock, /rosout and the controller's status topic.
"""

from __future__ import annotations

import io
from contextlib import redirect_stdout

from twil_control import PACKAGE_ROOT
from twil_control.launch.graph import print_graph
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import Launch

COMMAND = "/twil/ros_control/cart_linearizing_controller/command"
FIGURE_7 = {
    "/gazebo": {
        "publishes": {"/joint_states", "/gazebo/model_states", "/gazebo/link_states"},
        "subscribes": {COMMAND, "/gazebo/set_model_state", "/gazebo/set_link_state"},
    },
    "/twil/ros_control/controller_spawner": {"publishes": set(), "subscribes": set()},
}
FIGURE_TOPICS = {
    "/joint_states",
    COMMAND,
    "/gazebo/model_states",
    "/gazebo/link_states",
    "/gazebo/set_model_state",
    "/gazebo/set_link_state",
}


def test_cart_launch_graph_reads_like_fig_7():
    launch = Launch(load_launch(PACKAGE_ROOT / "launch/twil_cart_linearizing.launch.yaml"))
    launch.build()
    launch.start()
    bus = launch.master.bus
    try:
        assert set(FIGURE_7) <= set(launch.master.nodes)
        for node, edges in FIGURE_7.items():
            publishes = {t for t in bus.topic_types() if node in bus.publishers_of(t)}
            subscribes = {t for t in bus.topic_types() if node in bus.subscribers_of(t)}
            assert publishes & FIGURE_TOPICS == edges["publishes"], node
            assert subscribes & FIGURE_TOPICS == edges["subscribes"], node
            own = {t for t in publishes | subscribes if t not in FIGURE_TOPICS}
            if node == "/gazebo":
                assert own <= {"/clock", "/rosout", "/twil/ros_control/cart_linearizing_controller/status"}
            else:
                assert own <= {"/rosout"}
        # the controller manager's services belong to /gazebo too (the plugin's), as in Gazebo
        assert launch.master.services["/twil/ros_control/controller_manager/load_controller"][0] == "/gazebo"
        out = io.StringIO()
        with redirect_stdout(out):
            print_graph(launch)
        text = out.getvalue()
        assert f"  {COMMAND} [twil_control/CartLinearizingCommand]\n" in text
        assert "  /joint_states [sensor_msgs/JointState]\n    publisher:  /gazebo\n" in text
    finally:
        launch.shutdown()
