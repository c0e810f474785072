"""Test hosts in network namespaces: one namespace per peer, joined by veth pairs to a bridge in
a switch namespace, and partitions made by dropping traffic with nft inside the peers'
namespaces (the TCP connections stay established, as across a real network split).

Needs root and iproute2; partitions need nftables. `why_not()` says what is missing (tests
exit 77, a CTest skip). Every namespace made is deleted by close(), whatever happened."""

import os
import shutil
import subprocess
import sys
import uuid

SKIP = 77  # CTest's skip code for these tests (SKIP_RETURN_CODE)


def run(*args, check=True, stdin=None):
    return subprocess.run(list(args), capture_output=True, text=True, check=check, timeout=30,
                          input=stdin)


class Namespaces:
    """A bridge namespace and one namespace per peer (address SUBNET.i on its eth0)."""

    def __init__(self, subnet):
        self.subnet = subnet
        self.tag = "csc" + uuid.uuid4().hex[:6]
        self.made = []
        self.switch = f"{self.tag}sw"
        self.peers = []  # namespace names, peer i (1-based) at index i - 1

    def add(self, name):
        run("ip", "netns", "add", name)
        self.made.append(name)
        run("ip", "-n", name, "link", "set", "lo", "up")

    def build(self, count, netem=None):
        """`count` peer namespaces; `netem`: tc netem arguments for every peer's egress."""
        self.add(self.switch)
        run("ip", "-n", self.switch, "link", "add", "br0", "type", "bridge")
        run("ip", "-n", self.switch, "link", "set", "br0", "up")
        for i in range(1, count + 1):
            ns = f"{self.tag}p{i}"
            self.add(ns)
            run("ip", "-n", self.switch, "link", "add", f"s{i}", "type", "veth", "peer", "name",
                "eth0", "netns", ns)
            run("ip", "-n", self.switch, "link", "set", f"s{i}", "master", "br0")
            run("ip", "-n", self.switch, "link", "set", f"s{i}", "up")
            run("ip", "-n", ns, "addr", "add", f"{self.subnet}.{i}/24", "dev", "eth0")
            run("ip", "-n", ns, "link", "set", "eth0", "up")
            if netem:
                run("tc", "-n", ns, "qdisc", "add", "dev", "eth0", "root", "netem", *netem)
            self.peers.append(ns)
        return self.peers

    def address(self, i):
        return f"{self.subnet}.{i}"

    def prefix(self, i):
        """The command prefix that runs a program as peer i."""
        return ["ip", "netns", "exec", self.peers[i - 1]]

    def partition(self, *groups):
        """Splits the peers into `groups` (lists of 1-based peer numbers; peers in no group are
        cut off from everyone): each peer drops every packet to or from the others' groups."""
        for group in groups:
            others = [self.address(j) for j in range(1, len(self.peers) + 1) if j not in group]
            for i in group:
                self._drop(i, others)
        grouped = {i for g in groups for i in g}
        for i in range(1, len(self.peers) + 1):
            if i not in grouped:
                self._drop(i, [self.address(j) for j in range(1, len(self.peers) + 1) if j != i])

    def _drop(self, i, addresses):
        self.heal_peer(i)
        if not addresses:
            return
        targets = ", ".join(addresses)
        rules = (f"table inet cscpart {{\n"
                 f"  chain in {{\n    type filter hook input priority 0;\n"
                 f"    ip saddr {{ {targets} }} drop\n  }}\n"
                 f"  chain out {{\n    type filter hook output priority 0;\n"
                 f"    ip daddr {{ {targets} }} drop\n  }}\n"
                 f"}}\n")
        run(*self.prefix(i), "nft", "-f", "-", stdin=rules)

    def heal_peer(self, i):
        run(*self.prefix(i), "nft", "delete", "table", "inet", "cscpart", check=False)

    def heal(self):
        for i in range(1, len(self.peers) + 1):
            self.heal_peer(i)

    def close(self):
        for name in reversed(self.made):
            run("ip", "netns", "del", name, check=False)
        self.made = []


def exit_unless_possible(cli, **needs):
    """Exits 77 saying why when namespaces with `needs` (why_not's arguments) cannot be made
    here, and 1 when `cli` (the csculpt binary) is missing."""
    reason = why_not(**needs)
    if reason:
        print(f"SKIP: {reason}", flush=True)
        sys.exit(SKIP)
    if not (os.path.exists(cli) or shutil.which(cli)):
        print(f"csculpt not found at {cli}", flush=True)
        sys.exit(1)


def why_not(tools=("ip",), netem=None, nft=False):
    """None if namespaces (with netem arguments `netem`, nft partitions if `nft`) can be made
    here, else why not."""
    if os.geteuid() != 0:
        return "needs root to create network namespaces"
    wanted = list(tools) + (["tc"] if netem else []) + (["nft"] if nft else [])
    for tool in wanted:
        if shutil.which(tool) is None:
            package = {"nft": "nftables"}.get(tool, "iproute2")
            return f"'{tool}' not found (Debian package {package})"
    probe = Namespaces("192.168.250")
    try:
        name = f"{probe.tag}probe"
        try:
            probe.add(name)
            run("ip", "-n", name, "link", "add", "pa", "type", "veth", "peer", "name", "pb")
        except subprocess.CalledProcessError as e:
            return f"cannot create a network namespace with a veth pair: {e.stderr.strip()}"
        if netem:
            try:
                run("tc", "-n", name, "qdisc", "add", "dev", "pa", "root", "netem", *netem)
            except subprocess.CalledProcessError as e:
                return f"tc netem unavailable ({e.stderr.strip()}; kernel module sch_netem)"
        if nft:
            try:
                run("ip", "netns", "exec", name, "nft", "-f", "-",
                    stdin="table inet probe {\n chain out {\n type filter hook output priority 0;\n }\n}\n")
            except subprocess.CalledProcessError as e:
                return f"nft unusable in a namespace ({e.stderr.strip()}; kernel nf_tables)"
        return None
    finally:
        probe.close()
