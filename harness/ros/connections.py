"""Which topics a node sends to a subscriber, asked of the node that publishes them.

A rospy subscriber counts a connection (``get_num_connections``) once the publisher has answered
requestTopic, before the TCP connection is made (tcpros_pubsub.create_transport), and the
publisher sends only on connections it has accepted: a message published in between is lost. A
replay that took the count for a connection waited 30 s for a text on a busy machine."""

import xmlrpc.client
from typing import Any, Set

import rosgraph
import rospy


def topics_sent_to(node_uri: str, subscriber: str) -> Set[str]:
    """The topics on which the node at ``node_uri`` has an accepted connection to the node named
    ``subscriber``, from its getBusInfo: [connection id, destination, direction, transport, topic,
    connected, info]. OSError or xmlrpc.client.Error when the node does not answer."""
    info: Any = xmlrpc.client.ServerProxy(node_uri).getBusInfo(subscriber)
    _, _, connections = info
    return {
        str(topic)
        for _, destination, direction, _, topic, connected, *_ in connections
        if destination == subscriber and direction == "o" and connected
    }


def reaches_us(topic: str) -> bool:
    """Whether ``topic`` has a publisher and each of them has accepted this node's subscription
    to it; False also while one cannot be asked (gone meanwhile)."""
    ours = rospy.get_caller_id()
    master = rosgraph.Master(ours)
    try:
        publishers, _, _ = master.getSystemState()
        nodes = [node for name, names in publishers if name == topic for node in names]
        return bool(nodes) and all(topic in topics_sent_to(master.lookupNode(node), ours) for node in nodes)
    except (OSError, xmlrpc.client.Error, rosgraph.MasterError):
        return False
