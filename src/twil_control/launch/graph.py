"""--graph: the running graph as rosnode list and rostopic list -v would show it."""

from __future__ import annotations


def print_graph(launch) -> None:
    bus = launch.master.bus
    print("Nodes:")
    for fqn in sorted(launch.master.nodes):
        print(f"  {fqn}")
    print("\nTopics:")
    for topic, msgtype in bus.topic_types().items():
        print(f"  {topic} [{msgtype}]")
        for pub in bus.publishers_of(topic):
            print(f"    publisher:  {pub}")
        for sub in bus.subscribers_of(topic):
            print(f"    subscriber: {sub}")
    if launch.master.services:
        print("\nServices:")
        for name, (node, _) in sorted(launch.master.services.items()):
            print(f"  {name} ({node})")
