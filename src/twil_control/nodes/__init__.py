"""ROS-role nodes: each sees only topics, parameters and tf, as a ROS node does (gmapping,
move_base, map_server, robot_state_publisher, ...); never the simulator (import contract
`ros-nodes`). The simulator's own nodes live in gazebo/."""
