#!/usr/bin/env python3
"""Partitions of a session of four `csculpt peer` processes, each in its own network namespace;
traffic between the two sides is dropped with nft (the TCP connections stay established, as
across a real network split). Every peer makes a marker with each stroke (`--markers`), on
both sides during the partition and after the heal; the checks read the markers in the agreed
mesh itself:

- both sides keep merging while apart, and the heal loses no acknowledged marker;
- one chain and one digest after the heal, and after a SIGKILL of the merger that follows it;
- once healed, membership stays put (nobody is seen to leave or go evasive).

CSCULPT_PARTITION_SECONDS=300 runs the first case with a five-minute partition (the issue's
bound) instead of 8 s; run the script itself then, as CTest stops a test after 300 s:

    CSCULPT_CLI=build/cli/csculpt CSCULPT_PARTITION_SECONDS=300 \
      python3 tests/session/test_partition.py -v Partition.test_heal_loses_no_acknowledged_marker

Needs root, iproute2 and nftables; otherwise exits 77 (a CTest skip) saying what is missing."""

import os
import sys
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from netns import Namespaces, exit_unless_possible  # noqa: E402
from sessionlib import CLI, Peer, acknowledged_markers, converged, report, wait_all  # noqa: E402

SUBNET = "192.168.252"
TIMING = ["--sync-ms", "50", "--heartbeat-ms", "100", "--evasive-ms", "400",
          "--expired-ms", "1000", "--join-timeout-ms", "30000"]
FACES = "20000"


def start(nets, n, seconds, rate=4.0):
    creator = Peer(1, seconds=seconds, rate=rate, timing=TIMING, prefix=nets.prefix(1),
                   faces=FACES, extra=["--markers", "--bind", f"tcp://{nets.address(1)}:7200"])
    peers = [creator]
    invite = creator.invite()
    for i in range(2, n + 1):
        peers.append(Peer(i, join=invite, seconds=seconds, rate=rate, timing=TIMING,
                          prefix=nets.prefix(i),
                          extra=["--markers", "--bind", f"tcp://{nets.address(i)}:7200"]))
    for p in peers:
        p.wait_for(lambda p=p: p.state() and p.state()["members"] == n, 60, f"{n} members")
    return peers


def check_markers(testcase, survivors, everyone):
    """Quits the survivors; every marker anyone saw acknowledged is in the agreed mesh."""
    for p in survivors:
        p.quit()
    summaries = [p.summary() for p in survivors]
    marked = set(summaries[0]["marked"])
    for s in summaries:
        testcase.assertEqual(s["digest"], summaries[0]["digest"])
        testcase.assertEqual(set(s["marked"]), marked)
        testcase.assertEqual(s["markers_lost"], 0, s)
        testcase.assertEqual(s["markers_acknowledged"], s["markers_made"], s)
    lost = {p.peer_id: sorted(acknowledged_markers(p) - marked) for p in everyone}
    testcase.assertEqual({k: v for k, v in lost.items() if v}, {},
                         "acknowledged markers absent from the agreed mesh")
    return summaries, sum(len(acknowledged_markers(p)) for p in everyone)


def membership_changes(peers, since):
    return [(p.peer_id, e["event"], e.get("peer")) for p in peers
            for e in p.lines if e.get("event") in ("peer_left", "peer_evasive", "peer_joined")
            and e["_read_at"] >= since]


class Partition(unittest.TestCase):
    def run_partition(self, apart_s, kill_merger_after_s=None):
        nets = Namespaces(SUBNET)
        peers = []
        try:
            nets.build(4)
            peers = start(nets, 4, seconds=apart_s + 14)
            time.sleep(2)  # edits merged by everyone first
            nets.partition([1, 2], [3, 4])
            cut = time.time()
            time.sleep(apart_s)
            # Both sides merged while apart: each side's versions went on.
            versions = {p.peer_id: p.state()["version"] for p in peers}
            mergers = {p.peer_id: p.state()["merger"] for p in peers}
            nets.heal()
            healed = time.time()
            survivors = peers
            if kill_merger_after_s is not None:
                time.sleep(kill_merger_after_s)
                merger = peers[0].state()["merger"]
                victim = next(p for p in peers if p.peer_id == merger)
                victim.kill()
                survivors = [p for p in peers if p is not victim]
            settled = wait_all(lambda: converged(survivors), 90, "one chain and digest", survivors)
            stable_from = time.time()
            time.sleep(3)
            changes = membership_changes(survivors, stable_from)
            self.assertEqual(changes, [], "membership changed on a healthy network")
            self.assertTrue(converged(survivors))
            summaries, acked = check_markers(self, survivors, peers)
            report("partition", apart_s=apart_s, versions_at_heal=versions,
                   mergers_while_apart=mergers, version=settled["version"],
                   markers_acknowledged=acked, markers_lost=0,
                   settled_after_heal_s=round(stable_from - healed, 2),
                   partition_s=round(healed - cut, 2))
            self.assertNotEqual(mergers[1], mergers[3], "each side merged on its own")
        finally:
            for p in peers:
                p.stop()
            nets.close()

    def test_heal_loses_no_acknowledged_marker(self):
        self.run_partition(float(os.environ.get("CSCULPT_PARTITION_SECONDS", "8")))

    def test_merger_killed_after_a_heal_leaves_one_chain(self):
        self.run_partition(8, kill_merger_after_s=10)


def main():
    exit_unless_possible(CLI, nft=True)
    unittest.main()


if __name__ == "__main__":
    main()
