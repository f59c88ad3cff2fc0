"""`bag play --view` as the bag CLI composes it: a Player on a new graph's bus, drawn by the view."""

from __future__ import annotations

from pathlib import Path

from twil_control.bag.play import Player
from twil_control.bag.reader import Bag
from twil_control.core.node import Master
from twil_control.view.bag_replay import replay_into_view
from twil_control.view.view_node import ViewOptions


def play_with_view(bag: Path, options: ViewOptions, rate: float = 1.0, **player_args):
    master = Master()
    player = Player(Bag(bag), bus=master.bus, rate=rate, **player_args)
    return replay_into_view(master, options, player.run)
