#!/usr/bin/env python3
"""Three `csculpt peer` processes, each in its own network namespace, joined by veth pairs to a
bridge in a fourth namespace, every link delayed 200 ms with 5% loss by `tc netem`: they still
converge and lose no edit.

Needs root, iproute2 (`ip netns`, `tc`) and the kernel's netem qdisc; otherwise exits 77 (CTest
reports a skip) saying what is missing. Every namespace made is deleted whatever happens.
Addresses (192.168.251.0/24) exist only inside the namespaces made here.

CSCULPT_NETEM_OPTIONAL=1 runs the same topology without netem where netem is missing (to check
the namespace plumbing on such a machine)."""

import os
import shutil
import subprocess
import sys
import unittest
import uuid

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sessionlib import CLI, Peer, finish, report, wait_converged  # noqa: E402

SKIP = 77
SUBNET = "192.168.251"
NETEM = ["delay", "200ms", "loss", "5%"]
# Thresholds for a 400 ms round trip with TCP retransmissions after losses (a lost SYN waits 1 s).
SLOW = ["--sync-ms", "250", "--heartbeat-ms", "200", "--evasive-ms", "2000",
        "--expired-ms", "6000", "--join-timeout-ms", "60000"]
TAG = "csc" + uuid.uuid4().hex[:6]


def run(*args, check=True):
    return subprocess.run(list(args), capture_output=True, text=True, check=check, timeout=30)


class Namespaces:
    """A bridge namespace and one namespace per peer; deleted on close()."""

    def __init__(self):
        self.made = []
        self.switch = f"{TAG}sw"

    def add(self, name):
        run("ip", "netns", "add", name)
        self.made.append(name)
        run("ip", "-n", name, "link", "set", "lo", "up")

    def build(self, count, netem):
        self.add(self.switch)
        run("ip", "-n", self.switch, "link", "add", "br0", "type", "bridge")
        run("ip", "-n", self.switch, "link", "set", "br0", "up")
        names = []
        for i in range(1, count + 1):
            ns = f"{TAG}p{i}"
            self.add(ns)
            run("ip", "-n", self.switch, "link", "add", f"s{i}", "type", "veth", "peer", "name",
                "eth0", "netns", ns)
            run("ip", "-n", self.switch, "link", "set", f"s{i}", "master", "br0")
            run("ip", "-n", self.switch, "link", "set", f"s{i}", "up")
            run("ip", "-n", ns, "addr", "add", f"{SUBNET}.{i}/24", "dev", "eth0")
            run("ip", "-n", ns, "link", "set", "eth0", "up")
            if netem:
                # Egress of each peer: every packet between two peers is delayed and may be lost
                # once on its way.
                run("tc", "-n", ns, "qdisc", "add", "dev", "eth0", "root", "netem", *NETEM)
            names.append(ns)
        return names

    def close(self):
        for name in reversed(self.made):
            run("ip", "netns", "del", name, check=False)
        self.made = []


def why_not():
    """None if the test can run, else why not; and whether netem is there."""
    if os.geteuid() != 0:
        return "needs root to create network namespaces", False
    for tool in ("ip", "tc"):
        if shutil.which(tool) is None:
            return f"'{tool}' not found (Debian package iproute2)", False
    probe = Namespaces()
    try:
        try:
            probe.add(f"{TAG}probe")
        except subprocess.CalledProcessError as e:
            return f"cannot create a network namespace: {e.stderr.strip()}", False
        try:
            run("ip", "-n", f"{TAG}probe", "link", "add", "pa", "type", "veth", "peer", "name",
                "pb")
        except subprocess.CalledProcessError as e:
            return f"cannot create a veth pair: {e.stderr.strip()}", False
        try:
            run("tc", "-n", f"{TAG}probe", "qdisc", "add", "dev", "pa", "root", "netem", *NETEM)
        except subprocess.CalledProcessError as e:
            return f"tc netem unavailable ({e.stderr.strip()}; kernel module sch_netem)", True
        return None, True
    finally:
        probe.close()


class Netem(unittest.TestCase):
    netem = True

    def test_three_peers_behind_200ms_and_5pct_loss_converge(self):
        nets = Namespaces()
        peers = []
        try:
            names = nets.build(3, self.netem)
            creator = Peer(1, seconds=8, rate=3, timing=SLOW, prefix=["ip", "netns", "exec",
                                                                     names[0]],
                           extra=["--bind", f"tcp://{SUBNET}.1:7100"])
            peers.append(creator)
            invite = creator.invite()
            self.assertIn(f"{SUBNET}.1:7100", invite)
            for i in (2, 3):
                peers.append(Peer(i, join=invite, seconds=8, rate=3, timing=SLOW,
                                  prefix=["ip", "netns", "exec", names[i - 1]],
                                  extra=["--bind", f"tcp://{SUBNET}.{i}:7100"]))
            for p in peers:
                p.wait_for(lambda p=p: p.state() and p.state()["members"] == 3, 60, "3 members")
            result, seconds = wait_converged(self, peers, timeout=120)
            summaries = finish(self, peers)
            for s in summaries:
                self.assertGreater(s["strokes"], 3, s)
            report("netem" if self.netem else "namespaces without netem",
                   version=result["version"], converged_after_last_edit_s=round(seconds, 3),
                   fetches={s["id"]: s["fetches"] for s in summaries},
                   rebases={s["id"]: s["rebases"] for s in summaries})
        finally:
            for p in peers:
                p.stop()
            nets.close()


def main():
    reason, _ = why_not()
    if reason:
        optional = os.environ.get("CSCULPT_NETEM_OPTIONAL") == "1"
        if not (optional and "netem unavailable" in reason):
            print(f"SKIP: {reason}", flush=True)
            sys.exit(SKIP)
        print(f"netem missing ({reason}): running the namespaces without it", flush=True)
        Netem.netem = False
    if not (os.path.exists(CLI) or shutil.which(CLI)):
        print(f"csculpt not found at {CLI}", flush=True)
        sys.exit(1)
    unittest.main()


if __name__ == "__main__":
    main()
