#!/usr/bin/env python3
"""A Jepsen-style chaos run of a session: four `csculpt peer` processes, each in its own network
namespace, sculpt and paint the whole time, each stroke with a marker (`--markers`), while a
seeded random schedule injects faults one after another:

- kill:      SIGKILL of a peer (the merger half of the time), restarted 1-4 s later as a new
             peer that joins through a live one; the kill waits (at most 30 s) until what
             the victim saw acknowledged is held by another live peer too: a peer alone
             across a partition is the only holder of its side's versions until the heal has
             merged them again, and killing it then is a double fault;
- stall:     SIGSTOP of a peer (the merger half of the time) for 0.5-3 s, then SIGCONT;
- partition: the peers split in two at random (the merger's side too), traffic between the
             sides dropped with nft for 2-10 s, then healed.

The last fault is always a partition that cuts the merger off with one other peer. After it
heals, the checker asks: one merger on every live peer within 5 s (while they still edit); then,
editing stopped, one chain (version and digest) on every live peer, and every marker any peer
(killed ones too) saw acknowledged, i.e. present in a version it followed, is present in the
agreed mesh, read off its values.

    chaos.py [--minutes M] [--seed S] [--faces F] [--logs DIR]
                                                      (exit 0: passed; 1: failed; 77: cannot run)

With --logs (default: $CSCULPT_CHAOS_LOGS) every incarnation's output (JSON lines, then its
stderr) is written to DIR/peer-<id>.log at the end, passed or failed, with the schedule in
DIR/schedule.log: what each peer saw is what a diagnosis needs.

`./dev chaos --minutes 30` is the long run; CTest runs a short one (session.chaos). Needs root,
iproute2 and nftables."""

import argparse
import json
import os
import random
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from netns import Namespaces, exit_unless_possible  # noqa: E402
from sessionlib import CLI, Peer, acknowledged_markers, converged, wait_all  # noqa: E402

SUBNET = "192.168.253"
PEERS = 4
TIMING = ["--sync-ms", "50", "--heartbeat-ms", "100", "--evasive-ms", "400",
          "--expired-ms", "1000", "--join-timeout-ms", "30000"]
RATE = 2.0          # strokes (and markers) per second per peer
MARKER_SLOTS = 16   # cli/markers.h kMarkerSlots


