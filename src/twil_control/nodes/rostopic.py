"""rostopic as a launch node: ``pub`` publishes as ``rostopic pub`` does, in simulated time; the
subcommands that only print (echo, hz, list, ...) are display nodes.

Node type ``rostopic/rostopic`` with the command line as its args (``pub [-1 | -r RATE] [-l]
[-s] TOPIC TYPE [VALUES ...]``; docs/ros1.md, "rostopic pub"). VALUES are YAML, one per word, as
rostopic reads them. The message is built and checked when the node is constructed, so a wrong
field stops the launch before time starts.
"""

from __future__ import annotations

import optparse
import shlex

import yaml

from ..core.messages import MessageTypeError, msg_class
from ..core.ros_node import NodeArgsError, RosNode
from .message_args import MessageArgsError, command_line_fields, displays_only
from .timed_pub import TimedPubError, build_message

#: s a ``rostopic pub -1`` stays after publishing (rostopic's _ONCE_DELAY)
ONCE_DELAY = 3.0
#: subcommands that only print what they see
DISPLAY_COMMANDS = ("echo", "hz", "bw", "delay", "info", "list", "type", "find")


class Rostopic(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.displays_only = displays_only(self, "rostopic", "pub", "publishes", DISPLAY_COMMANDS)
        if self.displays_only:
            return
        opts, words = self._parse(self.args[1:])
        self.topic, self.type = words[0], words[1]
        try:
            msg_class(self.type)
        except MessageTypeError as error:
            raise NodeArgsError(f"node {self.fqn}: rostopic pub {self.topic}: {error}") from None
        try:
            self.values = [yaml.safe_load(word) for word in words[2:]]
        except yaml.YAMLError as error:
            raise NodeArgsError(f"node {self.fqn}: rostopic pub: a value is not YAML: {error}") from None
        self.rate, self.once, self.substitute = opts.rate, opts.once, opts.substitute_keywords
        self.latch = self.rate is None or opts.latch  # rostopic latches unless it publishes at a rate
        self.msg = self._build(self.now())
        self.publisher = self.create_publisher(self.topic, self.type, latch=self.latch)
        self.published = 0
        self.exited = False

    def _parse(self, args: list[str]):
        parser = optparse.OptionParser(prog=f"{self.fqn} (rostopic pub)", add_help_option=False)
        parser.add_option("-v", dest="verbose", action="store_true", default=False)
        parser.add_option("-r", "--rate", dest="rate", default=None)
        parser.add_option("-1", "--once", dest="once", action="store_true", default=False)
        parser.add_option("-l", "--latch", dest="latch", action="store_true", default=False)
        parser.add_option("-s", "--substitute-keywords", dest="substitute_keywords", action="store_true")
        parser.add_option("--use-rostime", dest="use_rostime", action="store_true", default=False)
        parser.add_option("-f", "--file", dest="file", default=None)

        def fail(message: str):
            raise NodeArgsError(
                f"node {self.fqn}: rostopic pub: {message} (args: {shlex.join(self.args)!r}; "
                f"usage: pub [-1 | -r RATE] [-l] [-s] TOPIC TYPE [VALUES ...])"
            )

        parser.error = fail
        opts, words = parser.parse_args(args)
        if opts.file is not None:
            fail(
                "-f FILE is not supported here; rostopic/timed_pub publishes a file of messages at given times"
            )
        if opts.rate is not None:
            if opts.once:
                fail("-r and -1 (--once) exclude each other")
            try:
                opts.rate = float(opts.rate)
            except ValueError:
                fail(f"the rate {opts.rate!r} is not a number")
            if not 0 < opts.rate < float("inf"):
                fail(f"the rate must be a number of Hz > 0 (got {opts.rate})")
        if len(words) < 2:
            fail("give the topic and the message type" if not words else "give the message type")
        if len(words) == 2:
            fail("give the message values (YAML, for example '{linear: {x: 0.2}}'; '{}' for zeros)")
        return opts, words

    def _build(self, now: float):
        try:
            return build_message(self.type, command_line_fields(self.type, self.values, now), "message")
        except (MessageArgsError, TimedPubError) as error:
            raise NodeArgsError(f"node {self.fqn}: rostopic pub {self.topic} {self.type}: {error}") from None

    def on_start(self) -> None:
        if self.displays_only:
            return
        self._publish()
        if self.rate is not None:
            self.create_timer(1.0 / self.rate, lambda _event: self._publish())
        elif self.once:
            self._exit_timer = self.create_timer(ONCE_DELAY, self._exit)

    def _publish(self) -> None:
        if self.substitute:
            self.msg = self._build(self.now())
        self.publisher.publish(self.msg)
        self.published += 1

    def _exit(self, _event) -> None:
        """rostopic pub -1's process ends: its publisher, and with it the latched message, goes."""
        self._exit_timer.shutdown()
        self.publisher.unregister()
        self.exited = True
        self.log.info("published once; exited %.0f s later, as rostopic pub -1 does", ONCE_DELAY)
