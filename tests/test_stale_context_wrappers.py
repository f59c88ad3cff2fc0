"""No Python object outlives a launch's diagram holding one of its contexts (through a view into
Drake's memory). pybind hands a still-registered wrapper out again for the next object made at
the same address and deletes the new object, so a stale context wrapper made a later plant's
context dangle: GetPositionsAndVelocities segfaulted after a qbot launch was dropped (4 runs in
4 before the laser scene copied its static poses). Run in a child process: a crash must fail
this test, not end the suite."""

from __future__ import annotations

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent("""
    from twil_control import PACKAGE_ROOT
    from twil_control.launch.loader import load_launch
    from twil_control.launch.runner import Launch

    def drive_and_drop():
        launch = Launch(load_launch(PACKAGE_ROOT / "launch/qbot_sim.launch.yaml", {}))
        launch.build()
        launch.start()
        launch.simulator.AdvanceTo(0.5)
        launch.shutdown()

    drive_and_drop()
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant
    from twil_control.world import models
    for _ in range(3):
        plant = MultibodyPlant(time_step=0.0)
        models.add_model(plant, "twil_wam", parser=Parser(plant))
        plant.Finalize()
        context = plant.CreateDefaultContext()
        assert len(plant.GetPositionsAndVelocities(context)) == plant.num_multibody_states()
    print("ok")
""")


def test_a_plant_made_after_a_dropped_launch_gets_a_context_of_its_own():
    done = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and done.stdout.strip().endswith("ok"), (done.returncode, done.stderr[-2000:])
