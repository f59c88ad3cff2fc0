"""The simulator's side of the launch graph, as gazebo_ros is: the world node (gzserver), spawn_model,
the /gazebo services, the Gazebo plugins a robot description names (drives, sensors,
gazebo_ros_control), and the nodes that read the simulator directly (laser, ground truth, contact
monitor, RobotHWSim). ROS-role nodes that see only topics, parameters and tf live in nodes/."""
