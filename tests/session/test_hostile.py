#!/usr/bin/env python3
"""Hostile input against a session of real `csculpt peer` processes (hostile_peer.cpp):
clients without the key, garbage and valid-but-wrong messages from a client with the key, and
a forged epoch at the top of the epoch range. Each time the session must survive, count what
it refused, keep every edit and converge."""

import collections
import os
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sessionlib import HOSTILE, Peer, finish, report, wait_converged  # noqa: E402

HOSTILE_ID = 900001


class Hostile(unittest.TestCase):
    def setUp(self):
        self.peers = []

    def tearDown(self):
        for p in self.peers:
            p.stop()

    def session(self, seconds):
        creator = Peer(1, seconds=seconds)
        self.peers.append(creator)
        invite = creator.invite()
        for i in (2, 3):
            self.peers.append(Peer(i, join=invite, seconds=seconds))
        for p in self.peers:
            p.wait_for(lambda p=p: p.state() and p.state()["members"] == 3, 30, "3 members")
        return invite

    def hostile(self, mode, invite, seconds):
        r = subprocess.run([HOSTILE, mode, invite, str(seconds)], capture_output=True, text=True,
                           timeout=60)
        self.assertEqual(r.returncode, 0, r.stderr)
        return r.stdout

    def dropped_reasons(self, p):
        return collections.Counter(e["reason"] for e in p.events("dropped"))

    def test_clients_without_the_key_are_refused_and_see_nothing(self):
        invite = self.session(seconds=4)
        creator = self.peers[0]
        out = self.hostile("nokey", invite, 1.0)
        self.assertIn("wrong client key", out)
        # The ZAP check refused the client with the right server key but a wrong client key.
        creator.wait_for(lambda: creator.state()["auth_rejected"] >= 1, 10, "auth_rejected")
        result, seconds = wait_converged(self, self.peers)
        summaries = finish(self, self.peers)
        for s in summaries:
            # Nothing reached the session layer: no message dropped, no stranger a member.
            self.assertEqual(s["messages_dropped"], 0, s)
        for p in self.peers:
            self.assertEqual(p.events("peer_joined") and
                             {e["peer"] for e in p.events("peer_joined")} - {1, 2, 3}, set())
        report("clients without the key", auth_rejected=summaries[0]["auth_rejected"],
               final_version=result["version"], converged_after_last_edit_s=round(seconds, 3))

    def test_garbage_and_valid_but_wrong_messages_change_nothing(self):
        invite = self.session(seconds=5)
        creator = self.peers[0]
        creator.wait_for(lambda: creator.state()["version"] >= 5, 30, "version 5")
        out = self.hostile("keyed", invite, 2.0)
        self.assertIn('"event":"learnt"', out)
        result, seconds = wait_converged(self, self.peers)
        # The merger never changed: a far-future epoch from a higher id gains nothing.
        for p in self.peers:
            self.assertEqual(p.state()["merger"], 1)
            self.assertEqual({e["merger"] for e in p.events("merger_changed")}, {1})
        summaries = finish(self, self.peers)
        reasons = {p.peer_id: self.dropped_reasons(p) for p in self.peers}
        inviter = " | ".join(reasons[1])
        for expected in ("not a cSculpt session envelope", "failed FlatBuffers verification",
                         "another session", "does not match its connection",
                         "hello with protocol 99",
                         # submits to the merger: a garbage diff, indices out of range
                         "not a cSculpt diff message", "out of range"):
            self.assertIn(expected, inviter)
        for p in self.peers:
            text = " | ".join(reasons[p.peer_id])
            self.assertIn("fails its hash chain", text, p.peer_id)  # replayed forged version
            self.assertIn("out of range", text, p.peer_id)  # version with a bad diff
            self.assertIn("does not match its connection", text, p.peer_id)  # merger's name
        # Nothing of the intruder's was merged: the merged strokes are exactly the members'.
        self.assertEqual(summaries[0]["merged_strokes"], sum(s["strokes"] for s in summaries),
                         summaries)
        # Submits on an unknown base and versions of a stale or foreign epoch: ignored.
        self.assertGreater(summaries[0]["stale_ignored"], 0)
        for s in summaries:
            self.assertGreater(s["stale_ignored"], 0, s)
            self.assertEqual(s["messages_dropped"],
                             sum(reasons[s["id"]].values()), s)
        # The intruder (it had the key, so it was a member) said goodbye and is gone.
        for p in self.peers:
            left = [e for e in p.events("peer_left") if e["peer"] == HOSTILE_ID]
            self.assertTrue(left, p.peer_id)
        report("garbage and wrong messages",
               dropped={s["id"]: s["messages_dropped"] for s in summaries},
               stale_ignored={s["id"]: s["stale_ignored"] for s in summaries},
               final_version=result["version"], final_epoch=summaries[0]["epoch"],
               converged_after_last_edit_s=round(seconds, 3))



class EpochOverflow(Hostile):
    """Registered as its own CTest test (session.epoch_overflow): it fails with the peer layer
    as of this writing (epochs wrap around at 2^64-1; see the report)."""

    test_clients_without_the_key_are_refused_and_see_nothing = None
    test_garbage_and_valid_but_wrong_messages_change_nothing = None

    def test_a_forged_epoch_at_the_top_of_the_range_does_not_break_failover(self):
        # A key holder names the merger in epoch 2^64-1 and claims that epoch for itself; then
        # the merger dies. The survivors must still elect a new merger that everyone follows,
        # and merge every edit.
        invite = self.session(seconds=6)
        creator, survivors = self.peers[0], self.peers[1:]
        creator.wait_for(lambda: creator.state()["version"] >= 5, 30, "version 5")
        self.hostile("overflow", invite, 1.0)
        killed_at = creator.kill()
        for p in survivors:
            p.wait_for(lambda p=p: [e for e in p.events("merger_changed")
                                    if e["merger"] == 2 and e["t"] / 1000 > killed_at - 0.05],
                       10, "merger 2 after the kill")
        result, seconds = wait_converged(self, survivors, timeout=30)
        finish(self, survivors)
        report("epoch 2^64-1 then failover", final_version=result["version"],
               epochs=[p.state()["epoch"] for p in survivors])


if __name__ == "__main__":
    unittest.main()
