"""Installs the twil_control package from src/ (catkin's setup.py role)."""

from setuptools import find_packages, setup

setup(
    name="twil_control",
    version="0.1.0",
    description="ROS 1 style workspace for the TWIL mobile manipulator and qbot, simulated in Drake",
    package_dir={"": "src"},
    packages=find_packages("src"),
    package_data={
        "twil_control": ["msg/*.msg", "share/**/*"]
    },  # share/: provided ROS packages, Gazebo's stock worlds and models
    python_requires=">=3.11",
    install_requires=[
        "drake==1.51.1",
        "rosbags==0.11.9",
        "numpy>=2.0,<3",
        "pyyaml>=6.0",
        "opencv-python-headless>=4.8",
        "ompl==2.0.1",
        "scipy>=1.11",
        "matplotlib>=3.8",
        # bag tables (export) and sweeps
        "pandas>=2.2",
        "pyarrow>=15",
        "rosbags-dataframe==0.10.2",
        "dask[distributed]==2026.8.0",
        # JIT for the measured hot loops of the laser and the SLAM scan matcher
        "numba==0.68.1",
        # --foxglove: the Foxglove WebSocket server
        "foxglove-sdk==0.30.3",
        # its server's own port speaks TLS with a certificate made per run (foxglove/front_door.py)
        "cryptography==50.0.2",
        # MCAP recordings and bag convert (zstd chunks)
        "mcap==1.6.0",
        "zstandard>=0.22",
        # LZ4 chunks of ROS 1 bags, read and written here (bag/format.py)
        "lz4==4.4.5",
        # users' robot descriptions: xacro run in-process, STL/OBJ/DAE meshes converted to OBJ
        "xacro==2.1.1",
        "trimesh==5.2.0",
        "pycollada==0.9.3",
        # trimesh imports it to decode a text STL; it does not declare it
        "charset-normalizer==3.4.7",
        # roslaunch XML read safely (no entity expansion, no external entities)
        "defusedxml==0.7.1",
    ],
    extras_require={
        "test": [
            "pytest>=8",
            "sympy>=1.12",
            "selenium==4.51.0",
            # the tests' Foxglove protocol client; an MCAP reader not written here
            "websocket-client==1.9.2",
            "mcap-ros1-support==0.9.0",
            # the layer contracts and the lint rules of pyproject.toml (tests/test_layers.py)
            "import-linter==2.16",
            "ruff==0.17.5",
        ]
    },
    entry_points={
        "console_scripts": [
            "twil-launch=twil_control.launch.__main__:main",
        ],
        # Controller plugins outside ros_control (pluginlib's plugin XML role).
        "twil_control.controllers": [
            "effort_controllers/ComputedTorqueController="
            "twil_control.controllers.computed_torque_controller:ComputedTorqueController",
            "twil_control/SkidSteerPwmController="
            "twil_control.controllers.skid_steer_pwm:SkidSteerPwmController",
            "twil_control/CartLinearizingController="
            "twil_control.controllers.cart_linearizing:CartLinearizingController",
        ],
    },
)
