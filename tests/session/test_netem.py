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
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from netns import SKIP, Namespaces, exit_unless_possible, why_not  # noqa: E402
from sessionlib import CLI, Peer, finish, report, wait_converged  # noqa: E402

SUBNET = "192.168.251"
NETEM = ["delay", "200ms", "loss", "5%"]
# Thresholds for a 400 ms round trip with TCP retransmissions after losses (a lost SYN waits 1 s).
SLOW = ["--sync-ms", "250", "--heartbeat-ms", "200", "--evasive-ms", "2000",
        "--expired-ms", "6000", "--join-timeout-ms", "60000"]


class Netem(unittest.TestCase):
    netem = True

    def test_three_peers_behind_200ms_and_5pct_loss_converge(self):
        nets = Namespaces(SUBNET)
        peers = []
        try:
            nets.build(3, NETEM if self.netem else None)
            creator = Peer(1, seconds=8, rate=3, timing=SLOW, prefix=nets.prefix(1),
                           extra=["--bind", f"tcp://{SUBNET}.1:7100"])
            peers.append(creator)
            invite = creator.invite()
            self.assertIn(f"{SUBNET}.1:7100", invite)
            for i in (2, 3):
                peers.append(Peer(i, join=invite, seconds=8, rate=3, timing=SLOW,
                                  prefix=nets.prefix(i),
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
    reason = why_not(netem=NETEM)
    if reason:
        optional = os.environ.get("CSCULPT_NETEM_OPTIONAL") == "1"
        if not (optional and "netem unavailable" in reason and why_not() is None):
            print(f"SKIP: {reason}", flush=True)
            sys.exit(SKIP)
        print(f"netem missing ({reason}): running the namespaces without it", flush=True)
        Netem.netem = False
    exit_unless_possible(CLI)  # the namespaces alone (without netem) are possible, checked above
    unittest.main()


if __name__ == "__main__":
    main()
