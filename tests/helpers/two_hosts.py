"""Two hosts on one machine: two network namespaces joined by a veth pair.

The "master host" holds roscore, the harness and soundDetection, the "node host" Speech Event, as
on the robot (its master on a laptop over Wi-Fi) or in the thesis (recognition on a second host).
Each namespace has its loopback and one end of the pair; the pair's addresses are the test's own
(a /30 in 10.213.0.0/16 picked from the process id), and nothing else is ever addressed.
Namespaces are removed at the end whatever happens; deleting a namespace deletes its veth end.
"""

import contextlib
import os
import signal
import subprocess
from dataclasses import dataclass
from typing import Iterator, List, Sequence

import pytest


@dataclass(frozen=True)
class Host:
    namespace: str
    link: str  # this host's end of the veth pair
    address: str

    def command(self, *command: str) -> List[str]:
        """``command`` run on this host (ip netns exec execs it: the process keeps its pid)."""
        return ["ip", "netns", "exec", self.namespace, *command]

    def ros_command(self, *command: str) -> List[str]:
        """``command`` as a ROS node of this host: it gives the master this host's address."""
        return self.command("env", f"ROS_IP={self.address}", *command)

    def ip(self, *arguments: str) -> None:
        _ip("-n", self.namespace, *arguments)


def _ip(*arguments: str) -> None:
    result = subprocess.run(["ip", *arguments], capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"ip {' '.join(arguments)}: {result.stderr.strip()}")


@dataclass(frozen=True)
class TwoHosts:
    master_host: Host
    node_host: Host

    def link_down(self) -> None:
        """As when Wi-Fi drops: the master host's end goes down, the node host sees no carrier
        (its own address stays, so its local subscribers can still reach it)."""
        self.master_host.ip("link", "set", self.master_host.link, "down")

    def link_up(self) -> None:
        self.master_host.ip("link", "set", self.master_host.link, "up")


def _create(hosts: Sequence[Host]) -> None:
    for host in hosts:
        _ip("netns", "add", host.namespace)
        host.ip("link", "set", "lo", "up")
    master_host, node_host = hosts
    master_host.ip(
        "link", "add", master_host.link, "type", "veth", "peer", node_host.link, "netns", node_host.namespace
    )
    for host in hosts:
        host.ip("addr", "add", f"{host.address}/30", "dev", host.link)
        host.ip("link", "set", host.link, "up")


def two_hosts() -> Iterator[TwoHosts]:
    """The namespaces for one test; the test fails, never skips, when they cannot be made."""
    tag = os.getpid() % 16384
    subnet = f"10.213.{tag // 64}.{(tag % 64) * 4}"
    base = subnet.rsplit(".", 1)[0] + "."
    last = int(subnet.rsplit(".", 1)[1])
    hosts = (
        Host(f"se{tag}master", f"se{tag}m", base + str(last + 1)),
        Host(f"se{tag}node", f"se{tag}n", base + str(last + 2)),
    )
    try:
        _create(hosts)
    except (RuntimeError, OSError) as problem:
        _remove(hosts)
        pytest.fail(
            f"cannot make two network namespaces joined by a veth pair (this test needs root, as CI "
            f"runs it, and the ip tool): {problem}",
            pytrace=False,
        )
    try:
        yield TwoHosts(*hosts)
    finally:
        _remove(hosts)


def _remove(hosts: Sequence[Host]) -> None:
    """Every process still on a host is killed (a namespace outlives its name while any process
    is in it), then the namespaces go, and the veth pair with them."""
    for host in hosts:
        pids = subprocess.run(["ip", "netns", "pids", host.namespace], capture_output=True, text=True)
        for pid in pids.stdout.split():
            with contextlib.suppress(ProcessLookupError):
                os.kill(int(pid), signal.SIGKILL)
        subprocess.run(["ip", "netns", "delete", host.namespace], capture_output=True)
