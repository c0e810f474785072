"""Helpers of the Blender add-on tests: find Blender (or skip with 77), give each Blender
process a clean user directory with the add-on zip unpacked (or installed), run Blender with a
script inside it, and pass files between the processes."""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
SKIP = 77


def blender_or_skip():
    exe = os.environ.get("CSCULPT_BLENDER") or shutil.which("blender")
    if not exe:
        print("blender is not installed: skipped")
        sys.exit(SKIP)
    return exe


def addon_zip():
    path = os.environ.get("CSCULPT_BLENDER_ZIP", "")
    if not os.path.isfile(path):
        raise SystemExit(f"the add-on zip {path!r} is missing (build the blender_addon target)")
    return path


class Workdir:
    """A temporary directory for one test: files passed between processes, and one clean
    Blender user directory per process name."""

    def __init__(self, name):
        self.path = tempfile.mkdtemp(prefix=f"csculpt-blender-{name}-")

    def file(self, name):
        return os.path.join(self.path, name)

    def user_dirs(self, who, unpack_addon=True):
        """Environment for a Blender process with its own config and scripts directories; with
        `unpack_addon` the zip is unpacked into scripts/addons (as Install would)."""
        base = os.path.join(self.path, who)
        config, scripts, tmp = (os.path.join(base, d) for d in ("config", "scripts", "tmp"))
        for d in (config, os.path.join(scripts, "addons"), tmp):
            os.makedirs(d, exist_ok=True)
        if unpack_addon:
            with zipfile.ZipFile(addon_zip()) as z:
                z.extractall(os.path.join(scripts, "addons"))
            # zipfile drops the permission bits: the libraries must stay loadable.
            for root, _dirs, files in os.walk(os.path.join(scripts, "addons")):
                for f in files:
                    if ".so" in f:
                        os.chmod(os.path.join(root, f), 0o755)
        env = dict(os.environ)
        for var in ("CSCULPT_LIBRARY", "LD_LIBRARY_PATH", "PYTHONPATH"):
            env.pop(var, None)
        env.update(BLENDER_USER_CONFIG=config, BLENDER_USER_SCRIPTS=scripts, TMPDIR=tmp,
                   CSCULPT_TEST_DIR=self.path, PYTHONDONTWRITEBYTECODE="1")
        return env

    def cleanup(self):
        shutil.rmtree(self.path, ignore_errors=True)


def start(exe, script, args, env, background=True, log=None, extra=()):
    """Starts Blender running `script` (in tests/blender) with `args` after `--`."""
    cmd = [exe, "--factory-startup", *extra]
    if background:
        cmd.append("-b")
    cmd += ["--python-exit-code", "1", "--python", os.path.join(HERE, script), "--", *args]
    out = open(log, "w") if log else subprocess.DEVNULL
    return subprocess.Popen(cmd, env=env, stdout=out, stderr=subprocess.STDOUT)


def wait_all(procs, logs, timeout):
    """Waits for every process; returns their exit codes (a process over time is killed)."""
    end = time.monotonic() + timeout
    codes = []
    for p in procs:
        try:
            codes.append(p.wait(max(end - time.monotonic(), 0.1)))
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
            codes.append("timeout")
    for log in logs:
        if log and os.path.exists(log):
            print(f"---- {os.path.basename(log)}")
            with open(log, errors="replace") as f:
                print(f.read()[-6000:])
    return codes


def read_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def wait_converged(work, names, timeout, extra=lambda states: True, procs=()):
    """Waits until every process `names` published the same version and digest, with all its
    strokes acknowledged and the others as peers; returns the states."""
    end = time.monotonic() + timeout
    states = {}
    while time.monotonic() < end:
        states = {n: read_json(work.file(f"state-{n}.json")) for n in names}
        if all(states.values()):
            s = list(states.values())
            if (len({x["digest"] for x in s}) == 1 and len({x["version"] for x in s}) == 1 and
                    all(x["acked"] >= x["strokes"] >= 1 and x["peers"] == len(names) - 1
                        and not x["refused"] for x in s) and extra(states)):
                return states
        if any(p.poll() is not None for p in procs):
            raise AssertionError(f"a Blender process ended early: {[p.poll() for p in procs]}")
        time.sleep(0.2)
    raise AssertionError(f"no convergence within {timeout} s: {json.dumps(states, indent=1)}")
