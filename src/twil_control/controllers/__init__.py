"""Controller plugins that need Drake (robot models) and so live outside ros_control.

ros_control stays free of Drake and robotics math; these plugins glue the pure laws of
``twil_control.control`` and the Drake models of ``twil_control.world`` to its Controller
interface. They are found through the entry point group ``twil_control.controllers``
(pyproject.toml), as pluginlib finds a plugin library:

- effort_controllers/ComputedTorqueController (computed_torque_controller.py)
- twil_control/SkidSteerPwmController (skid_steer_pwm.py)
- twil_control/CartLinearizingController (cart_linearizing.py)
"""
