#!/usr/bin/env python3
"""Sessions of 3-4 real `csculpt peer` processes on loopback: join and merge with convergence
by hash, late join, a clean leave, and SIGKILL of the merger (re-election within 2 s, no lost
edit). And a peer under an open-file limit too low for a session refuses to start, saying so."""

import os
import resource
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sessionlib import CLI, Peer, finish, report, wait_converged  # noqa: E402

REELECTION_LIMIT_S = 2.0


class Processes(unittest.TestCase):
    def setUp(self):
        self.peers = []

    def tearDown(self):
        for p in self.peers:
            p.stop()

    def start(self, *args, **kwargs):
        p = Peer(*args, **kwargs)
        self.peers.append(p)
        return p

    def test_three_peers_merge_and_converge_by_hash(self):
        creator = self.start(1, seconds=3)
        invite = creator.invite()
        others = [self.start(i, join=invite, seconds=3) for i in (2, 3)]
        peers = [creator] + others
        for p in others:
            joined = p.wait_for(lambda p=p: p.first("joined"), 30, "joined event")
            self.assertGreaterEqual(joined["version"], 0)
        # Everyone knows everyone (gossip through the inviter) and the creator merges.
        for p in peers:
            p.wait_for(lambda p=p: p.state() and p.state()["members"] == 3, 30, "3 members")
            p.wait_for(lambda p=p: p.state() and p.state()["merger"] == 1, 30, "merger 1")
        result, seconds = wait_converged(self, peers)
        summaries = finish(self, peers)
        merged = summaries[0]
        self.assertGreater(merged["merges"], 5)
        # Each stroke merged exactly once (cumulative submits are not counted twice).
        self.assertEqual(merged["merged_strokes"], sum(s["strokes"] for s in summaries))
        for s in summaries:
            self.assertGreater(s["strokes"], 5, s)
            self.assertEqual(s["messages_dropped"], 0, s)
        # Every peer saw every version in order (a version line for each number after joining).
        for p in others:
            numbers = [e["version"] for e in p.events("version")]
            self.assertEqual(numbers, sorted(numbers))
            self.assertEqual(numbers[-1], result["version"])
        report("three peers", version=result["version"], digest=result["digest"],
               converged_after_last_edit_s=round(seconds, 3), merges=merged["merges"],
               conflicting_strokes=merged["conflicting_strokes"])

    def test_late_joiner_gets_the_current_version(self):
        creator = self.start(1, seconds=5)
        invite = creator.invite()
        second = self.start(2, join=invite, seconds=5)
        # Wait until several versions are out, then join late.
        before = creator.wait_for(
            lambda: creator.state() if creator.state() and creator.state()["version"] >= 10
            else None, 30, "version 10")["version"]
        late = self.start(3, join=invite, seconds=2)
        joined = late.wait_for(lambda: late.first("joined"), 30, "joined event")
        first_state = late.wait_for(lambda: late.first("state"), 30, "first state")
        # The snapshot is of the version current when it was sent: not older than what the
        # creator held before the joiner started, and the joiner starts from it, not from 0.
        self.assertGreaterEqual(joined["version"], before)
        # A version that arrived in the same poll as the snapshot may already be applied when
        # the first state line is printed: the joiner is then at a version it announced.
        announced = {joined["version"]} | {e["version"] for e in late.events("version")
                                           if e["t"] <= first_state["t"]}
        self.assertIn(first_state["version"], announced)
        self.assertEqual(first_state["digest"], first_state["base_digest"])
        peers = [creator, second, late]
        result, seconds = wait_converged(self, peers)
        finish(self, peers)
        self.assertGreater(result["version"], joined["version"])
        report("late join", joined_at_version=joined["version"], creator_version_before=before,
               final_version=result["version"], converged_after_last_edit_s=round(seconds, 3))

    def test_a_peer_leaves_cleanly_and_the_others_go_on(self):
        creator = self.start(1, seconds=4)
        invite = creator.invite()
        stay = self.start(2, join=invite, seconds=4)
        leaver = self.start(3, join=invite, seconds=30)
        for p in (creator, stay, leaver):
            p.wait_for(lambda p=p: p.state() and p.state()["members"] == 3, 30, "3 members")
        leaver.wait_for(lambda: leaver.state()["acknowledged"] > 0, 30, "an acknowledged stroke")
        creator.wait_for(lambda: creator.state()["version"] >= 10, 30, "version 10")
        leaver.quit()
        left = leaver.summary()
        self.assertEqual(leaver.proc.returncode, 0, leaver.stderr)
        for p in (creator, stay):
            ev = p.wait_for(lambda p=p: [e for e in p.events("peer_left") if e["peer"] == 3],
                            10, "peer_left of 3")[0]
            # Told, not timed out.
            self.assertEqual(ev["detail"], "left")
            p.wait_for(lambda p=p: p.state()["members"] == 2, 10, "2 members")
        # The merger did not change; the two go on editing and converge.
        self.assertEqual(len(stay.events("merger_changed")), 1)
        peers = [creator, stay]
        result, seconds = wait_converged(self, peers)
        finish(self, peers)
        self.assertGreater(result["version"], left["version"])
        report("leave", leaver_left_at=left["version"], final_version=result["version"],
               converged_after_last_edit_s=round(seconds, 3))

    def test_sigkill_of_the_merger_elects_a_new_one_and_loses_no_edit(self):
        creator = self.start(1, seconds=30)
        invite = creator.invite()
        survivors = [self.start(i, join=invite, seconds=6) for i in (2, 3, 4)]
        peers = [creator] + survivors
        for p in peers:
            p.wait_for(lambda p=p: p.state() and p.state()["members"] == 4, 30, "4 members")
        creator.wait_for(lambda: creator.state()["version"] >= 10, 30, "version 10")
        # Survivors are mid-edit at the kill.
        for p in survivors:
            self.assertTrue(p.state()["editing"])
        killed_at = creator.kill()
        version_at_kill = creator.state()["version"]
        delays = []
        for p in survivors:
            ev = p.wait_for(
                lambda p=p: [e for e in p.events("merger_changed")
                             if e["merger"] != 1 and e["t"] / 1000 > killed_at - 0.05],
                10, "a new merger")[0]
            self.assertEqual(ev["merger"], 2,  # the lowest live id
                             [e for e in p.lines if e["event"] not in ("state", "version")])
            delays.append(ev["t"] / 1000 - killed_at)
        self.assertLess(max(delays), REELECTION_LIMIT_S, delays)
        # Versions go on past the kill under the new merger.
        survivors[0].wait_for(lambda: survivors[0].state()["version"] > version_at_kill + 3,
                              30, "versions after the kill")
        result, seconds = wait_converged(self, survivors)
        for p in survivors:  # before anyone quits (then the next lowest id takes over)
            self.assertEqual(p.state()["merger"], 2)
        summaries = finish(self, survivors)
        self.assertGreater(summaries[0]["merges"], 0)  # peer 2 merged
        report("sigkill of the merger", reelection_s=[round(d, 3) for d in delays],
               version_at_kill=version_at_kill, final_version=result["version"],
               converged_after_last_edit_s=round(seconds, 3), new_merger_merges=summaries[0]["merges"])

    def test_an_open_file_limit_too_low_for_a_session_is_refused_with_a_message(self):
        # At 8 libzmq cannot open its own descriptors (it aborts the process); at 16 the
        # listener could accept no joiner, without a word. Both must be refused up front.
        for limit in (8, 16):
            def lower(limit=limit):
                resource.setrlimit(resource.RLIMIT_NOFILE, (limit, limit))
            r = subprocess.run([CLI, "peer", "--faces", "2000", "--seconds", "0", "--linger", "0"],
                               stdin=subprocess.DEVNULL, capture_output=True, text=True,
                               timeout=30, preexec_fn=lower)
            self.assertEqual(r.returncode, 1, f"limit {limit}: exit {r.returncode}: {r.stderr}")
            self.assertIn(f"the open-file limit is {limit}", r.stderr)
            self.assertIn("ulimit -n", r.stderr)


if __name__ == "__main__":
    unittest.main()
