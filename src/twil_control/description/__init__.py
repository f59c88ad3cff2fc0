"""Robot descriptions as a ROS 1 user writes them, pure (no Drake): xacro, URDF with its
``<gazebo>`` tags and ``<transmission>``s, and meshes converted to what the simulator reads."""
