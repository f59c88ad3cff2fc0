"""The standard controllers of ros_controllers (ROS 1), registered by their ROS type names.

- joint_state_controller/JointStateController
- diff_drive_controller/DiffDriveController
- effort_controllers/JointEffortController, JointGroupEffortController, JointPositionController
- velocity_controllers/JointVelocityController, JointGroupVelocityController
- position_controllers/JointPositionController, JointGroupPositionController
"""

from . import diff_drive_controller, effort_controllers, forward_command, joint_state_controller  # noqa: F401  (they register)
