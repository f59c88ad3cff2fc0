"""Robot descriptions and worlds as a ROS 1 user writes them, pure (no Drake): xacro, URDF with
its ``<gazebo>`` tags and ``<transmission>``s, Gazebo worlds and SDF models as Gazebo reads them
(gazebo_world, sdf_robot), and meshes converted to what the simulator reads."""
