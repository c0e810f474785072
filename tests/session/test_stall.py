#!/usr/bin/env python3
"""A false expiry: the merger (peer 1) is frozen with SIGSTOP for longer than the expired
threshold, so peers 2 and 3 elect peer 2, which publishes versions of its own; on SIGCONT peer 1
(the lowest id) re-asserts itself and everyone follows it back. Peers that applied peer 2's
interim versions may hold a history peer 1 never saw; the session must still converge by hash
with no dropped message and no lost edit."""

import os
import signal
import sys
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sessionlib import Peer, converged, report, wait_all  # noqa: E402

# Longer than --expired-ms 500 (sessionlib.FAST) with room for the survivors to elect and merge.
STALL_S = 1.5
CONVERGENCE_LIMIT_S = 30.0
REPORTED = ("merger_changed", "peer_left", "peer_joined", "peer_evasive", "dropped", "error",
            "unparsable")


def same_history(peers):
    """Done editing, same version and mesh digest, the mesh being the agreed version's. Unlike
    sessionlib.converged's default, unacknowledged strokes are not required to be 0: lost
    edits are checked (and reported) separately from convergence."""
    return converged(peers, require_acknowledged=False)


def replaced_branch(peer, fork_version):
    """Snapshots the peer took after joining, seen in its state lines, and how many of its own
    strokes it saw acknowledged between the fork and each: strokes merged into a history the
    snapshot then replaced. An upper bound of what that history took away (a stroke may have
    been merged into both histories), which lost_edits, a counter, would not show. A snapshot
    emits no version event: the agreed mesh changed to a version number without one (several
    versions applied in one update have one each), or changed at the same version number."""
    states = peer.events("state")
    events = peer.events("version")
    taken = []
    for a, b in zip(states, states[1:]):  # a joiner's first state already follows its join
        # A version's event can be printed before the host applies it (one loop earlier).
        seen = {e["version"] for e in events if e["t"] <= b["t"] + 1}
        skipped = [n for n in range(a["version"] + 1, b["version"] + 1) if n not in seen]
        rebased = b["version"] <= a["version"] and b["base_digest"] != a["base_digest"]
        if not (skipped or rebased):
            continue
        at_fork = [s for s in states if s["t"] <= a["t"] and s["version"] <= fork_version]
        since = a["acknowledged"] - (at_fork[-1]["acknowledged"] if at_fork else 0)
        taken.append((a["version"], b["version"], since))
    return taken, sum(t[2] for t in taken)


def nothing_pending(peers):
    return same_history(peers) and all(p.state()["unacknowledged"] == 0 for p in peers)


