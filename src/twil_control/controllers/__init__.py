"""Controller plugins that need Drake (robot models), and so live outside ros_control.

They glue `twil_control.control`'s laws and `twil_control.world`'s Drake models to ros_control's
Controller interface, and are found through the entry point group ``twil_control.controllers``
(pyproject.toml), as pluginlib finds a plugin library: ComputedTorqueController,
SkidSteerPwmController and CartLinearizingController (docs/ros_control.md).
"""
