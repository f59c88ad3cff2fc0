"""rosservice as a launch node: ``call`` calls a service once, as ``rosservice call`` does from a
terminal; the subcommands that only print (list, info, type, ...) are display nodes.

Node type ``rosservice/rosservice``, with the command line as its args::

    call [--wait] SERVICE [ARGS ...]

The call is made when time starts (every node built, their services advertised); with
``--wait`` a service not advertised yet is called as soon as it is (checked every 0.1 s of
simulated time), without it a missing service fails the node, as rosservice exits with an
error. ARGS are YAML, one per word: a mapping gives the request's fields by name, other values
its fields in order (``rosservice call /set_map "{map: ..., initial_pose: ...}"``; none for
std_srvs/Empty). The response is logged on one line, as rosservice prints it.
"""

from __future__ import annotations

import shlex

import yaml

from ..core.ros_node import NodeArgsError, RosNode
from .message_args import displays_only

#: subcommands that only print what they find
DISPLAY_COMMANDS = ("list", "info", "type", "find", "uri", "args")
WAIT_PERIOD = 0.1  # s of simulated time between looks for a --wait service


class Rosservice(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.displays_only = displays_only(self, "rosservice", "call", "calls a service", DISPLAY_COMMANDS)
        if self.displays_only:
            return
        words = self.args[1:]
        self.wait = "--wait" in words
        words = [w for w in words if w != "--wait"]
        if not words or words[0].startswith("-"):
            raise NodeArgsError(
                f"node {self.fqn}: rosservice call: give the service (args: {shlex.join(self.args)!r}; "
                "usage: call [--wait] SERVICE [ARGS ...])"
            )
        self.service = self.resolve(words[0])
        try:
            values = [yaml.safe_load(word) for word in words[1:]]
        except yaml.YAMLError as error:
            raise NodeArgsError(
                f"node {self.fqn}: rosservice call: an argument is not YAML: {error}"
            ) from None
        if len(values) == 1 and isinstance(values[0], dict):
            self.call_args, self.call_kwargs = [], values[0]
        else:
            self.call_args, self.call_kwargs = values, {}
        self.response = None
        self.called = False

    def on_start(self) -> None:
        if self.displays_only:
            return
        if self.wait and self.service not in self.master.services:
            self._timer = self.create_timer(WAIT_PERIOD, self._try)
            return
        self._call()

    def _try(self, _event) -> None:
        if self.service in self.master.services:
            self._timer.shutdown()
            self._call()

    def _call(self) -> None:
        self.response = self.master.call_service(self.service, *self.call_args, **self.call_kwargs)
        self.called = True
        self.log.info("called %s: %s", self.service, self.response)