class Stall(unittest.TestCase):
    def setUp(self):
        self.peers = []
        self.stopped = None
        self.stopped_at = self.continued_at = None

    def tearDown(self):
        if self.stopped is not None:  # a failure while frozen: thaw it so that it can quit
            self.stopped.proc.send_signal(signal.SIGCONT)
        for p in self.peers:
            p.stop()
        self.record()

    def record(self):
        """Membership and election events and the versions around the stall, pass or fail."""
        if self.stopped_at is None:
            return
        stopped_at, continued_at = self.stopped_at, self.continued_at or time.time()
        for p in self.peers:
            for e in p.lines:
                if e.get("event") not in REPORTED:
                    continue
                fields = {k: v for k, v in e.items() if k not in ("event", "id", "_read_at")}
                since = f" (+{e['t'] / 1000 - stopped_at:.3f} s from SIGSTOP)" if "t" in e else ""
                print(f"[stall] peer {p.peer_id} {e['event']} {fields}{since}", flush=True)
            around = [(e["version"], e["merger"], e["epoch"]) for e in p.events("version")
                      if stopped_at - 0.3 <= e["t"] / 1000 <= continued_at + 1.5]
            print(f"[stall] peer {p.peer_id} versions (version, merger followed, epoch) around "
                  f"the stall: {around}", flush=True)

    def start(self, *args, **kwargs):
        p = Peer(*args, **kwargs)
        self.peers.append(p)
        return p

    def test_sigstop_of_the_merger_then_sigcont_converges_without_loss(self):
        # Everyone edits before, during and after the stall, so edits land in both branches.
        merger = self.start(1, seconds=8)
        invite = merger.invite()
        survivors = [self.start(i, join=invite, seconds=7) for i in (2, 3)]
        peers = [merger] + survivors
        for p in peers:
            p.wait_for(lambda p=p: p.state() and p.state()["members"] == 3, 30, "3 members")
            p.wait_for(lambda p=p: p.state() and p.state()["merger"] == 1, 30, "merger 1")
        merger.wait_for(lambda: merger.state()["version"] >= 5, 30, "version 5")

        merger.proc.send_signal(signal.SIGSTOP)
        self.stopped = merger
        stopped_at = self.stopped_at = time.time()
        version_at_stop = merger.state()["version"]
        # The stall lasts at least STALL_S and until peer 2 has been elected and has published a
        # version that a survivor applied (else there would be no second history to test).
        elected = wait_all(
            lambda: [e for p in survivors for e in p.events("merger_changed")
                     if e["merger"] == 2 and e["t"] / 1000 > stopped_at],
            10, "a survivor following peer 2 during the stall", peers)
        wait_all(
            lambda: [e for p in survivors for e in p.events("version")
                     if e["merger"] == 2 and e["t"] / 1000 > stopped_at],
            10, "a version published by peer 2 during the stall", peers)
        left = STALL_S - (time.time() - stopped_at)
        if left > 0:
            time.sleep(left)  # holds the process frozen; nothing is asserted after this sleep
        merger.proc.send_signal(signal.SIGCONT)
        self.stopped = None
        continued_at = self.continued_at = time.time()
        stall_s = continued_at - stopped_at
        survivor_versions_at_cont = {p.peer_id: p.state()["version"] for p in survivors}
        self.assertGreater(elected[0]["t"] / 1000, stopped_at)
        self.assertLess(elected[0]["t"] / 1000, continued_at)

        # Peer 1 is the lowest live id: everyone, itself included, follows it again.
        wait_all(lambda: all(p.state()["merger"] == 1 for p in peers), 15,
                 "every peer following peer 1 again", peers)
        back_at = time.time()
        for p in survivors:
            self.assertTrue([e for e in p.events("merger_changed")
                             if e["merger"] == 1 and e["t"] / 1000 >= continued_at - 0.05],
                            f"peer {p.peer_id} did not report merger_changed back to 1")
        # ... and it publishes again.
        merger.wait_for(
            lambda: [e for e in merger.events("version")
                     if e["merger"] == 1 and e["t"] / 1000 > continued_at], 15,
            "a version by peer 1 after SIGCONT")

        result = wait_all(lambda: same_history(peers), CONVERGENCE_LIMIT_S,
                          "convergence (same version and digest, digest == base_digest)", peers)
        converged_at = time.time()
        for p in peers:  # before anyone quits (then the next lowest id takes over)
            self.assertEqual(p.state()["merger"], 1, f"peer {p.peer_id}: {p.state()}")
        try:
            # Give a resend in flight the chance to be acknowledged before judging lost edits.
            wait_all(lambda: nothing_pending(peers), 10, "every stroke acknowledged", peers)
            pending_cleared = True
        except AssertionError:
            pending_cleared = False
        for p in peers:
            p.quit()
        summaries = [p.summary() for p in peers]

        # The record: what happened around the stall, whatever the verdict below.
        print(f"\n[stall] stopped at version {version_at_stop}, stall {stall_s:.3f} s, "
              f"survivor versions at SIGCONT {survivor_versions_at_cont}, everyone back on peer 1 "
              f"{back_at - continued_at:.3f} s after SIGCONT, converged at version "
              f"{result['version']} {converged_at - continued_at:.3f} s after SIGCONT, "
              f"unacknowledged cleared: {pending_cleared}", flush=True)
        snapshots_taken, acknowledged_in_replaced = {}, {}
        for p, s in zip(peers, summaries):
            # The host counts a snapshot as an applied version but the node emits no version
            # event for it; a joiner's first snapshot is its join.
            snapshots_taken[p.peer_id] = (s["versions_applied"] - len(p.events("version")) -
                                          (0 if p is merger else 1))
            taken, in_replaced = replaced_branch(p, version_at_stop)
            acknowledged_in_replaced[p.peer_id] = in_replaced
            print(f"[stall] peer {p.peer_id} snapshots taken after joining (by the counters): "
                  f"{snapshots_taken[p.peer_id]}; seen in state lines as (version before, version "
                  f"after, own strokes acknowledged since the fork at {version_at_stop}): {taken}",
                  flush=True)
        for p, s in zip(peers, summaries):
            print(f"[stall] peer {p.peer_id} summary: strokes={s['strokes']} "
                  f"submitted={s['strokes_submitted']} acknowledged={s['acknowledged']} "
                  f"lost_edits={s['lost_edits']} version={s['version']} merges={s['merges']} "
                  f"merged_strokes={s['merged_strokes']} rebases={s['rebases']} "
                  f"versions_applied={s['versions_applied']} stale_ignored={s['stale_ignored']} "
                  f"snapshots_sent={s['snapshots_sent']} fetches={s['fetches']} "
                  f"epoch={s['epoch']} merger={s['merger']} "
                  f"messages_dropped={s['messages_dropped']}", flush=True)
        report("false expiry", stall_s=round(stall_s, 3), version_at_stop=version_at_stop,
               versions_while_following_2=len({e["version"] for p in survivors
                                                for e in p.events("version")
                                                if e["merger"] == 2}),
               diverged_snapshots=snapshots_taken,
               acknowledged_in_a_replaced_history=acknowledged_in_replaced,
               back_on_1_s=round(back_at - continued_at, 3),
               converged_after_sigcont_s=round(converged_at - continued_at, 3),
               final_version=result["version"],
               lost_edits=[s["lost_edits"] for s in summaries])

        for p, s in zip(peers, summaries):
            self.assertEqual(p.proc.returncode, 0, f"peer {p.peer_id}: {p.stderr}")
            p.err_reader.join(10)
            self.assertEqual(p.stderr, "", f"peer {p.peer_id}")  # a sanitizer report goes there
            self.assertEqual(s["messages_dropped"], 0, f"peer {p.peer_id}: {s}")
            self.assertEqual(s["version"], result["version"], f"peer {p.peer_id}: {s}")
            self.assertEqual(s["digest"], result["digest"], f"peer {p.peer_id}: {s}")
            self.assertEqual(s["digest"], s["base_digest"], f"peer {p.peer_id}: {s}")
            self.assertGreater(s["strokes"], 5, f"peer {p.peer_id}: {s}")
        # Last, so that everything above is checked whatever happens here: an edit merged only
        # into the losing branch (peer 2's interim versions) must not vanish.
        for p, s in zip(peers, summaries):
            self.assertEqual(s["lost_edits"], 0, f"peer {p.peer_id} lost edits: {s}")
            self.assertEqual(s["acknowledged"], s["strokes"], f"peer {p.peer_id}: {s}")


if __name__ == "__main__":
    unittest.main()