class Cluster:
    """The peers by position 1..PEERS (each position's namespace), with every incarnation kept
    for the checker."""

    def __init__(self, nets, faces, edit_seconds, minutes):
        self.nets = nets
        self.faces = int(faces)
        self.edit_seconds = edit_seconds
        self.live = {}        # position -> Peer
        self.everyone = []    # every incarnation, killed ones too
        self.incarnations = 0
        self.next_id = 1
        # Each incarnation marks its own vertices: slot n % 16, a block of `limit` markers. A
        # kill is a third of the faults, which come every 2-10 s: at most ~6 a minute.
        self.max_incarnations = PEERS + 4 + int(minutes * 6)
        vertices = self.faces // 2
        rows = (self.max_incarnations + MARKER_SLOTS - 1) // MARKER_SLOTS
        self.marker_limit = vertices // MARKER_SLOTS // rows

    def markers(self):
        n = self.incarnations
        self.incarnations += 1
        if n >= self.max_incarnations:
            raise RuntimeError("more incarnations than marker blocks")
        return ["--markers", "--marker-slot", str(n % MARKER_SLOTS), "--marker-first",
                str((n // MARKER_SLOTS) * self.marker_limit), "--marker-limit",
                str(self.marker_limit)]

    def start(self, position, invite=None):
        port = 7300 + self.incarnations
        extra = self.markers() + ["--bind", f"tcp://{self.nets.address(position)}:{port}"]
        peer = Peer(self.next_id, join=invite, seconds=self.edit_seconds, rate=RATE,
                    timing=TIMING, prefix=self.nets.prefix(position), faces=str(self.faces),
                    extra=extra, linger=3600)
        peer.position = position
        self.next_id += 1
        self.live[position] = peer
        self.everyone.append(peer)
        return peer

    def invite(self):
        """An invite through a live peer (its own endpoint)."""
        for p in self.live.values():
            line = p.first("invite")
            if line and p.proc.poll() is None:
                return line["invite"]
        raise AssertionError("no live peer to join through")

    def merger_position(self):
        mergers = [p.state()["merger"] for p in self.live.values() if p.state()]
        if not mergers:
            return None
        merger = max(set(mergers), key=mergers.count)
        for pos, p in self.live.items():
            if p.peer_id == merger:
                return pos
        return None


def one_merger(cluster):
    """Every live peer names the same live merger."""
    states = [p.state() for p in cluster.live.values()]
    if any(s is None for s in states):
        return False
    mergers = {s["merger"] for s in states}
    ids = {p.peer_id for p in cluster.live.values()}
    return len(mergers) == 1 and mergers <= ids and mergers


def held_elsewhere(cluster, victim, recent=400):
    """Every marker `victim` has seen acknowledged is in a base another live peer showed too:
    one of its latest states whose base held all of them (markers_held) has the version and
    base digest of some other live peer's recent state."""
    states = victim.events("state")
    if not states or states[-1].get("markers_acknowledged", 0) == 0:
        return True
    acknowledged = states[-1]["markers_acknowledged"]
    others = {(s["version"], s["base_digest"]) for p in cluster.live.values() if p is not victim
              for s in p.events("state")[-recent:]}
    for s in reversed(states[-recent:]):
        if s["markers_acknowledged"] != acknowledged:
            return False  # older states knew fewer
        if s["markers_held"] == acknowledged and (s["version"], s["base_digest"]) in others:
            return True
    return False


def pick(rng, cluster):
    """A peer to hit: the merger half of the time."""
    merger = cluster.merger_position()
    if merger is not None and rng.random() < 0.5:
        return merger
    return rng.choice(sorted(cluster.live))


class Schedule:
    def __init__(self, cluster, rng, log):
        self.cluster = cluster
        self.rng = rng
        self.log = log
        self.faults = {"kill": 0, "stall": 0, "partition": 0}

    def kill(self):
        c = self.cluster
        wait_all(lambda: one_merger(c), 30, "one merger before a kill", list(c.live.values()))
        position = pick(self.rng, c)
        victim = c.live[position]
        # A peer alone on its side of a partition acknowledges its own edits in versions only
        # it holds until the heal has merged them again; killing it before that takes the
        # only copy with it (a double fault no protocol survives without its journal). So a
        # kill waits until the victim's acknowledged markers are in a base another peer held.
        waited = time.time()
        wait_all(lambda: held_elsewhere(c, victim), 30,
                 f"peer {victim.peer_id}'s acknowledged markers held by another peer",
                 list(c.live.values()))
        del c.live[position]
        victim.kill()
        self.log(f"kill peer {victim.peer_id} (position {position}), its acknowledged markers "
                 f"held elsewhere after {time.time() - waited:.1f} s")
        time.sleep(self.rng.uniform(1, 4))
        peer = c.start(position, c.invite())
        peer.wait_for(lambda: peer.state() is not None, 60, "its first state")
        self.log(f"restart at position {position} as peer {peer.peer_id}")

    def stall(self):
        position = pick(self.rng, self.cluster)
        peer = self.cluster.live[position]
        seconds = self.rng.uniform(0.5, 3)
        peer.proc.send_signal(19)  # SIGSTOP
        time.sleep(seconds)
        peer.proc.send_signal(18)  # SIGCONT
        self.log(f"stall peer {peer.peer_id} {seconds:.1f} s")

    def partition(self, sides=None):
        if sides is None:
            positions = sorted(self.cluster.live)
            self.rng.shuffle(positions)
            cut = self.rng.randint(1, len(positions) - 1)
            sides = [sorted(positions[:cut]), sorted(positions[cut:])]
        seconds = self.rng.uniform(2, 10)
        self.cluster.nets.partition(*sides)
        time.sleep(seconds)
        self.cluster.nets.heal()
        self.log(f"partition {sides[0]} | {sides[1]} {seconds:.1f} s")

    def run(self, until):
        while time.time() < until:
            kind = self.rng.choice(["kill", "stall", "partition"])
            getattr(self, kind)()
            self.faults[kind] += 1
            time.sleep(self.rng.uniform(0.5, 3))
        # The last fault: the merger and one other cut off from the rest.
        merger = self.cluster.merger_position() or 1
        others = [p for p in sorted(self.cluster.live) if p != merger]
        self.rng.shuffle(others)
        self.partition([sorted([merger, others[0]]), sorted(others[1:])])
        self.faults["partition"] += 1


def check(cluster):
    """The checker; returns the figures, raises AssertionError saying what failed."""
    # The merger quits last: a merger leaving first makes the others elect another, which
    # would merge anything still pending into a version only the peers quitting later see.
    merger = cluster.merger_position()
    live = sorted(cluster.live.values(), key=lambda p: cluster.live.get(merger) is p)
    for p in live[:-1]:
        p.quit()
    summaries = [p.summary(60) for p in live[:-1]]
    live[-1].quit()
    summaries.append(live[-1].summary(60))
    digests = {s["digest"] for s in summaries}
    versions = {s["version"] for s in summaries}
    if len(digests) != 1 or len(versions) != 1:
        raise AssertionError(f"more than one chain at the end: versions {versions}, "
                             f"digests {digests}")
    marked = set(summaries[0]["marked"])
    lost = {p.peer_id: sorted(acknowledged_markers(p) - marked) for p in cluster.everyone}
    lost = {k: v for k, v in lost.items() if v}
    made = sum(len(p.events("marker")) for p in cluster.everyone)
    acked = sum(len(acknowledged_markers(p)) for p in cluster.everyone)
    unmerged = [s for s in summaries if s["markers_acknowledged"] != s["markers_made"]]
    if lost:
        raise AssertionError(f"acknowledged markers absent from the agreed mesh: {lost}")
    if unmerged:
        raise AssertionError(f"live peers with markers never merged: {unmerged}")
    # Forks of a few seconds are far inside the kept history: every version of a branch that
    # lost is carried from its fork, none left in a base for the rebase to erase.
    dropped = {s["id"]: s["branch_versions_dropped"] for s in summaries
               if s["branch_versions_dropped"]}
    if dropped:
        raise AssertionError(f"branch versions not stepped back (branch_versions_dropped): "
                             f"{dropped}")
    for p in cluster.everyone:
        if p.proc.returncode not in (0, -9):
            raise AssertionError(f"peer {p.peer_id} exited {p.proc.returncode}: {p.stderr}")
    return {"markers_made": made, "markers_acknowledged": acked, "markers_lost": 0,
            "version": summaries[0]["version"],
            "branch_rebases": sum(s["branch_rebases"] for s in summaries),
            "branch_versions_dropped": sum(s["branch_versions_dropped"] for s in summaries),
            "submits_resent": sum(s["submits_resent"] for s in summaries)}


def diagnose(cluster, reason):
    """The failure first, then what each live peer is doing: one line of its latest state, its
    exit code and stderr, and, when it has printed nothing for 5 s, the stacks (gdb, where
    installed) of its threads that are not idle. CI keeps only the head and tail of a long
    output: the reason and the states come before the stacks."""
    print(f"FAILED: {str(reason)[:300]}", flush=True)
    keys = ("version", "merger", "epoch", "members", "unacknowledged", "editing", "strokes")
    for p in cluster.live.values():
        s = p.state() or {}
        same = s.get("digest") == s.get("base_digest")
        print(f"peer {p.peer_id}: " + " ".join(f"{k} {s.get(k)}" for k in keys) +
              f" digest {s.get('digest')} local==base {same} exit {p.proc.poll()} "
              f"silent {time.time() - s.get('_read_at', 0):.1f} s", flush=True)
    for p in cluster.live.values():
        code = p.proc.poll()
        state = p.state() or {}
        silent = time.time() - state.get("_read_at", 0)
        if p.stderr:
            print(f"peer {p.peer_id} stderr: {p.stderr[-500:]!r}", flush=True)
        reasons = {}
        for line in p.events("dropped"):
            reasons[line["reason"]] = reasons.get(line["reason"], 0) + 1
        if reasons:
            print(f"peer {p.peer_id} dropped: {sorted(reasons.items(), key=lambda r: -r[1])[:3]}",
                  flush=True)
        if code is None and silent > 5 and shutil.which("gdb"):
            stacks = subprocess.run(["gdb", "-p", str(p.proc.pid), "-batch", "-ex",
                                     "thread apply all bt 12"], capture_output=True, text=True,
                                    timeout=120).stdout
            print(f"peer {p.peer_id} busy threads:\n" + busy_threads(stacks), flush=True)


def busy_threads(gdb_output):
    """The frames of the threads gdb listed, without those waiting for work (the merge's
    worker pool, ZeroMQ's I/O threads, the network thread's poll)."""
    idle = ("WorkerPool::work", "epoll_wait", "Transport::wait")
    threads, current = [], []
    for line in gdb_output.splitlines():
        if line.startswith("Thread"):
            threads.append(current)
            current = [line]
        elif line.startswith("#") and current:
            current.append(line[:200])
    threads.append(current)
    kept = [t for t in threads if t and not any(word in f for f in t for word in idle)]
    return "\n".join(line for t in kept for line in t)


def write_logs(cluster, schedule_lines, directory):
    """Every incarnation's output and the schedule, for a failure's diagnosis."""
    os.makedirs(directory, exist_ok=True)
    with open(os.path.join(directory, "schedule.log"), "w") as f:
        f.write("\n".join(schedule_lines) + "\n")
    for p in cluster.everyone:  # stopped: their stderr is complete
        with open(os.path.join(directory, f"peer-{p.peer_id}.log"), "w") as f:
            f.write(f"# {' '.join(p.cmd)}\n# started {p.started:.3f}\n")
            with p.cond:
                for line in p.lines:
                    f.write(json.dumps(line) + "\n")
            f.write("# stderr\n" + p.stderr)
    print(f"logs of {len(cluster.everyone)} peers in {directory}", flush=True)


def run(minutes, seed, faces, logs=None):
    rng = random.Random(seed)
    started = time.time()
    schedule_lines = [f"# started {started:.3f}"]

    def log(text):
        line = f"[{time.time() - started:7.1f} s] {text}"
        schedule_lines.append(line)
        print(line, flush=True)

    nets = Namespaces(SUBNET)
    cluster = None
    try:
        nets.build(PEERS)
        cluster = Cluster(nets, faces, edit_seconds=minutes * 60 + 5, minutes=minutes)
        creator = cluster.start(1)
        invite = creator.invite()
        for position in range(2, PEERS + 1):
            cluster.start(position, invite)
        peers = list(cluster.live.values())
        wait_all(lambda: all(p.state() and p.state()["members"] == PEERS for p in peers), 60,
                 "every peer joined", peers)
        schedule = Schedule(cluster, rng, log)
        schedule.run(started + minutes * 60)
        nets.heal()
        last_fault = time.time()
        log(f"faults done: {schedule.faults}")
        merged = wait_all(lambda: one_merger(cluster), 60, "one merger",
                          list(cluster.live.values()))
        one_merger_s = time.time() - last_fault
        if one_merger_s > 5:
            raise AssertionError(f"one merger only {one_merger_s:.1f} s after the last fault")
        for p in cluster.live.values():  # stop editing: the chain can settle on one version
            p.proc.stdin.write("stop-editing\n")
            p.proc.stdin.flush()
        settled = wait_all(lambda: converged(list(cluster.live.values())), 120, "one chain",
                           list(cluster.live.values()))
        one_chain_s = time.time() - last_fault
        figures = check(cluster)
        figures.update({"seed": seed, "minutes": minutes, "faces": faces, "faults": schedule.faults,
                        "incarnations": cluster.incarnations, "merger": sorted(merged)[0],
                        "one_merger_after_last_fault_s": round(one_merger_s, 2),
                        "one_chain_after_last_fault_s": round(one_chain_s, 2),
                        "agreed_version": settled["version"]})
        print(json.dumps({"chaos": figures}), flush=True)
        return figures
    except AssertionError as e:
        if cluster:
            diagnose(cluster, e)
        raise
    finally:
        if cluster:
            for p in cluster.everyone:
                p.stop()
            if logs:
                write_logs(cluster, schedule_lines, logs)
        nets.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=2.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--faces", type=int, default=20000)
    parser.add_argument("--logs", default=os.environ.get("CSCULPT_CHAOS_LOGS"),
                        help="directory for every peer's output")
    args = parser.parse_args()
    exit_unless_possible(CLI, nft=True)
    try:
        run(args.minutes, args.seed, args.faces, args.logs)
    except AssertionError as e:
        print(f"FAILED: {e}", flush=True)
        sys.exit(1)


if __name__ == "__main__":
    main()
