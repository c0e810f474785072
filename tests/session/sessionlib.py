"""Drives `csculpt peer` processes for the multi-process session tests.

Each Peer is a subprocess whose stdout (one JSON object per line) a reader thread collects;
tests wait on conditions over those lines with generous deadlines and never sleep a fixed time
to assert something.
"""

import json
import os
import signal
import subprocess
import threading
import time

CLI = os.environ.get("CSCULPT_CLI", "csculpt")
HOSTILE = os.environ.get("CSCULPT_HOSTILE_PEER", "csculpt_hostile_peer")

# Short thresholds so that expiry and re-election happen in well under a second.
FAST = ["--sync-ms", "50", "--heartbeat-ms", "50", "--evasive-ms", "200", "--expired-ms", "500"]
FACES = "5000"


class Peer:
    def __init__(self, peer_id, join=None, seconds=3.0, rate=5.0, linger=120.0, extra=(),
                 prefix=(), timing=FAST, faces=FACES):
        self.peer_id = peer_id
        cmd = list(prefix) + [CLI, "peer", "--id", str(peer_id), "--seed", str(peer_id),
                              "--seconds", str(seconds), "--strokes-per-second", str(rate),
                              "--linger", str(linger)] + list(timing) + list(extra)
        if join:
            cmd += ["--join", join]
        else:
            cmd += ["--faces", faces]
        self.cmd = cmd
        self.started = time.time()
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, bufsize=1)
        self.lines = []
        self.stderr = ""
        self.cond = threading.Condition()
        self.closed = False
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()
        self.err_reader = threading.Thread(target=self._read_err, daemon=True)
        self.err_reader.start()

    def _read(self):
        for raw in self.proc.stdout:
            raw = raw.strip()
            if not raw:
                continue
            try:
                obj = json.loads(raw)
            except json.JSONDecodeError:
                obj = {"event": "unparsable", "text": raw}
            obj["_read_at"] = time.time()
            with self.cond:
                self.lines.append(obj)
                self.cond.notify_all()
        with self.cond:
            self.closed = True
            self.cond.notify_all()

    def _read_err(self):
        self.stderr = self.proc.stderr.read()

    # ---- queries ------------------------------------------------------------------------
    def events(self, kind):
        with self.cond:
            return [line for line in self.lines if line.get("event") == kind]

    def first(self, kind):
        e = self.events(kind)
        return e[0] if e else None

    def last(self, kind):
        e = self.events(kind)
        return e[-1] if e else None

    def state(self):
        return self.last("state")

    def invite(self):
        return self.wait_for(lambda: self.first("invite"), 60, "its invite")["invite"]

    def wait_for(self, predicate, timeout, what):
        """Waits until predicate() is truthy (re-evaluated as lines arrive); returns its value."""
        deadline = time.time() + timeout
        with self.cond:
            while True:
                value = predicate()
                if value:
                    return value
                left = deadline - time.time()
                if left <= 0:
                    raise AssertionError(f"peer {self.peer_id}: no {what} within {timeout} s; "
                                         f"last lines: {self.lines[-3:]}; stderr: {self.stderr}")
                if self.closed and not predicate():
                    raise AssertionError(f"peer {self.peer_id} ended before {what} "
                                         f"(exit {self.proc.poll()}): {self.stderr}")
                self.cond.wait(min(left, 0.2))

    # ---- control --------------------------------------------------------------------------
    def quit(self):
        """Asks the peer to finish (it leaves the session and prints its summary)."""
        try:
            self.proc.stdin.write("quit\n")
            self.proc.stdin.flush()
        except (BrokenPipeError, ValueError):
            pass

    def summary(self, timeout=30):
        s = self.wait_for(lambda: self.last("summary"), timeout, "summary")
        self.proc.wait(timeout)
        return s

    def kill(self):
        """SIGKILL: no leave message, no summary. Returns the time of the kill."""
        t = time.time()
        self.proc.send_signal(signal.SIGKILL)
        self.proc.wait(10)
        return t

    def stop(self):
        if self.proc.poll() is None:
            self.quit()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5)
        self.reader.join(5)
        self.err_reader.join(5)
        for f in (self.proc.stdin, self.proc.stdout, self.proc.stderr):
            try:
                f.close()
            except (BrokenPipeError, OSError):
                pass


def wait_all(predicate, timeout, what, peers):
    """Waits until predicate() over several peers holds, polling as lines arrive."""
    deadline = time.time() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.time() > deadline:
            states = {p.peer_id: p.state() for p in peers}
            raise AssertionError(f"no {what} within {timeout} s; states: {states}")
        time.sleep(0.02)  # polling the readers' latest lines, not waiting to assert


def converged(peers, require_acknowledged=True):
    """Every peer done editing, following one merger, on the same version and mesh digest, with
    nothing unmerged (its mesh is the agreed version's) and, unless told otherwise, every stroke
    acknowledged."""
    states = [p.state() for p in peers]
    if any(s is None for s in states):
        return False
    v, d, m = states[0]["version"], states[0]["digest"], states[0]["merger"]
    for s in states:
        if (s["editing"] or s["version"] != v or s["digest"] != d or s["base_digest"] != d or
                s["merger"] != m):
            return False
        if require_acknowledged and s["unacknowledged"] != 0:
            return False
    return {"version": v, "digest": d}


def acknowledged_markers(peer):
    """The markers (`--markers`) a peer saw in versions it applied."""
    return {v for line in peer.events("marker_acked") for v in line["vertices"]}


def wait_converged(testcase, peers, timeout=60):
    """Waits for convergence; returns it and how long after the last peer stopped editing it
    was seen (seconds)."""
    result = wait_all(lambda: converged(peers), timeout, "convergence", peers)
    seen = time.time()
    stopped = []
    for p in peers:
        ends = [s["t"] / 1000 for s in p.events("state") if not s["editing"]]
        stopped.append(ends[0] if ends else seen)
    return result, seen - max(stopped)


def finish(testcase, peers):
    """Quits every peer and checks the summaries agree: same version and digest, no lost
    edit. Returns the summaries."""
    for p in peers:
        p.quit()
    summaries = [p.summary() for p in peers]
    for p, s in zip(peers, summaries):
        testcase.assertEqual(p.proc.returncode, 0, f"peer {p.peer_id}: {p.stderr}")
        p.err_reader.join(10)
        # Nothing on stderr: a sanitizer report would be there.
        testcase.assertEqual(p.stderr, "", f"peer {p.peer_id}")
        testcase.assertEqual(s["lost_edits"], 0, f"peer {p.peer_id} lost edits: {s}")
        testcase.assertEqual(s["acknowledged"], s["strokes"], f"peer {p.peer_id}: {s}")
        testcase.assertEqual(s["version"], summaries[0]["version"])
        testcase.assertEqual(s["digest"], summaries[0]["digest"])
        testcase.assertEqual(s["digest"], s["base_digest"])
    return summaries


def report(name, **figures):
    """Figures for the log (ctest -V shows them)."""
    print(f"[figure] {name}: " + ", ".join(f"{k}={v}" for k, v in figures.items()), flush=True)
